#pragma once
/// \file cloud_stream.h
/// Streaming point-cloud readers: a CloudChunkReader opens a cloud file and hands out its points
/// in fixed-size chunks (positions, and normals / colours where the file has them) without ever
/// holding the whole file. Formats, validation and error messages are those of read_cloud()
/// (cloud_io.h); the chunks are the points read_cloud reads, in file order, BEFORE its clean-up
/// (non-finite points are handed out, duplicates are not merged: apply clean_cloud() to the
/// concatenation to get read_cloud's result).
///
/// Memory: one read buffer (StreamReaderOptions::buffer_bytes) plus one chunk, for every format
/// except PCD `binary_compressed`: that format stores the whole cloud as ONE LZF block laid out
/// column by column (all x, then all y, ...), so the reader holds the decompressed block (the
/// size of the uncompressed cloud) for the file's lifetime; convert such files to binary PCD or
/// binary PLY to stream them in bounded memory.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace heatcvt {

/// A piece of a cloud.
///   P  #rows by 3 positions (may hold NaN / inf: no clean-up is applied)
///   N  #rows by 3 normals, or 0 rows when the file has none
///   C  #rows by 3 colours in [0,1], or 0 rows when the file has none
struct CloudChunk {
  Eigen::MatrixX3d P;
  Eigen::MatrixX3d N;
  Eigen::MatrixX3d C;
  Eigen::Index rows() const { return P.rows(); }
  bool has_normals() const { return N.rows() > 0 && N.rows() == P.rows(); }
  bool has_colours() const { return C.rows() > 0 && C.rows() == P.rows(); }
};

/// Progress of a streamed read.
struct StreamProgress {
  std::int64_t bytes_read = 0;     ///< bytes of the file consumed so far
  std::int64_t bytes_total = 0;    ///< size of the file
  std::int64_t points_read = 0;    ///< points handed out so far
  std::int64_t points_total = -1;  ///< points announced by the header; -1 when unknown (XYZ text)
};
/// Called after every chunk (and once when the data ends).
using StreamProgressCallback = std::function<void(const StreamProgress&)>;

/// Anything that hands out a cloud chunk by chunk and can start again from the beginning
/// (reconstruct_surface_streamed reads its source twice: reconstruct_stream.h).
class CloudChunkSource {
 public:
  virtual ~CloudChunkSource() = default;
  /// Fills `chunk` with the next at most chunk_points() points; returns false (and an empty
  /// chunk) when the cloud is exhausted. \throw IOError "<name>: <problem>" on bad data.
  virtual bool next(CloudChunk& chunk) = 0;
  /// Starts again from the first point.
  virtual void rewind() = 0;
  /// The file (or other source) name used in error messages.
  virtual const std::string& name() const = 0;
};

/// A cloud held in memory handed out in chunks of `chunk_points` rows (a cloud read whole and
/// changed before it is streamed: the quantised depth of a depth frame refitted, depth_steps.h).
/// Normals and colours are handed out where the cloud has them for every point.
class MemoryChunkSource : public CloudChunkSource {
 public:
  /// `P`, `N` and `C` must outlive the source. \throw InvalidInputError where chunk_points < 1.
  MemoryChunkSource(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixX3d& C,
                    std::string name, std::int64_t chunk_points = 65536);
  bool next(CloudChunk& chunk) override;
  void rewind() override { next_ = 0; }
  const std::string& name() const override { return name_; }

 private:
  const Eigen::MatrixX3d &P_, &N_, &C_;
  std::string name_;
  std::int64_t chunk_points_;
  Eigen::Index next_ = 0;
};

/// Options of CloudChunkReader.
struct StreamReaderOptions {
  /// Points per chunk (>= 1). Default 65536 (1.5 MB of positions per chunk).
  std::int64_t chunk_points = 65536;
  /// Size of the file read buffer in bytes (>= 4096). Default 1 MiB.
  std::size_t buffer_bytes = std::size_t(1) << 20;
  /// Progress callback (empty = none). Default none.
  StreamProgressCallback progress;
};

/// Streams a cloud file chunk by chunk; format by extension as read_cloud():
///   .ply            binary little / big endian and ascii PLY: the vertex element (x y z, nx ny nz,
///                   red green blue or diffuse_*); other elements are read past and validated
///                   (face indices in range, list lengths, truncation) but not stored;
///   .pcd            ascii, binary, binary_compressed (see the file comment about memory);
///                   fields x y z (+ normal_x normal_y normal_z, rgb / rgba or r g b) of any type;
///   .xyz .pwn .txt  lines "x y z [nx ny nz ...]", '#' comments and blank lines skipped, one
///                   leading count line accepted.
/// XYZ normals: read_cloud keeps normals only if EVERY line has >= 6 columns, which a stream
/// cannot know in advance; the chunks carry normals when the first point's line has them, a later
/// line with fewer columns gets a NaN normal, and all_points_had_normals() turns false (the
/// caller then drops the normals, as read_cloud does).
/// \throw IOError "<path>: <problem>" (missing / unreadable / empty file, unknown extension,
///        malformed header or data, truncated data: detected where the data ends, or at the start
///        of an element when the file is too short for the count its header announces).
class CloudChunkReader : public CloudChunkSource {
 public:
  explicit CloudChunkReader(const std::string& path, StreamReaderOptions options = {});
  ~CloudChunkReader() override;
  CloudChunkReader(const CloudChunkReader&) = delete;
  CloudChunkReader& operator=(const CloudChunkReader&) = delete;

  bool next(CloudChunk& chunk) override;
  void rewind() override;
  const std::string& name() const override { return path_; }

  /// "ply-binary_little_endian", "pcd-ascii", ..., "xyz": the CloudReadReport::format names.
  const std::string& format() const;
  /// The chunks carry normals / colours.
  bool has_normals() const;
  bool has_colours() const;
  /// XYZ only: false once a line without normals followed lines with normals (see above).
  bool all_points_had_normals() const;
  /// Points announced by the header (PLY vertex count, PCD POINTS); -1 for XYZ text.
  std::int64_t points_in_file() const;
  /// Organisation of a PCD cloud (WIDTH × HEIGHT, row-major; HEIGHT > 1 is an image grid);
  /// other formats: points_in_file() × 1.
  std::int64_t grid_width() const;
  std::int64_t grid_height() const;
  /// The sensor position of a PCD cloud (its VIEWPOINT translation); the origin otherwise.
  Eigen::Vector3d sensor_origin() const;
  /// Points handed out so far.
  std::int64_t points_read() const;
  /// Bytes of the file consumed so far and the file size.
  std::int64_t bytes_read() const;
  std::int64_t bytes_total() const;
  /// Passes over the file started so far (1 + the number of rewind() calls).
  int passes() const { return passes_; }

  /// The format-specific decoder (defined in the implementation).
  class Decoder;

 private:
  void open();
  std::string path_;
  StreamReaderOptions options_;
  std::unique_ptr<Decoder> decoder_;
  int passes_ = 1;
};

}  // namespace heatcvt
