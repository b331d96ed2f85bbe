// Quantised depth of depth cameras: detection and the refit of each point's depth.
#include "heatcvt/depth_steps.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

// The distinct values of column `axis` of P, ascending.
std::vector<double> levels_of(const Eigen::MatrixX3d& P, int axis) {
  std::vector<double> v(P.col(axis).data(), P.col(axis).data() + P.rows());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// The step of each level: the median of the gaps to its neighbouring levels (two on each side),
// so that a level missing from the cloud (no surface at that depth) does not count as a step.
std::vector<double> level_steps(const std::vector<double>& levels) {
  const int m = static_cast<int>(levels.size());
  std::vector<double> step(levels.size(), 0.0);
  for (int i = 0; i < m; ++i) {
    std::vector<double> gaps;
    for (int j = std::max(1, i - 1); j <= std::min(m - 1, i + 2); ++j) gaps.push_back(levels[j] - levels[j - 1]);
    if (gaps.empty()) continue;
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    step[i] = gaps[gaps.size() / 2];
  }
  return step;
}

// The image coordinates (u, v, 0) of the points, seen from `sensor` along `axis`.
Eigen::MatrixX3d image_coordinates(const Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, int axis) {
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  Eigen::MatrixX3d UV = Eigen::MatrixX3d::Zero(P.rows(), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double d = P(i, axis) - sensor[axis];
    UV(i, 0) = (P(i, a) - sensor[a]) / d;
    UV(i, 1) = (P(i, b) - sensor[b]) / d;
  }
  return UV;
}

// The state shared by the refits of one cloud.
struct Frame {
  const Eigen::MatrixX3d& P;
  const Eigen::MatrixX3d& UV;
  const Eigen::Vector3d& sensor;
  int axis;
  const std::vector<double>& levels;
  const std::vector<double>& step;
  double depth(Eigen::Index j) const { return P(j, axis) - sensor[axis]; }
  double step_of(Eigen::Index j) const {
    const auto it = std::lower_bound(levels.begin(), levels.end(), P(j, axis));
    return step[static_cast<size_t>(std::min<std::ptrdiff_t>(it - levels.begin(), levels.size() - 1))];
  }
};

// The fit window of point i among its k nearest image neighbours `nn`: those on its surface
// (within window_steps steps of its depth). Whether it spans min_levels levels with min_fit_points
// points goes to `enough`; `r` gets the image distance of the k-th neighbour.
std::vector<int> fit_window(const Frame& f, Eigen::Index i, const int* nn, int k, double s, const DepthStepOptions& o,
                            bool& enough, double& r) {
  std::vector<int> window;
  std::vector<double> seen;
  for (int q = 0; q < k; ++q) {
    const int j = nn[q];
    if (std::abs(f.depth(j) - f.depth(i)) > o.window_steps * s) continue;
    window.push_back(j);
    if (static_cast<int>(seen.size()) < o.min_levels && std::find(seen.begin(), seen.end(), f.P(j, f.axis)) == seen.end())
      seen.push_back(f.P(j, f.axis));
  }
  r = (f.UV.row(nn[k - 1]) - f.UV.row(i)).norm();
  enough = static_cast<int>(seen.size()) >= o.min_levels && static_cast<int>(window.size()) >= o.min_fit_points;
  return window;
}

// The refitted depth of point i over `window` (the file comment of depth_steps.h), or its own
// where the fit is degenerate. Inverse depth w = a + b·u' + c·v' with (u', v') the image offsets
// over r.
double refitted_depth(const Frame& f, Eigen::Index i, const std::vector<int>& window, double r, double s,
                      const DepthStepOptions& o) {
  const double d = f.depth(i);
  if (static_cast<int>(window.size()) < o.min_fit_points || !(r > 0)) return d;
  std::vector<char> use(window.size(), 1);
  double fit = 1 / d;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    int used = 0;
    for (size_t q = 0; q < window.size(); ++q) {
      if (!use[q]) continue;
      const int j = window[q];
      const Eigen::Vector3d x(1, (f.UV(j, 0) - f.UV(i, 0)) / r, (f.UV(j, 1) - f.UV(i, 1)) / r);
      const double w = std::exp(-2 * x.tail<2>().squaredNorm());  // Gaussian of σ = r / 2
      A += w * x * x.transpose();
      y += w * x / f.depth(j);
      ++used;
    }
    if (used < o.min_fit_points) return d;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-9)) return d;
    const Eigen::Vector3d c = ldlt.solve(y);
    fit = c[0];
    const double tolerance = o.inlier_steps * s / (d * d);  // a step of depth in inverse depth
    for (size_t q = 0; q < window.size(); ++q) {
      const int j = window[q];
      const double at = c[0] + c[1] * (f.UV(j, 0) - f.UV(i, 0)) / r + c[2] * (f.UV(j, 1) - f.UV(i, 1)) / r;
      use[q] = std::abs(1 / f.depth(j) - at) <= tolerance;
    }
  }
  if (!(fit * d > 0) || !std::isfinite(fit)) return d;
  return std::clamp(1 / fit, d - o.max_move_steps * s, d + o.max_move_steps * s);
}

