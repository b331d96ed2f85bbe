#pragma once
// Internal pieces of the streaming cloud readers (cloud_stream.h): a buffered byte source over a
// file and the per-format decoders. Not installed.
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "heatcvt/cloud_stream.h"
#include "heatcvt/errors.h"
#include "text_tokens.h"

namespace heatcvt::stream_detail {

[[noreturn]] inline void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

using detail::for_each_token;
using detail::is_space;
using detail::parse_double;
using detail::parse_int;
using detail::split;

/// Sequential reads from a file through one fixed buffer; tracks the byte offset.
class ByteSource {
 public:
  ByteSource(const std::string& path, std::size_t buffer_bytes);
  const std::string& path() const { return path_; }
  std::int64_t size() const { return size_; }
  /// Bytes consumed so far.
  std::int64_t offset() const { return file_pos_ - static_cast<std::int64_t>(end_ - pos_); }
  std::int64_t remaining() const { return size_ - offset(); }
  /// Pointer to the next `n` bytes (n <= buffer size), consumed; nullptr when the file ends first.
  const char* take(std::size_t n) {
    if (end_ - pos_ < n && !fill(n)) return nullptr;
    const char* p = buf_.data() + pos_;
    pos_ += n;
    return p;
  }
  /// Copies the next `n` bytes (any n) into dst; false when the file ends first.
  bool read(char* dst, std::size_t n);
  /// Next line without its '\n' (a trailing '\r' is kept); false at the end of the file.
  bool getline(std::string& line);
  /// Next whitespace-separated token; false at the end of the file.
  bool token(std::string& tok);

 private:
  bool fill(std::size_t want);  // compacts the buffer and reads until `want` bytes are buffered
  std::string path_;
  std::ifstream in_;
  std::vector<char> buf_;
  std::size_t pos_ = 0, end_ = 0;
  std::int64_t file_pos_ = 0, size_ = 0;
};

}  // namespace heatcvt::stream_detail

namespace heatcvt {

/// A format decoder: reads points into preallocated chunk rows.
class CloudChunkReader::Decoder {
 public:
  Decoder(const std::string& path, std::size_t buffer_bytes) : src(path, buffer_bytes) {}
  virtual ~Decoder() = default;
  /// Reads up to `max` points into rows [0, max) of chunk.P (and N / C when `normals` /
  /// `colours`); returns how many were read (0 = the data is exhausted and fully validated).
  virtual std::int64_t read(std::int64_t max, CloudChunk& chunk) = 0;

  stream_detail::ByteSource src;
  std::string format;
  bool normals = false, colours = false;
  bool all_normals = true;
  std::int64_t points_total = -1;
  std::int64_t points_read = 0;
  std::int64_t grid_width = 0, grid_height = 1;  // PCD organisation; height 1 = unorganised
  Eigen::Vector3d sensor = Eigen::Vector3d::Zero();  // PCD VIEWPOINT position
};

namespace stream_detail {
std::unique_ptr<CloudChunkReader::Decoder> make_ply_decoder(const std::string& path, std::size_t buffer_bytes);
std::unique_ptr<CloudChunkReader::Decoder> make_pcd_decoder(const std::string& path, std::size_t buffer_bytes);
std::unique_ptr<CloudChunkReader::Decoder> make_xyz_decoder(const std::string& path, std::size_t buffer_bytes);
}  // namespace stream_detail

}  // namespace heatcvt
