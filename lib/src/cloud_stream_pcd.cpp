// Streaming PCD decoder (cloud_stream.h): ascii, binary and binary_compressed bodies with the
// header checks of read_cloud. Every point is first brought to PCL's in-memory record layout
// (fields packed in header order, SIZE × COUNT bytes each), then x y z, the normals and the
// colour are read from the record as read_cloud does.
#include <pcl/io/lzf.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "cloud_stream_detail.h"
#include "pcd_format.h"

namespace heatcvt::stream_detail {

namespace {

// PCL's datatypes (pcl::PCLPointField), named here by size and kind.
enum class PcdType { invalid, i8, u8, i16, u16, i32, u32, f32, f64, i64, u64 };

PcdType pcd_type(char kind, long long size) {
  if (kind == 'F') return size == 4 ? PcdType::f32 : size == 8 ? PcdType::f64 : PcdType::invalid;
  if (kind == 'I')
    return size == 1 ? PcdType::i8 : size == 2 ? PcdType::i16 : size == 4 ? PcdType::i32 : size == 8 ? PcdType::i64 : PcdType::invalid;
  if (kind == 'U')
    return size == 1 ? PcdType::u8 : size == 2 ? PcdType::u16 : size == 4 ? PcdType::u32 : size == 8 ? PcdType::u64 : PcdType::invalid;
  return PcdType::invalid;
}

double load_field(const char* p, PcdType t) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (t) {
    case PcdType::i8: return get(int8_t());
    case PcdType::u8: return get(uint8_t());
    case PcdType::i16: return get(int16_t());
    case PcdType::u16: return get(uint16_t());
    case PcdType::i32: return get(int32_t());
    case PcdType::u32: return get(uint32_t());
    case PcdType::f32: return get(float());
    case PcdType::f64: return get(double());
    case PcdType::i64: return get(int64_t());
    case PcdType::u64: return get(uint64_t());
    case PcdType::invalid: break;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Writes one ascii value into a record slot of type t (floats parsed directly in their own
// precision, as PCL's ascii reader does).
void store_ascii(std::string_view tok, PcdType t, char* dst) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (t == PcdType::f32) {
    float v = 0;
    std::from_chars(tok.data(), tok.data() + tok.size(), v);
    std::memcpy(dst, &v, 4);
    return;
  }
  double v = 0;
  std::from_chars(tok.data(), tok.data() + tok.size(), v);
  auto put = [&](auto x) { std::memcpy(dst, &x, sizeof(x)); };
  switch (t) {
    case PcdType::i8: put(static_cast<int8_t>(v)); break;
    case PcdType::u8: put(static_cast<uint8_t>(v)); break;
    case PcdType::i16: put(static_cast<int16_t>(v)); break;
    case PcdType::u16: put(static_cast<uint16_t>(v)); break;
    case PcdType::i32: put(static_cast<int32_t>(v)); break;
    case PcdType::u32: put(static_cast<uint32_t>(v)); break;
    case PcdType::f64: put(v); break;
    case PcdType::i64: put(static_cast<int64_t>(v)); break;
    case PcdType::u64: put(static_cast<uint64_t>(v)); break;
    case PcdType::f32: case PcdType::invalid: break;
  }
}

struct PcdField {
  std::string name;
  long long size = 0, count = 1;
  char kind = 'F';
  PcdType type = PcdType::f32;
  std::size_t offset = 0;  // in the packed record
};

class PcdDecoder : public CloudChunkReader::Decoder {
 public:
  PcdDecoder(const std::string& path, std::size_t buffer_bytes) : Decoder(path, buffer_bytes) {
    read_header();
    check_body_size();
    locate_fields();
  }

  std::int64_t read(std::int64_t max, CloudChunk& chunk) override {
    std::int64_t n = 0;
    while (n < max && next_record_ < points_) {
      const char* rec = kind_ == "binary" ? binary_record() : kind_ == "ascii" ? ascii_record() : compressed_record();
      extract(rec, chunk, static_cast<Eigen::Index>(n));
      ++next_record_;
      ++n;
    }
    if (kind_ == "ascii" && next_record_ == points_ && !tail_checked_) {
      tail_checked_ = true;
      detail::check_pcd_ascii_tail(src.path(), line_no_, points_, [&](std::string& l) { return src.getline(l); });
    }
    return n;
  }

 private:
  void read_header();
  void check_body_size();
  void locate_fields();
  const char* ascii_record();
  const char* binary_record();
  const char* compressed_record();
  void extract(const char* rec, CloudChunk& chunk, Eigen::Index row) const;

  std::vector<PcdField> fields_;
  std::string kind_;
  long long points_ = 0, point_step_ = 0, values_per_point_ = 0;
  int header_lines_ = 0;
  long line_no_ = 0;
  long long next_record_ = 0;
  bool tail_checked_ = false;  // ascii: the lines after the last point were checked (blank)
  std::vector<char> record_;
  std::vector<char> block_;                  // binary_compressed: the decompressed block
  std::vector<std::size_t> column_start_;    // binary_compressed: start of each field's column
  const PcdField* xyz_[6] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  const PcdField* packed_ = nullptr;
  const PcdField* rgb_[3] = {nullptr, nullptr, nullptr};
  bool rgb_integer_ = true;
  std::string line_;
  detail::PcdHeader header_;
};

// The header checks of read_cloud (pcd_format.h); TYPE gives the datatypes.
void PcdDecoder::read_header() {
  const detail::PcdHeader h = detail::read_pcd_header(src.path(), [&](std::string& line) { return src.getline(line); });
  kind_ = h.data_kind;
  header_lines_ = h.lines;
  points_ = h.points;
  grid_width = h.width;
  grid_height = h.height;
  sensor = Eigen::Vector3d(h.viewpoint[0], h.viewpoint[1], h.viewpoint[2]);
  for (std::size_t k = 0; k < h.field_names.size(); ++k) {
    PcdField f;
    f.name = h.field_names[k];
    f.size = h.sizes[k];
    f.count = h.count(k);
    f.kind = k < h.kinds.size() ? h.kinds[k] : 'F';
    f.type = pcd_type(f.kind, f.size);
    f.offset = static_cast<std::size_t>(point_step_);
    point_step_ += f.size * f.count;
    values_per_point_ += f.count;
    fields_.push_back(f);
  }
  record_.assign(static_cast<std::size_t>(point_step_), 0);
  format = "pcd-" + kind_;
  points_total = points_;
  header_ = h;
}

// Checks that the body can hold the announced points before any of it is read.
void PcdDecoder::check_body_size() {
  const std::string& path = src.path();
  uint32_t sz[2] = {0, 0};
  detail::check_pcd_body_size(
      path, header_, src.remaining(), [&](char* dst, std::size_t n) { return src.read(dst, n); }, sz);
  if (kind_ == "binary_compressed") {
    // One LZF block: it must be decompressed whole (see cloud_stream.h).
    if (sz[0] == 0 && sz[1] > 0)
      fail(path, "corrupt compressed PCD: compressed size 0 for " + std::to_string(sz[1]) + " bytes of data");
    std::vector<char> packed(sz[0]);
    if (sz[0] > 0 && !src.read(packed.data(), sz[0])) fail(path, "truncated: compressed PCD data missing");
    block_.resize(sz[1]);
    if (sz[1] > 0 && pcl::lzfDecompress(packed.data(), sz[0], block_.data(), sz[1]) != sz[1])
      fail(path, "PCL could not read the PCD file (malformed or truncated)");
    // Column layout: each field (padding fields "_" excepted) stores all its points in turn.
    std::size_t start = 0;
    for (const auto& f : fields_) {
      column_start_.push_back(start);
      if (f.name != "_") start += static_cast<std::size_t>(f.size * f.count * points_);
    }
  } else if (kind_ == "ascii") {
    line_no_ = header_lines_;
  }
}

// The fields read_cloud uses: x y z, normal_x/y/z, packed rgb / rgba or separate r g b.
void PcdDecoder::locate_fields() {
  const std::string& path = src.path();
  static const char* names[6] = {"x", "y", "z", "normal_x", "normal_y", "normal_z"};
  for (const auto& field : fields_) {
    for (int k = 0; k < 6; ++k)
      if (field.name == names[k]) xyz_[k] = &field;
    if (field.name == "rgb" || field.name == "rgba") packed_ = &field;
    if (field.name == "r") rgb_[0] = &field;
    if (field.name == "g") rgb_[1] = &field;
    if (field.name == "b") rgb_[2] = &field;
  }
  for (int k = 0; k < 3; ++k)
    if (!xyz_[k]) fail(path, std::string("PCD file has no '") + names[k] + "' field");
  normals = xyz_[3] && xyz_[4] && xyz_[5];
  for (int k = 0; k < (normals ? 6 : 3); ++k)
    if (xyz_[k]->type == PcdType::invalid)
      fail(path, std::string("PCD field '") + names[k] + "' has an unsupported type or lies outside the point");
  if (packed_) {
    if (packed_->size != 4 || packed_->type == PcdType::invalid)
      fail(path, "PCD field '" + packed_->name + "' is not a packed 4-byte colour");
    colours = true;
  } else if (rgb_[0] && rgb_[1] && rgb_[2]) {
    for (const auto* f : rgb_)
      if (f->type == PcdType::invalid)
        fail(path, "PCD colour field '" + f->name + "' has an unsupported type or lies outside the point");
    rgb_integer_ = rgb_[0]->type != PcdType::f32 && rgb_[0]->type != PcdType::f64;
    colours = true;
  }
}

// One non-blank body line, checked as read_cloud checks ascii bodies, stored into the record.
const char* PcdDecoder::ascii_record() {
  const std::string& path = src.path();
  while (true) {
    if (!src.getline(line_))
      fail(path, "truncated: header announces " + std::to_string(points_) + " points, file holds " + std::to_string(next_record_));
    ++line_no_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    std::size_t field = 0, slot = 0;
    const long long cols = detail::read_pcd_ascii_line(path, line_no_, line_, values_per_point_, [&](std::string_view tok) {
      if (field < fields_.size()) {
        const PcdField& f = fields_[field];
        store_ascii(tok, f.type, record_.data() + f.offset + slot * static_cast<std::size_t>(f.size));
        if (++slot == static_cast<std::size_t>(f.count)) slot = 0, ++field;
      }
    });
    if (cols == 0) continue;
    return record_.data();
  }
}

const char* PcdDecoder::binary_record() {
  const char* rec = src.take(static_cast<std::size_t>(point_step_));
  if (!rec) {  // point_step_ may exceed the buffer: copy through it
    if (!src.read(record_.data(), record_.size()))
      fail(src.path(), "truncated: PCD data holds fewer than " + std::to_string(points_) + " points");
    return record_.data();
  }
  return rec;
}

const char* PcdDecoder::compressed_record() {
  for (std::size_t k = 0; k < fields_.size(); ++k) {
    const PcdField& f = fields_[k];
    if (f.name == "_") continue;
    const auto bytes = static_cast<std::size_t>(f.size * f.count);
    std::memcpy(record_.data() + f.offset, block_.data() + column_start_[k] + bytes * static_cast<std::size_t>(next_record_), bytes);
  }
  return record_.data();
}

void PcdDecoder::extract(const char* rec, CloudChunk& chunk, Eigen::Index row) const {
  for (int k = 0; k < 3; ++k) chunk.P(row, k) = load_field(rec + xyz_[k]->offset, xyz_[k]->type);
  if (normals)
    for (int k = 0; k < 3; ++k) chunk.N(row, k) = load_field(rec + xyz_[k + 3]->offset, xyz_[k + 3]->type);
  if (!colours) return;
  if (packed_) {
    // PCL packs the colour as 0xAARRGGBB read little-endian: bytes blue, green, red, alpha.
    const auto* p = reinterpret_cast<const unsigned char*>(rec + packed_->offset);
    for (int k = 0; k < 3; ++k) chunk.C(row, k) = p[2 - k] / 255.0;
    return;
  }
  for (int k = 0; k < 3; ++k) {
    const double v = load_field(rec + rgb_[k]->offset, rgb_[k]->type);
    chunk.C(row, k) = std::clamp(rgb_integer_ ? v / 255.0 : v, 0.0, 1.0);
  }
}

}  // namespace

std::unique_ptr<CloudChunkReader::Decoder> make_pcd_decoder(const std::string& path, std::size_t buffer_bytes) {
  return std::make_unique<PcdDecoder>(path, buffer_bytes);
}

}  // namespace heatcvt::stream_detail