// Exact nearest neighbours in the image plane: a uniform grid of cells over (u, v) holding about
// kPointsPerCell points each, searched ring by ring around the query's cell until the k nearest
// are closer than the ring's inner edge. Ties are ordered by index.
class ImageGrid {
 public:
  static constexpr double kPointsPerCell = 4;
  explicit ImageGrid(const Eigen::MatrixX3d& UV) : UV_(UV) {
    const Eigen::Index n = UV.rows();
    lo_ = UV.colwise().minCoeff().head<2>().transpose();
    const Eigen::Vector2d span = (UV.colwise().maxCoeff().head<2>().transpose() - lo_).cwiseMax(1e-300);
    cell_ = std::sqrt(span.x() * span.y() * kPointsPerCell / static_cast<double>(n));
    cell_ = std::max({cell_, span.maxCoeff() / static_cast<double>(n), 1e-300});
    nu_ = static_cast<int>(std::min<double>(n, std::floor(span.x() / cell_))) + 1;
    nv_ = static_cast<int>(std::min<double>(n, std::floor(span.y() / cell_))) + 1;
    std::vector<int> count(static_cast<size_t>(nu_) * nv_ + 1, 0);
    for (Eigen::Index i = 0; i < n; ++i) ++count[cell_of(i) + 1];
    for (size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    start_ = count;
    items_.resize(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) items_[static_cast<size_t>(count[cell_of(i)]++)] = static_cast<int>(i);
  }
  // The k nearest points of row i (itself first), into `out`.
  void nearest(Eigen::Index i, int k, std::vector<std::pair<double, int>>& found, std::vector<int>& out) const {
    const int cu = column(UV_(i, 0)), cv = row(UV_(i, 1));
    found.clear();
    for (int r = 0;; ++r) {
      for (int v = cv - r; v <= cv + r; ++v) {
        if (v < 0 || v >= nv_) continue;
        const bool edge_row = v == cv - r || v == cv + r;
        for (int u = cu - r; u <= cu + r; u += edge_row ? 1 : 2 * std::max(r, 1)) {
          if (u < 0 || u >= nu_) continue;
          const size_t c = static_cast<size_t>(v) * nu_ + u;
          for (int q = start_[c]; q < start_[c + 1]; ++q) {
            const int j = items_[static_cast<size_t>(q)];
            const double du = UV_(j, 0) - UV_(i, 0), dv = UV_(j, 1) - UV_(i, 1);
            found.emplace_back(du * du + dv * dv, j);
          }
        }
      }
      const bool all = r > nu_ && r > nv_;
      if (static_cast<int>(found.size()) >= k) {
        std::nth_element(found.begin(), found.begin() + (k - 1), found.end());
        const double reach = r * cell_;
        if (all || found[static_cast<size_t>(k - 1)].first <= reach * reach) break;
      } else if (all) {
        break;
      }
    }
    const int m = std::min<int>(k, static_cast<int>(found.size()));
    if (m < static_cast<int>(found.size())) std::nth_element(found.begin(), found.begin() + (m - 1), found.end());
    std::sort(found.begin(), found.begin() + m);
    out.resize(static_cast<size_t>(m));
    for (int q = 0; q < m; ++q) out[static_cast<size_t>(q)] = found[static_cast<size_t>(q)].second;
  }

 private:
  int column(double u) const { return std::clamp(static_cast<int>((u - lo_.x()) / cell_), 0, nu_ - 1); }
  int row(double v) const { return std::clamp(static_cast<int>((v - lo_.y()) / cell_), 0, nv_ - 1); }
  size_t cell_of(Eigen::Index i) const { return static_cast<size_t>(row(UV_(i, 1))) * nu_ + column(UV_(i, 0)); }
  const Eigen::MatrixX3d& UV_;
  Eigen::Vector2d lo_;
  double cell_ = 1;
  int nu_ = 1, nv_ = 1;
  std::vector<int> start_, items_;
};

// The refitted depth of every point: a window of start_neighbours image neighbours, doubled while
// it is not enough, up to max_neighbours (most points need the first or the second).
Eigen::VectorXd refitted_depths(const Frame& f, const DepthStepOptions& o) {
  const Eigen::Index n = f.P.rows();
  const int k_max = static_cast<int>(std::min<Eigen::Index>(o.max_neighbours, n));
  const ImageGrid grid(f.UV);
  Eigen::VectorXd depth(n);
#pragma omp parallel num_threads(resolve_threads(o.threads))
  {
    std::vector<std::pair<double, int>> found;
    std::vector<int> nn;
#pragma omp for schedule(dynamic, 256)
    for (Eigen::Index i = 0; i < n; ++i) {
      depth[i] = f.depth(i);
      const double s = f.step_of(i);
      if (!(s > 0)) continue;
      for (int k = std::min(o.start_neighbours, k_max);; k = std::min(2 * k, k_max)) {
        grid.nearest(i, k, found, nn);
        bool enough = false;
        double r = 0;
        const std::vector<int> window = fit_window(f, i, nn.data(), static_cast<int>(nn.size()), s, o, enough, r);
        if (enough || k == k_max) {
          depth[i] = refitted_depth(f, i, window, r, s, o);
          break;
        }
      }
    }
  }
  return depth;
}

}  // namespace

