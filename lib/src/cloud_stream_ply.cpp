// Streaming PLY decoder (cloud_stream.h): ascii and binary little / big endian. Points come from
// the first `vertex` element; every other element is read past with the checks of the
// whole-file PLY reader (list lengths, face indices in range, truncation), without storing it.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>

#include "cloud_stream_detail.h"
#include "heatcvt/atomic_file.h"

namespace heatcvt::stream_detail {

namespace {

constexpr long long kMaxCount = 2000000000LL;  // counts beyond int range are rejected

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

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

template <typename T>
T load_raw(const char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

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

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::f32;       // scalar type or list item type
  PlyType count_type = PlyType::u8;  // list count type
  int role = -1;                     // vertex element: 0-2 x y z, 3-5 nx ny nz, 6-8 red green blue
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> props;
};

class PlyDecoder : public CloudChunkReader::Decoder {
 public:
  PlyDecoder(const std::string& path, std::size_t buffer_bytes) : Decoder(path, buffer_bytes) {
    read_header();
    setup_vertex_roles();
  }

  std::int64_t read(std::int64_t max, CloudChunk& chunk) override {
    std::int64_t n = 0;
    while (n < max && current_ < elements_.size()) {
      const PlyElement& el = elements_[current_];
      if (!started_) start_element(el);
      if (instance_ >= el.count || el.props.empty()) {  // a property-less element occupies no bytes
        ++current_;
        instance_ = 0;
        started_ = false;
        continue;
      }
      const bool is_vertex = static_cast<long long>(current_) == vertex_element_;
      for (std::size_t j = 0; j < el.props.size(); ++j) read_property(el, j, is_vertex ? &chunk : nullptr, n);
      if (is_vertex) ++n;
      ++instance_;
      if (!ascii_ && src.remaining() == 0 && instance_ < el.count && min_bytes_ > 0)
        fail(src.path(), "truncated: binary data ends after " + std::to_string(instance_) + " of " +
                             std::to_string(el.count) + " " + el.name + " elements");
    }
    return n;
  }

 private:
  void read_header();
  void setup_vertex_roles();
  void start_element(const PlyElement& el);
  void read_property(const PlyElement& el, std::size_t j, CloudChunk* chunk, std::int64_t row);

  std::string context(const PlyElement& el, const PlyProperty& p) const {
    return el.name + " " + std::to_string(instance_) + " of " + std::to_string(el.count) + " (property " + p.name + ")";
  }

  // One value of type t (ascii token or binary bytes).
  double value(PlyType t, const PlyElement& el, const PlyProperty& p) {
    if (ascii_) {
      if (!src.token(tok_)) fail(src.path(), "truncated: data ends in " + context(el, p));
      double v = 0;
      if (!parse_double(tok_, v)) fail(src.path(), "malformed number " + quote_excerpt(tok_) + " in " + context(el, p));
      if (ply_is_integer(t) && v != std::floor(v))
        fail(src.path(), "non-integer value " + quote_excerpt(tok_) + " for an integer property in " + context(el, p));
      return v;
    }
    const char* b = src.take(ply_size(t));
    if (!b) fail(src.path(), "truncated: binary data ends in " + context(el, p));
    return load_value(b, t, swap_);
  }

