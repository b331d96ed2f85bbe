// PLY format pieces shared by the readers (ply_format.h).
#include "ply_format.h"

#include <cctype>
#include <cmath>

#include "heatcvt/errors.h"
#include "text_tokens.h"

namespace heatcvt::detail {

namespace {
[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }
}  // namespace

bool ply_type_from_name(std::string_view n, PlyType& t) {
  static const std::pair<const char*, PlyType> table[] = {
      {"char", PlyType::i8},    {"int8", PlyType::i8},     {"uchar", PlyType::u8},   {"uint8", PlyType::u8},
      {"short", PlyType::i16},  {"int16", PlyType::i16},   {"ushort", PlyType::u16}, {"uint16", PlyType::u16},
      {"int", PlyType::i32},    {"int32", PlyType::i32},   {"uint", PlyType::u32},   {"uint32", PlyType::u32},
      {"float", PlyType::f32},  {"float32", PlyType::f32}, {"double", PlyType::f64}, {"float64", PlyType::f64}};
  for (const auto& e : table)
    if (n == e.first) {
      t = e.second;
      return true;
    }
  return false;
}

std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8: case PlyType::u8: return 1;
    case PlyType::i16: case PlyType::u16: return 2;
    case PlyType::i32: case PlyType::u32: case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 1;
}

bool ply_is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

double load_value(const char* p, PlyType t, bool swap) {
  switch (t) {
    case PlyType::i8: return static_cast<double>(static_cast<int8_t>(*p));
    case PlyType::u8: return static_cast<double>(static_cast<uint8_t>(*p));
    case PlyType::i16: return load_raw<int16_t>(p, swap);
    case PlyType::u16: return load_raw<uint16_t>(p, swap);
    case PlyType::i32: return load_raw<int32_t>(p, swap);
    case PlyType::u32: return load_raw<uint32_t>(p, swap);
    case PlyType::f32: return load_raw<float>(p, swap);
    case PlyType::f64: return load_raw<double>(p, swap);
  }
  return 0;
}

