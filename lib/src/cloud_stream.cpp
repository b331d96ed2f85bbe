// Streaming cloud readers (cloud_stream.h): the buffered byte source, the chunk reader driving the
// per-format decoders, and the XYZ / PWN / TXT decoder. PLY and PCD decoders are in
// cloud_stream_ply.cpp and cloud_stream_pcd.cpp.
#include "heatcvt/cloud_stream.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "cloud_stream_detail.h"
#include "xyz_lines.h"
#include "heatcvt/input_file.h"

namespace heatcvt {

namespace stream_detail {

namespace fs = std::filesystem;

ByteSource::ByteSource(const std::string& path, std::size_t buffer_bytes)
    : path_(path), buf_(std::max<std::size_t>(buffer_bytes, 4096)) {
  std::error_code ec;
  require_regular_file(path);
  in_.open(path, std::ios::binary);
  if (!in_) fail(path, "cannot open file for reading");
  const auto sz = fs::file_size(path, ec);
  if (ec) fail(path, "cannot determine the file size");
  size_ = static_cast<std::int64_t>(sz);
  if (size_ == 0) fail(path, "file is empty");
}

bool ByteSource::fill(std::size_t want) {
  if (pos_ > 0) {
    std::memmove(buf_.data(), buf_.data() + pos_, end_ - pos_);
    end_ -= pos_;
    pos_ = 0;
  }
  while (end_ < want && in_) {
    in_.read(buf_.data() + end_, static_cast<std::streamsize>(buf_.size() - end_));
    const auto got = static_cast<std::size_t>(in_.gcount());
    if (got == 0) break;
    end_ += got;
    file_pos_ += static_cast<std::int64_t>(got);
  }
  return end_ >= want;
}

bool ByteSource::read(char* dst, std::size_t n) {
  while (n > 0) {
    if (pos_ == end_ && !fill(1)) return false;
    const std::size_t k = std::min(n, end_ - pos_);
    std::memcpy(dst, buf_.data() + pos_, k);
    pos_ += k;
    dst += k;
    n -= k;
  }
  return true;
}

bool ByteSource::getline(std::string& line) {
  line.clear();
  bool any = false;
  while (true) {
    if (pos_ == end_ && !fill(1)) return any;
    any = true;
    const char* start = buf_.data() + pos_;
    const void* nl = std::memchr(start, '\n', end_ - pos_);
    if (nl) {
      const auto len = static_cast<std::size_t>(static_cast<const char*>(nl) - start);
      line.append(start, len);
      pos_ += len + 1;
      return true;
    }
    line.append(start, end_ - pos_);
    pos_ = end_;
  }
}

bool ByteSource::token(std::string& tok) {
  tok.clear();
  while (true) {  // skip white space
    if (pos_ == end_ && !fill(1)) return false;
    while (pos_ < end_ && is_space(buf_[pos_])) ++pos_;
    if (pos_ < end_) break;
  }
  while (true) {
    const std::size_t start = pos_;
    while (pos_ < end_ && !is_space(buf_[pos_])) ++pos_;
    tok.append(buf_.data() + start, pos_ - start);
    if (pos_ < end_ || !fill(1)) return true;
  }
}

namespace {

// XYZ / PWN / TXT: the rules of read_cloud's text reader, line by line.
class XyzDecoder : public CloudChunkReader::Decoder {
 public:
  XyzDecoder(const std::string& path, std::size_t buffer_bytes) : Decoder(path, buffer_bytes) {
    format = "xyz";
    // Normals are carried when the first data line has >= 6 columns: look ahead to it.
    while (next_line()) {
      if (cols_ == 0) continue;
      pending_ = true;
      normals = cols_ >= 6;
      break;
    }
  }

  std::int64_t read(std::int64_t max, CloudChunk& chunk) override {
    std::int64_t n = 0;
    while (n < max) {
      if (!pending_) {
        if (!next_line()) break;
        if (cols_ == 0) continue;
      }
      pending_ = false;
      if (cols_ < 3)
        fail(src.path(), "line " + std::to_string(line_no_) + ": expected at least 3 numbers (x y z), found " +
                             std::to_string(cols_));
      for (int k = 0; k < 3; ++k) chunk.P(n, k) = vals_[k];
      if (normals) {
        if (cols_ < 6) all_normals = false;
        for (int k = 0; k < 3; ++k) chunk.N(n, k) = cols_ >= 6 ? vals_[k + 3] : std::numeric_limits<double>::quiet_NaN();
      }
      ++n;
    }
    return n;
  }

 private:
  // Reads and tokenises the next line into vals_ / cols_; false at the end of the file.
  bool next_line() {
    if (!src.getline(line_)) return false;
    ++line_no_;
    const detail::XyzLineKind kind = detail::read_xyz_line(line_, first_data_line_, src.path(), line_no_, vals_, cols_);
    if (kind != detail::XyzLineKind::blank) first_data_line_ = false;
    // Column names and a point count on the first line are not points.
    if (kind != detail::XyzLineKind::values) cols_ = 0;
    return true;
  }