  std::vector<PlyElement> elements_;
  long long vertex_element_ = -1;
  long long num_vertices_ = -1;
  bool ascii_ = false, swap_ = false;
  double colour_scale_ = 1.0;
  std::size_t current_ = 0;
  long long instance_ = 0;
  bool started_ = false;
  std::size_t min_bytes_ = 0;
  bool is_face_ = false;
  int face_list_ = -1;
  std::string tok_;
};

void PlyDecoder::read_header() {
  std::string raw;
  std::vector<std::string_view> tok;
  long line_no = 0;
  auto next = [&](std::string_view& line) {
    if (!src.getline(raw)) return false;
    ++line_no;
    line = raw;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return true;
  };
  std::string_view line;
  std::string magic;
  if (next(line)) magic = std::string(line.substr(0, 3));
  for (auto& c : magic) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (line_no == 0 || magic != "ply" || (line.size() > 3 && !is_space(line[3])))
    fail(src.path(), "not a PLY file (missing 'ply' magic line)");
  std::string fmt;
  bool header_done = false;
  while (next(line)) {
    split(line, tok);
    if (tok.empty()) continue;
    const auto key = tok[0];
    auto hdr = [&](const std::string& problem) {
      return IOError(src.path() + ": PLY header line " + std::to_string(line_no) + ": " + problem);
    };
    if (key == "end_header") {
      header_done = true;
      break;
    } else if (key == "format") {
      if (tok.size() < 2) throw hdr("format line without a format");
      fmt = std::string(tok[1]);
      if (fmt != "ascii" && fmt != "binary_little_endian" && fmt != "binary_big_endian")
        throw hdr("unknown PLY format " + quote_excerpt(fmt));
    } else if (key == "comment" || key == "obj_info") {
      continue;
    } else if (key == "element") {
      long long count = -1;
      if (tok.size() < 3 || !parse_int(tok[2], count) || count < 0 || count > kMaxCount) throw hdr("malformed element line");
      elements_.push_back({std::string(tok[1]), count, {}});
    } else if (key == "property") {
      if (elements_.empty()) throw hdr("property before any element");
      PlyProperty p;
      if (tok.size() >= 2 && tok[1] == "list") {
        if (tok.size() < 5) throw hdr("malformed list property");
        p.is_list = true;
        if (!ply_type_from_name(tok[2], p.count_type) || !ply_is_integer(p.count_type))
          throw hdr("bad list count type " + quote_excerpt(tok[2]));
        if (!ply_type_from_name(tok[3], p.type)) throw hdr("unknown property type " + quote_excerpt(tok[3]));
        p.name = std::string(tok[4]);
      } else {
        if (tok.size() < 3) throw hdr("malformed property line");
        if (!ply_type_from_name(tok[1], p.type)) throw hdr("unknown property type " + quote_excerpt(tok[1]));
        p.name = std::string(tok[2]);
      }
      elements_.back().props.push_back(p);
    } else {
      throw hdr("unexpected keyword " + quote_excerpt(key));
    }
  }
  if (!header_done) fail(src.path(), "truncated PLY header (no end_header)");
  if (fmt.empty()) fail(src.path(), "PLY header has no format line");
  ascii_ = fmt == "ascii";
  swap_ = !ascii_ && ((fmt == "binary_little_endian") != host_is_little_endian());
  format = "ply-" + fmt;
}

// Finds the vertex element and the columns of positions, normals and colours.
void PlyDecoder::setup_vertex_roles() {
  for (std::size_t e = 0; e < elements_.size(); ++e)
    if (elements_[e].name == "vertex") {
      vertex_element_ = static_cast<long long>(e);
      num_vertices_ = elements_[e].count;
      break;
    }
  if (vertex_element_ < 0) fail(src.path(), "PLY file has no vertex element");
  auto& props = elements_[static_cast<std::size_t>(vertex_element_)].props;
  // Colour properties: "red green blue" (most writers) or "diffuse_red ..." (Stanford, MeshLab).
  static const char* names[9] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"};
  int col[9] = {-1, -1, -1, -1, -1, -1, -1, -1, -1};
  for (int k = 0; k < 9; ++k)
    for (std::size_t j = 0; j < props.size(); ++j)
      if (!props[j].is_list && (props[j].name == names[k] || (k >= 6 && props[j].name == std::string("diffuse_") + names[k])))
        col[k] = static_cast<int>(j);
  if (col[0] < 0 || col[1] < 0 || col[2] < 0) fail(src.path(), "PLY vertex element lacks x, y or z");
  normals = col[3] >= 0 && col[4] >= 0 && col[5] >= 0;
  colours = col[6] >= 0 && col[7] >= 0 && col[8] >= 0;
  for (int k = 0; k < 9; ++k) {
    if (col[k] < 0 || (k >= 3 && k < 6 && !normals) || (k >= 6 && !colours)) continue;
    props[static_cast<std::size_t>(col[k])].role = k;
  }
  if (colours) {
    const PlyType t = props[static_cast<std::size_t>(col[6])].type;
    if (ply_is_integer(t)) colour_scale_ = ply_size(t) >= 2 ? 1.0 / 65535.0 : 1.0 / 255.0;
  }
  points_total = num_vertices_;
}

// Checks, before the element's data, that the file can hold its announced count.
void PlyDecoder::start_element(const PlyElement& el) {
  started_ = true;
  min_bytes_ = 0;
  for (const auto& p : el.props) min_bytes_ += ascii_ ? 2 : (p.is_list ? ply_size(p.count_type) : ply_size(p.type));
  if (el.count > 0 && min_bytes_ > 0 &&
      static_cast<double>(el.count) * static_cast<double>(min_bytes_) > static_cast<double>(src.remaining()) + 1)
    fail(src.path(), "truncated: header announces " + std::to_string(el.count) + " " + el.name + " elements but only " +
                         std::to_string(src.remaining()) + " bytes of data remain");
  is_face_ = el.name == "face";
  face_list_ = -1;
  if (is_face_) {
    for (std::size_t j = 0; j < el.props.size(); ++j)
      if (el.props[j].is_list && (el.props[j].name == "vertex_indices" || el.props[j].name == "vertex_index"))
        face_list_ = static_cast<int>(j);
    if (face_list_ < 0) fail(src.path(), "PLY face element has no vertex_indices/vertex_index list");
  }
}

void PlyDecoder::read_property(const PlyElement& el, std::size_t j, CloudChunk* chunk, std::int64_t row) {
  const PlyProperty& p = el.props[j];
  if (!p.is_list) {
    const double v = value(p.type, el, p);
    if (chunk && p.role >= 0) {
      const Eigen::Index r = static_cast<Eigen::Index>(row);
      if (p.role < 3) chunk->P(r, p.role) = v;
      else if (p.role < 6) chunk->N(r, p.role - 3) = v;
      else chunk->C(r, p.role - 6) = std::clamp(v * colour_scale_, 0.0, 1.0);
    }
    return;
  }
  const double cnt = value(p.count_type, el, p);
  if (!(cnt >= 0)) fail(src.path(), "negative or invalid list length in " + context(el, p));
  if (!(cnt <= static_cast<double>(src.remaining())))
    fail(src.path(), "truncated: list longer than the remaining data in " + context(el, p));
  const auto n = static_cast<std::size_t>(cnt);
  if (!ascii_ && static_cast<std::int64_t>(n * ply_size(p.type)) > src.remaining())
    fail(src.path(), "truncated: binary data ends in " + context(el, p));
  const bool indices = is_face_ && static_cast<int>(j) == face_list_;
  const double nv = static_cast<double>(std::max<long long>(num_vertices_, 0));
  for (std::size_t k = 0; k < n; ++k) {
    const double idx = value(p.type, el, p);
    // Negated comparisons so that a NaN index (float-typed lists) is rejected too.
    if (indices && (!(idx >= 0 && idx < nv) || idx != std::floor(idx)))
      fail(src.path(), "face " + std::to_string(instance_) + ": vertex index " + format_double(idx) + " out of range (" +
                           std::to_string(std::max<long long>(num_vertices_, 0)) + " vertices)");
  }
}

}  // namespace

std::unique_ptr<CloudChunkReader::Decoder> make_ply_decoder(const std::string& path, std::size_t buffer_bytes) {
  return std::make_unique<PlyDecoder>(path, buffer_bytes);
}

}  // namespace heatcvt::stream_detail
