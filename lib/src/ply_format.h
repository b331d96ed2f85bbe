#pragma once
// Internal PLY format pieces shared by the whole-file mesh reader (mesh_io.cpp) and the streaming
// cloud reader (cloud_stream_ply.cpp): property types and their sizes, binary value loading, the
// header parser and the checks both readers make on elements. Not installed.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace heatcvt::detail {

/// Counts beyond int range are rejected (element counts in the header).
constexpr long long kPlyMaxCount = 2000000000LL;

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

/// Type from its PLY name ("char", "int8", "float", "float32", ...); false for an unknown name.
bool ply_type_from_name(std::string_view n, PlyType& t);
/// Size in bytes of a binary value of type t.
std::size_t ply_size(PlyType t);
bool ply_is_integer(PlyType t);

/// Reads a T from (unaligned) bytes, reversing them first when `swap`.
template <typename T>
T load_raw(const char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

/// One binary value of type t at p, as a double.
double load_value(const char* p, PlyType t, bool swap);
bool host_is_little_endian();

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::f32;       // scalar type or list item type
  PlyType count_type = PlyType::u8;  // list count type
  int role = -1;                     // used by the streaming reader: 0-2 x y z, 3-5 nx ny nz, 6-8 red green blue
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> props;
};

struct PlyHeader {
  std::string format;  // "ascii", "binary_little_endian" or "binary_big_endian"
  std::vector<PlyElement> elements;
  bool ascii = false;
  bool swap = false;  // binary data whose byte order differs from the host's
};

/// Parses a PLY header from the magic line to end_header. `next_line(line)` yields the next line
/// without its '\n' and trailing '\r' (false at the end of the file); afterwards the source is at
/// the first byte of the body. Throws IOError "path: ..." on any malformed line.
PlyHeader read_ply_header(const std::string& path, const std::function<bool(std::string_view&)>& next_line);

/// Fewest bytes one instance of `el` occupies (2 per value in ascii: a digit and a separator).
std::size_t ply_min_bytes(const PlyElement& el, bool ascii);
/// Fails when `remaining` bytes cannot hold el.count instances of min_bytes each.
void check_ply_element_fits(const std::string& path, const PlyElement& el, std::size_t min_bytes, std::int64_t remaining);
/// Columns of x y z, nx ny nz and the colour (red green blue or diffuse_red ...) among the vertex
/// properties (-1 where absent); fails when x, y or z is missing.
void ply_vertex_columns(const std::string& path, const std::vector<PlyProperty>& props, int col[9]);
/// Factor taking colours of type t to [0,1]: 1/255 for 8-bit, 1/65535 for wider integers, 1 for floats.
double ply_colour_scale(PlyType t);
/// Parses one ascii value `tok` of type t into v; false when it is not a number or, for an
/// integer type, not an integer (ply_ascii_value_error() then gives the message).
bool ply_parse_ascii(std::string_view tok, PlyType t, double& v);
/// The problem with a token ply_parse_ascii() rejected, ending in " in " + where.
[[noreturn]] void ply_ascii_value_error(const std::string& path, std::string_view tok, const std::string& where);

/// One ascii value of type t; fails with `context()` (called only on failure) in the message.
template <typename Context>
double ply_ascii_value(const std::string& path, std::string_view tok, PlyType t, const Context& context) {
  double v = 0;
  if (!ply_parse_ascii(tok, t, v)) ply_ascii_value_error(path, tok, context());
  return v;
}

}  // namespace heatcvt::detail