void check_depth_step_options(const DepthStepOptions& o) {
  auto fail = [](const std::string& what) { throw InvalidInputError("depth steps: " + what); };
  if (!(o.max_distinct_fraction >= 0 && o.max_distinct_fraction <= 1)) fail("max_distinct_fraction must be in [0, 1]");
  if (!(o.max_view_angle_deg > 0 && o.max_view_angle_deg < 90)) fail("max_view_angle_deg must be in (0, 90)");
  if (!(o.min_view_extent_deg >= 0 && o.min_view_extent_deg < 180)) fail("min_view_extent_deg must be in [0, 180)");
  if (!(o.min_relative_step >= 0 && o.min_relative_step < 1)) fail("min_relative_step must be in [0, 1)");
  if (o.min_points < 3 || o.min_levels < 2 || o.min_fit_points < 3) fail("min_points, min_levels and min_fit_points must be >= 3, 2 and 3");
  if (o.start_neighbours < 3 || o.start_neighbours > o.max_neighbours || o.max_neighbours > 1024)
    fail("need 3 <= start_neighbours <= max_neighbours <= 1024");
  if (!(o.window_steps > 0 && std::isfinite(o.window_steps)) || !(o.inlier_steps > 0 && std::isfinite(o.inlier_steps)) ||
      !(o.max_move_steps > 0 && std::isfinite(o.max_move_steps)))
    fail("window_steps, inlier_steps and max_move_steps must be finite and > 0");
}