  std::string line_;
  long line_no_ = 0;
  int cols_ = 0;
  double vals_[6] = {0, 0, 0, 0, 0, 0};
  bool first_data_line_ = true;
  bool pending_ = false;  // vals_ holds a data line not yet handed out
};

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::unique_ptr<CloudChunkReader::Decoder> make_xyz_decoder(const std::string& path, std::size_t buffer_bytes) {
  return std::make_unique<XyzDecoder>(path, buffer_bytes);
}

}  // namespace stream_detail

MemoryChunkSource::MemoryChunkSource(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixX3d& C,
                                     std::string name, std::int64_t chunk_points)
    : P_(P), N_(N), C_(C), name_(std::move(name)), chunk_points_(chunk_points) {
  if (chunk_points < 1) throw InvalidInputError(name_ + ": chunk_points must be >= 1");
}

bool MemoryChunkSource::next(CloudChunk& chunk) {
  const Eigen::Index count = std::min<Eigen::Index>(chunk_points_, P_.rows() - next_);
  chunk.P = P_.middleRows(next_, count);
  chunk.N = N_.rows() == P_.rows() ? Eigen::MatrixX3d(N_.middleRows(next_, count)) : Eigen::MatrixX3d();
  chunk.C = C_.rows() == P_.rows() ? Eigen::MatrixX3d(C_.middleRows(next_, count)) : Eigen::MatrixX3d();
  next_ += count;
  return count > 0;
}

CloudChunkReader::CloudChunkReader(const std::string& path, StreamReaderOptions options)
    : path_(path), options_(std::move(options)) {
  if (options_.chunk_points < 1)
    throw InvalidInputError("CloudChunkReader: chunk_points must be >= 1 (got " + std::to_string(options_.chunk_points) + ")");
  open();
}

CloudChunkReader::~CloudChunkReader() = default;

void CloudChunkReader::open() {
  using namespace stream_detail;
  decoder_.reset();
  // The checks of read_cloud, in its order: a regular file before the extension.
  require_regular_file(path_);
  const std::string ext = lower(std::filesystem::path(path_).extension().string());
  if (ext != ".pcd" && ext != ".ply" && ext != ".xyz" && ext != ".pwn" && ext != ".txt")
    fail(path_, "unknown point-cloud format " + quote_excerpt(ext) + " (expected .pcd, .ply, .xyz, .pwn or .txt)");
  if (ext == ".pcd") decoder_ = make_pcd_decoder(path_, options_.buffer_bytes);
  else if (ext == ".ply") decoder_ = make_ply_decoder(path_, options_.buffer_bytes);
  else decoder_ = make_xyz_decoder(path_, options_.buffer_bytes);
}

bool CloudChunkReader::next(CloudChunk& chunk) {
  const Eigen::Index m = static_cast<Eigen::Index>(options_.chunk_points);
  chunk.P.resize(m, 3);
  chunk.N.resize(decoder_->normals ? m : 0, 3);
  chunk.C.resize(decoder_->colours ? m : 0, 3);
  const std::int64_t n = decoder_->read(options_.chunk_points, chunk);
  decoder_->points_read += n;
  if (n < m) {
    chunk.P.conservativeResize(n, 3);
    if (decoder_->normals) chunk.N.conservativeResize(n, 3);
    if (decoder_->colours) chunk.C.conservativeResize(n, 3);
  }
  if (options_.progress) options_.progress({bytes_read(), bytes_total(), points_read(), points_in_file()});
  return n > 0;
}

void CloudChunkReader::rewind() {
  open();
  ++passes_;
}

const std::string& CloudChunkReader::format() const { return decoder_->format; }
bool CloudChunkReader::has_normals() const { return decoder_->normals; }
bool CloudChunkReader::has_colours() const { return decoder_->colours; }
bool CloudChunkReader::all_points_had_normals() const { return decoder_->normals && decoder_->all_normals; }
std::int64_t CloudChunkReader::points_in_file() const { return decoder_->points_total; }
std::int64_t CloudChunkReader::grid_width() const { return decoder_->grid_width > 0 ? decoder_->grid_width : points_in_file(); }
std::int64_t CloudChunkReader::grid_height() const { return decoder_->grid_height; }
Eigen::Vector3d CloudChunkReader::sensor_origin() const { return decoder_->sensor; }
std::int64_t CloudChunkReader::points_read() const { return decoder_->points_read; }
std::int64_t CloudChunkReader::bytes_read() const { return decoder_->src.offset(); }
std::int64_t CloudChunkReader::bytes_total() const { return decoder_->src.size(); }

}  // namespace heatcvt
