#pragma once
/// \file flying_pixels.h
/// Flying pixels of organised clouds. A depth sensor (time-of-flight, some structured-light and
/// stereo cameras) that sees a foreground edge in front of a background mixes the two returns in
/// the pixels on the edge: their depth lies anywhere between the two surfaces, and the cloud gets
/// a sparse veil of points standing along the viewing rays. Meshed, the veil becomes a curtain of
/// triangles from the object's silhouette down to the background, in the air.
///
/// In the image grid of an organised cloud (PCD WIDTH × HEIGHT > 1, row-major, NaN where there is
/// no return) a pixel on a surface has neighbours on that surface, at most a few pixel footprints
/// away, while a flying pixel is far from all of them. The rule: a pixel with at least
/// `min_close_neighbours` valid grid neighbours (of its 8), fewer than `min_close_neighbours` of
/// which lie within `neighbour_distance_ratio` × its range (distance to the sensor), is flying.
/// Pixels with fewer valid neighbours than that (dropouts around them) are kept: nothing to judge
/// them by. Unorganised clouds have no grid and are left as they are.
#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <vector>

#include "heatcvt/cloud_stream.h"

namespace heatcvt {

/// Options of the flying-pixel rule (see the file comment).
struct FlyingPixelOptions {
  /// A grid neighbour closer than this times the pixel's range counts as on the same surface.
  /// A pixel footprint on a surface seen at angle θ from head-on is (pixel angle / cos θ) × range,
  /// so the default 3 % keeps surfaces seen at up to 85° by a 320-pixel, 50° camera (87° at 640
  /// pixels, 77° at 160); pixels at more grazing angles go too. 0 turns the rule off. Default 0.03.
  double neighbour_distance_ratio = 0.03;
  /// Close neighbours a pixel needs (and valid neighbours it must have to be judged). Default 2:
  /// a pixel on a one-pixel-wide wire still has its two neighbours along the wire.
  int min_close_neighbours = 2;
  bool enabled() const { return neighbour_distance_ratio > 0; }
};

/// \throw InvalidInputError on a non-finite or negative ratio or min_close_neighbours outside 1..8.
void check_flying_pixel_options(const FlyingPixelOptions& options);

/// 1 for the flying pixels of the row-major `width` × `height` grid P (#P = width·height rows;
/// NaN rows are pixels without a return), ranges measured from `sensor`. All zeros when the
/// rule is off or height < 2.
/// \throw InvalidInputError when P.rows() != width·height, or on bad options.
std::vector<char> flying_pixel_mask(const Eigen::MatrixX3d& P, int width, int height, const Eigen::Vector3d& sensor,
                                    const FlyingPixelOptions& options = {});

/// Sets the flying pixels of the grid to NaN (so that the clean-up drops them) and returns how
/// many there were.
std::int64_t remove_flying_pixels(Eigen::MatrixX3d& P, int width, int height, const Eigen::Vector3d& sensor,
                                  const FlyingPixelOptions& options = {});

/// The same rule on a stream: wraps a source of an organised cloud (chunks in file order, NaN
/// pixels included) and hands out the same points with the flying pixels set to NaN. Holds three
/// grid rows at a time; the result does not depend on the chunk sizes of the source.
class FlyingPixelFilter : public CloudChunkSource {
 public:
  /// `source` must outlive the filter. \throw InvalidInputError on bad options or width < 1.
  FlyingPixelFilter(CloudChunkSource& source, int width, int height, const Eigen::Vector3d& sensor,
                    const FlyingPixelOptions& options = {});
  bool next(CloudChunk& chunk) override;
  void rewind() override;
  const std::string& name() const override { return source_.name(); }
  /// The wrapped source.
  const CloudChunkSource& source() const { return source_; }
  /// Flying pixels found in the current pass so far.
  std::int64_t removed() const { return removed_; }

 private:
  bool fill(std::int64_t rows_wanted);
  CloudChunkSource& source_;
  int width_, height_;
  Eigen::Vector3d sensor_;
  FlyingPixelOptions options_;
  CloudChunk pending_;            // points read from the source and not yet handed out
  std::int64_t pending_first_ = 0;  // grid index of pending_'s first row
  std::int64_t next_out_ = 0;       // grid index of the next point to hand out
  bool source_done_ = false;
  std::int64_t removed_ = 0;
};

}  // namespace heatcvt