namespace {

// What the detection found, with the levels, their steps and the image coordinates the refit
// goes on with (empty where the cloud is not a quantised depth frame).
struct Detection {
  DepthStepReport rep;
  std::vector<double> levels, step;
  Eigen::MatrixX3d UV;
};

Detection detect(const Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, const DepthStepOptions& o) {
  check_depth_step_options(o);
  Detection out;
  DepthStepReport& rep = out.rep;
  if (!o.enabled() || P.rows() < o.min_points) return out;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = static_cast<std::int64_t>(levels_of(P, a).size());
    if (rep.axis < 0 || n < rep.levels) rep.axis = a, rep.levels = n;
  }
  rep.distinct_fraction = static_cast<double>(rep.levels) / static_cast<double>(P.rows());
  if (rep.distinct_fraction > o.max_distinct_fraction || rep.levels < 2) return out;
  // In front of the sensor along the axis, within the field of view.
  const double max_tan = std::tan(o.max_view_angle_deg * M_PI / 180);
  const double sign = P(0, rep.axis) - sensor[rep.axis] > 0 ? 1 : -1;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    Eigen::Vector3d off = P.row(i).transpose() - sensor;
    const double along = sign * off[rep.axis];
    off[rep.axis] = 0;
    if (!(along > 0) || off.norm() > max_tan * along) return out;
  }
  out.UV = image_coordinates(P, sensor, rep.axis);
  const Eigen::RowVector3d extent = out.UV.colwise().maxCoeff() - out.UV.colwise().minCoeff();
  if (extent.maxCoeff() < std::tan(o.min_view_extent_deg * M_PI / 180)) return out;
  out.levels = levels_of(P, rep.axis);
  out.step = level_steps(out.levels);
  const std::vector<double>& levels = out.levels;
  const std::vector<double>& step = out.step;
  std::vector<double> per_point(static_cast<size_t>(P.rows())), depth(per_point.size());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    per_point[static_cast<size_t>(i)] =
        step[static_cast<size_t>(std::lower_bound(levels.begin(), levels.end(), P(i, rep.axis)) - levels.begin())];
    depth[static_cast<size_t>(i)] = std::abs(P(i, rep.axis) - sensor[rep.axis]);
  }
  const size_t mid = per_point.size() / 2;
  std::nth_element(per_point.begin(), per_point.begin() + mid, per_point.end());
  std::nth_element(depth.begin(), depth.begin() + mid, depth.end());
  if (!(per_point[mid] >= o.min_relative_step * depth[mid])) return out;
  rep.median_step = per_point[mid];
  rep.quantised = true;
  return out;
}

}  // namespace

DepthStepReport depth_steps_of(const Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, const DepthStepOptions& o) {
  return detect(P, sensor, o).rep;
}

DepthStepReport smooth_depth_steps(Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, const DepthStepOptions& o) {
  if (!P.allFinite() || !sensor.allFinite()) throw InvalidInputError("depth steps: a NaN or infinite coordinate");
  const auto started = std::chrono::steady_clock::now();
  const Detection found = detect(P, sensor, o);
  DepthStepReport rep = found.rep;
  const auto timed = [&] {
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return rep;
  };
  if (!rep.quantised) return timed();
  const Frame frame{P, found.UV, sensor, rep.axis, found.levels, found.step};
  const Eigen::VectorXd depth = refitted_depths(frame, o);
  // Each point moves along its ray: p ↦ sensor + (p − sensor) · d' / d.
  double moved_steps = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double d = frame.depth(i);
    if (depth[i] == d) continue;
    moved_steps += std::abs(depth[i] - d) / frame.step_of(i);
    P.row(i) = (sensor + (P.row(i).transpose() - sensor) * (depth[i] / d)).transpose();
    ++rep.points_moved;
  }
  rep.mean_move_steps = rep.points_moved > 0 ? moved_steps / static_cast<double>(rep.points_moved) : 0;
  return timed();
}

}  // namespace heatcvt
