// Streaming PLY decoder (cloud_stream.h): ascii and binary little / big endian. Points come from
// the first `vertex` element; every other element is read past with the checks of the
// whole-file PLY reader (list lengths, face indices in range, truncation), without storing it.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>

#include "cloud_stream_detail.h"
#include "heatcvt/atomic_file.h"
#include "ply_format.h"

namespace heatcvt::stream_detail {

namespace {

using detail::load_value;
using detail::ply_size;
using detail::PlyElement;
using detail::PlyProperty;
using detail::PlyType;

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
    // An ascii file with values left after its last element has more data than its header
    // declares (a wrong count): refused rather than read in part.
    if (ascii_ && current_ >= elements_.size() && !tail_checked_) {
      tail_checked_ = true;
      std::string tok;
      if (src.token(tok)) fail(src.path(), "more values than the header declares (a wrong element count?)");
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
      return detail::ply_ascii_value(src.path(), tok_, t, [&] { return context(el, p); });
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
  bool tail_checked_ = false;
  std::size_t min_bytes_ = 0;
  bool is_face_ = false;
  int face_list_ = -1;
  std::string tok_;
};

void PlyDecoder::read_header() {
  std::string raw;
  detail::PlyHeader h = detail::read_ply_header(src.path(), [&](std::string_view& line) {
    if (!src.getline(raw)) return false;
    line = raw;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return true;
  });
  elements_ = std::move(h.elements);
  ascii_ = h.ascii;
  swap_ = h.swap;
  format = "ply-" + h.format;
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
  int col[9];
  detail::ply_vertex_columns(src.path(), props, col);
  normals = col[3] >= 0 && col[4] >= 0 && col[5] >= 0;
  colours = col[6] >= 0 && col[7] >= 0 && col[8] >= 0;
  for (int k = 0; k < 9; ++k) {
    if (col[k] < 0 || (k >= 3 && k < 6 && !normals) || (k >= 6 && !colours)) continue;
    props[static_cast<std::size_t>(col[k])].role = k;
  }
  if (colours) colour_scale_ = detail::ply_colour_scale(props[static_cast<std::size_t>(col[6])].type);
  points_total = num_vertices_;
}

// Checks, before the element's data, that the file can hold its announced count.
void PlyDecoder::start_element(const PlyElement& el) {
  started_ = true;
  min_bytes_ = detail::ply_min_bytes(el, ascii_);
  detail::check_ply_element_fits(src.path(), el, min_bytes_, src.remaining());
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