bool host_is_little_endian() {
  const uint16_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

PlyHeader read_ply_header(const std::string& path, const std::function<bool(std::string_view&)>& next_line) {
  long line_no = 0;
  auto next = [&](std::string_view& line) {
    if (!next_line(line)) return false;
    ++line_no;
    return true;
  };
  std::string_view line;
  std::string magic;
  if (next(line)) magic = std::string(line.substr(0, 3));
  for (auto& c : magic) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (line_no == 0 || magic != "ply" || (line.size() > 3 && !is_space(line[3])))
    fail(path, "not a PLY file (missing 'ply' magic line)");
  PlyHeader h;
  std::vector<std::string_view> tok;
  bool header_done = false;
  while (next(line)) {
    split(line, tok);
    if (tok.empty()) continue;
    const auto key = tok[0];
    auto hdr = [&](const std::string& problem) {
      return IOError(path + ": PLY header line " + std::to_string(line_no) + ": " + problem);
    };
    // Element and property names appear in later messages: no control bytes in them.
    auto require_printable_name = [&](std::string_view name) {
      for (char c : name)
        if (!std::isprint(static_cast<unsigned char>(c))) throw hdr("unprintable name " + quote_excerpt(name));
      return std::string(name);
    };
    if (key == "end_header") {
      header_done = true;
      break;
    } else if (key == "format") {
      if (tok.size() < 2) throw hdr("format line without a format");
      h.format = std::string(tok[1]);
      if (h.format != "ascii" && h.format != "binary_little_endian" && h.format != "binary_big_endian")
        throw hdr("unknown PLY format " + quote_excerpt(h.format));
    } else if (key == "comment" || key == "obj_info") {
      continue;
    } else if (key == "element") {
      long long count = -1;
      if (tok.size() >= 2) require_printable_name(tok[1]);
      if (tok.size() < 3 || !parse_int(tok[2], count)) throw hdr("malformed element line");
      if (count < 0 || count > kPlyMaxCount)
        throw hdr("element " + quote_excerpt(tok[1]) + " count " + std::string(tok[2]) + " is out of range (0 to " +
                  std::to_string(kPlyMaxCount) + ")");
      h.elements.push_back({std::string(tok[1]), count, {}});
    } else if (key == "property") {
      if (h.elements.empty()) throw hdr("property before any element");
      PlyProperty p;
      if (tok.size() >= 2 && tok[1] == "list") {
        if (tok.size() < 5) throw hdr("malformed list property");
        p.is_list = true;
        if (!ply_type_from_name(tok[2], p.count_type) || !ply_is_integer(p.count_type))
          throw hdr("bad list count type " + quote_excerpt(tok[2]));
        if (!ply_type_from_name(tok[3], p.type)) throw hdr("unknown property type " + quote_excerpt(tok[3]));
        p.name = require_printable_name(tok[4]);
      } else {
        if (tok.size() < 3) throw hdr("malformed property line");
        if (!ply_type_from_name(tok[1], p.type)) throw hdr("unknown property type " + quote_excerpt(tok[1]));
        p.name = require_printable_name(tok[2]);
      }
      h.elements.back().props.push_back(p);
    } else {
      throw hdr("unexpected keyword " + quote_excerpt(key));
    }
  }
  if (!header_done) fail(path, "truncated PLY header (no end_header)");
  if (h.format.empty()) fail(path, "PLY header has no format line");
  h.ascii = h.format == "ascii";
  h.swap = !h.ascii && ((h.format == "binary_little_endian") != host_is_little_endian());
  return h;
}

std::size_t ply_min_bytes(const PlyElement& el, bool ascii) {
  std::size_t min_bytes = 0;
  for (const auto& p : el.props) min_bytes += ascii ? 2 : (p.is_list ? ply_size(p.count_type) : ply_size(p.type));
  return min_bytes;
}

void check_ply_element_fits(const std::string& path, const PlyElement& el, std::size_t min_bytes, std::int64_t remaining) {
  if (el.count > 0 && min_bytes > 0 &&
      static_cast<double>(el.count) * static_cast<double>(min_bytes) > static_cast<double>(remaining) + 1)
    fail(path, "truncated: header announces " + std::to_string(el.count) + " " + el.name + " elements but only " +
                   std::to_string(remaining) + " bytes of data remain");
}

void ply_vertex_columns(const std::string& path, const std::vector<PlyProperty>& props, int col[9]) {
  // Colour properties: "red green blue" (most writers) or "diffuse_red ..." (Stanford, MeshLab).
  static const char* names[9] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
  for (int k = 0; k < 9; ++k) col[k] = -1;
  for (int k = 0; k < 9; ++k)
    for (std::size_t j = 0; j < props.size(); ++j)
      if (!props[j].is_list && (props[j].name == names[k] || (k >= 6 && props[j].name == std::string("diffuse_") + names[k])))
        col[k] = static_cast<int>(j);
  if (col[0] < 0 || col[1] < 0 || col[2] < 0) fail(path, "PLY vertex element lacks x, y or z");
}

double ply_colour_scale(PlyType t) {
  if (!ply_is_integer(t)) return 1.0;
  return ply_size(t) >= 2 ? 1.0 / 65535.0 : 1.0 / 255.0;
}

bool ply_parse_ascii(std::string_view tok, PlyType t, double& v) {
  return parse_double(tok, v) && (!ply_is_integer(t) || v == std::floor(v));
}

void ply_ascii_value_error(const std::string& path, std::string_view tok, const std::string& where) {
  double v = 0;
  if (!parse_double(tok, v)) fail(path, "malformed number " + quote_excerpt(tok) + " in " + where);
  fail(path, "non-integer value " + quote_excerpt(tok) + " for an integer property in " + where);
}

}  // namespace heatcvt::detail
