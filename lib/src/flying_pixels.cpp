// Flying pixels of organised clouds (flying_pixels.h).
#include "heatcvt/flying_pixels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace {

// Whether pixel (x, y) of the grid is flying. `P` holds the grid's points from index `first` on
// (rows y − 1 .. y + 1 at least, as far as they exist).
bool is_flying(const Eigen::MatrixX3d& P, std::int64_t first, int width, int height, int x, int y,
               const Eigen::Vector3d& sensor, const FlyingPixelOptions& o) {
  auto at = [&](int xx, int yy) { return P.row(static_cast<Eigen::Index>(static_cast<std::int64_t>(yy) * width + xx - first)); };
  const Eigen::RowVector3d p = at(x, y);
  if (!p.allFinite()) return false;
  const double reach = o.neighbour_distance_ratio * (p.transpose() - sensor).norm();
  int valid = 0, close = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if ((dx == 0 && dy == 0) || xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
      const Eigen::RowVector3d q = at(xx, yy);
      if (!q.allFinite()) continue;
      ++valid;
      close += (q - p).norm() < reach;
    }
  return valid >= o.min_close_neighbours && close < o.min_close_neighbours;
}

void append_rows(CloudChunk& dst, const CloudChunk& src) {
  const Eigen::Index n = dst.rows(), m = src.rows();
  auto grow = [&](Eigen::MatrixX3d& d, const Eigen::MatrixX3d& s) {
    if (s.rows() != m) return;
    d.conservativeResize(n + m, 3);
    d.bottomRows(m) = s;
  };
  if (n == 0) {
    dst = src;
    return;
  }
  grow(dst.N, src.N);
  grow(dst.C, src.C);
  grow(dst.P, src.P);
}

CloudChunk take_rows(const CloudChunk& c, Eigen::Index begin, Eigen::Index count) {
  CloudChunk out;
  out.P = c.P.middleRows(begin, count);
  if (c.has_normals()) out.N = c.N.middleRows(begin, count);
  if (c.has_colours()) out.C = c.C.middleRows(begin, count);
  return out;
}

}  // namespace

void check_flying_pixel_options(const FlyingPixelOptions& o) {
  if (!std::isfinite(o.neighbour_distance_ratio) || o.neighbour_distance_ratio < 0)
    throw InvalidInputError("flying pixels: the neighbour distance ratio must be finite and >= 0");
  if (o.min_close_neighbours < 1 || o.min_close_neighbours > 8)
    throw InvalidInputError("flying pixels: min_close_neighbours must be in 1..8");
}

std::vector<char> flying_pixel_mask(const Eigen::MatrixX3d& P, int width, int height, const Eigen::Vector3d& sensor,
                                    const FlyingPixelOptions& options) {
  check_flying_pixel_options(options);
  if (width < 1 || height < 1 || P.rows() != static_cast<Eigen::Index>(width) * height)
    throw InvalidInputError("flying pixels: the grid has " + std::to_string(P.rows()) + " points, not width " +
                            std::to_string(width) + " x height " + std::to_string(height));
  std::vector<char> mask(static_cast<size_t>(P.rows()), 0);
  if (!options.enabled() || height < 2) return mask;
#pragma omp parallel for schedule(static)
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      mask[static_cast<size_t>(y) * width + x] = is_flying(P, 0, width, height, x, y, sensor, options);
  return mask;
}

std::int64_t remove_flying_pixels(Eigen::MatrixX3d& P, int width, int height, const Eigen::Vector3d& sensor,
                                  const FlyingPixelOptions& options) {
  const std::vector<char> mask = flying_pixel_mask(P, width, height, sensor, options);
  std::int64_t removed = 0;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      P.row(static_cast<Eigen::Index>(i)).setConstant(std::numeric_limits<double>::quiet_NaN());
      ++removed;
    }
  return removed;
}

FlyingPixelFilter::FlyingPixelFilter(CloudChunkSource& source, int width, int height, const Eigen::Vector3d& sensor,
                                     const FlyingPixelOptions& options)
    : source_(source), width_(width), height_(height), sensor_(sensor), options_(options) {
  check_flying_pixel_options(options);
  if (width < 1 || height < 1) throw InvalidInputError(source.name() + ": an organised cloud needs width and height >= 1");
}

// Reads source chunks until pending_ reaches grid index `upto` (exclusive) or the source ends.
bool FlyingPixelFilter::fill(std::int64_t upto) {
  CloudChunk c;
  while (!source_done_ && pending_first_ + pending_.rows() < upto) {
    if (!source_.next(c)) {
      source_done_ = true;
      break;
    }
    append_rows(pending_, c);
  }
  return pending_first_ + pending_.rows() > next_out_;
}

bool FlyingPixelFilter::next(CloudChunk& chunk) {
  const std::int64_t total = static_cast<std::int64_t>(width_) * height_;
  const std::int64_t y0 = next_out_ / width_;  // next_out_ is always at a row start
  // Rows y0 .. y1 − 1 go out; each needs the row after it complete (or to be the last row).
  if (!fill(std::min(total, (y0 + 2) * width_))) {
    chunk = CloudChunk{};
    return false;
  }
  const std::int64_t have = pending_first_ + pending_.rows();
  std::int64_t y1 = have >= total ? height_ : std::max<std::int64_t>(y0 + 1, have / width_ - 1);
  // A source shorter than its grid (not an organised cloud after all): the rest goes out as is.
  const bool short_source = source_done_ && have < total;
  if (short_source) y1 = y0;
  const std::int64_t end = short_source ? have : std::min(have, y1 * width_);
  chunk = take_rows(pending_, static_cast<Eigen::Index>(next_out_ - pending_first_),
                    static_cast<Eigen::Index>(end - next_out_));
  if (options_.enabled() && height_ >= 2)
    for (std::int64_t y = y0; y < y1; ++y)
      for (int x = 0; x < width_; ++x)
        if (is_flying(pending_.P, pending_first_, width_, height_, x, static_cast<int>(y), sensor_, options_)) {
          chunk.P.row(static_cast<Eigen::Index>(y * width_ + x - next_out_))
              .setConstant(std::numeric_limits<double>::quiet_NaN());
          ++removed_;
        }
  next_out_ = end;
  // Keep the last row handed out: it is the row above the next one.
  const std::int64_t keep_from = std::max(pending_first_, short_source ? end : (y1 - 1) * width_);
  pending_ = take_rows(pending_, static_cast<Eigen::Index>(keep_from - pending_first_),
                       static_cast<Eigen::Index>(have - keep_from));
  pending_first_ = keep_from;
  return chunk.rows() > 0 || next(chunk);
}

void FlyingPixelFilter::rewind() {
  source_.rewind();
  pending_ = CloudChunk{};
  pending_first_ = next_out_ = 0;
  source_done_ = false;
  removed_ = 0;
}

}  // namespace heatcvt
