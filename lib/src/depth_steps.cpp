// Quantised depth of depth cameras: detection and the refit of each point's depth.
#include "heatcvt/depth_steps.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

// Queries of one kNN call: bounds the neighbour table to chunk × max_neighbours entries.
constexpr Eigen::Index kQueryChunk = 65536;

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

// The neighbours (a prefix of the row `nn`) on the point's surface: the smallest window that
// spans min_levels levels with min_fit_points points, or the largest one. `r` gets the image
// distance of the window's last neighbour.
std::vector<int> fit_window(const Frame& f, Eigen::Index i, const int* nn, int k_max, double s,
                            const DepthStepOptions& o, double& r) {
  std::vector<int> window;
  for (int k = std::min(o.start_neighbours, k_max);; k = std::min(2 * k, k_max)) {
    window.clear();
    std::vector<double> seen;
    for (int q = 0; q < k; ++q) {
      const int j = nn[q];
      if (std::abs(f.depth(j) - f.depth(i)) > o.window_steps * s) continue;
      window.push_back(j);
      if (std::find(seen.begin(), seen.end(), f.P(j, f.axis)) == seen.end()) seen.push_back(f.P(j, f.axis));
    }
    r = (f.UV.row(nn[k - 1]) - f.UV.row(i)).norm();
    const bool enough = static_cast<int>(seen.size()) >= o.min_levels && static_cast<int>(window.size()) >= o.min_fit_points;
    if (enough || k == k_max) return window;
  }
}

// The refitted depth of point i (the file comment of depth_steps.h), or its own where the fit is
// degenerate. Inverse depth w = a + b·u' + c·v' with (u', v') the image offsets over r.
double refitted_depth(const Frame& f, Eigen::Index i, const int* nn, int k_max, const DepthStepOptions& o) {
  const double d = f.depth(i), s = f.step_of(i);
  if (!(s > 0)) return d;
  double r = 0;
  const std::vector<int> window = fit_window(f, i, nn, k_max, s, o, r);
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

}  // namespace

void check_depth_step_options(const DepthStepOptions& o) {
  auto fail = [](const std::string& what) { throw InvalidInputError("depth steps: " + what); };
  if (!(o.max_distinct_fraction >= 0 && o.max_distinct_fraction <= 1)) fail("max_distinct_fraction must be in [0, 1]");
  if (!(o.max_view_angle_deg > 0 && o.max_view_angle_deg < 90)) fail("max_view_angle_deg must be in (0, 90)");
  if (o.min_points < 3 || o.min_levels < 2 || o.min_fit_points < 3) fail("min_points, min_levels and min_fit_points must be >= 3, 2 and 3");
  if (o.start_neighbours < 3 || o.start_neighbours > o.max_neighbours || o.max_neighbours > 1024)
    fail("need 3 <= start_neighbours <= max_neighbours <= 1024");
  if (!(o.window_steps > 0 && std::isfinite(o.window_steps)) || !(o.inlier_steps > 0 && std::isfinite(o.inlier_steps)) ||
      !(o.max_move_steps > 0 && std::isfinite(o.max_move_steps)))
    fail("window_steps, inlier_steps and max_move_steps must be finite and > 0");
}

DepthStepReport depth_steps_of(const Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, const DepthStepOptions& o) {
  check_depth_step_options(o);
  DepthStepReport rep;
  if (!o.enabled() || P.rows() < o.min_points) return rep;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t n = static_cast<std::int64_t>(levels_of(P, a).size());
    if (rep.axis < 0 || n < rep.levels) rep.axis = a, rep.levels = n;
  }
  rep.distinct_fraction = static_cast<double>(rep.levels) / static_cast<double>(P.rows());
  if (rep.distinct_fraction > o.max_distinct_fraction || rep.levels < 2) return rep;
  // In front of the sensor along the axis, within the field of view.
  const double max_tan = std::tan(o.max_view_angle_deg * M_PI / 180);
  const Eigen::VectorXd d = P.col(rep.axis).array() - sensor[rep.axis];
  const double sign = d[0] > 0 ? 1 : -1;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    Eigen::Vector3d off = P.row(i).transpose() - sensor;
    const double along = sign * off[rep.axis];
    off[rep.axis] = 0;
    if (!(along > 0) || off.norm() > max_tan * along) return rep;
  }
  rep.quantised = true;
  const std::vector<double> levels = levels_of(P, rep.axis), step = level_steps(levels);
  std::vector<double> per_point(static_cast<size_t>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    per_point[static_cast<size_t>(i)] =
        step[static_cast<size_t>(std::lower_bound(levels.begin(), levels.end(), P(i, rep.axis)) - levels.begin())];
  std::nth_element(per_point.begin(), per_point.begin() + per_point.size() / 2, per_point.end());
  rep.median_step = per_point[per_point.size() / 2];
  return rep;
}

DepthStepReport smooth_depth_steps(Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor, const DepthStepOptions& o) {
  if (!P.allFinite() || !sensor.allFinite()) throw InvalidInputError("depth steps: a NaN or infinite coordinate");
  DepthStepReport rep = depth_steps_of(P, sensor, o);
  if (!rep.quantised) return rep;
  const std::vector<double> levels = levels_of(P, rep.axis), step = level_steps(levels);
  const Eigen::MatrixX3d UV = image_coordinates(P, sensor, rep.axis);
  const int k_max = static_cast<int>(std::min<Eigen::Index>(o.max_neighbours, P.rows()));
  const Frame frame{P, UV, sensor, rep.axis, levels, step};
  Eigen::VectorXd depth(P.rows()), moved_steps = Eigen::VectorXd::Zero(P.rows());
  for (Eigen::Index first = 0; first < P.rows(); first += kQueryChunk) {
    const Eigen::Index count = std::min(kQueryChunk, P.rows() - first);
    // Row-major neighbour table of the chunk (the point itself first, ties by index).
    const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> nn =
        nearest_neighbors_of(UV, UV.middleRows(first, count), k_max, o.threads);
#pragma omp parallel for num_threads(resolve_threads(o.threads)) schedule(dynamic, 256)
    for (Eigen::Index q = 0; q < count; ++q) {
      const Eigen::Index i = first + q;
      depth[i] = refitted_depth(frame, i, nn.row(q).data(), k_max, o);
      const double s = frame.step_of(i);
      if (s > 0) moved_steps[i] = std::abs(depth[i] - frame.depth(i)) / s;
    }
  }
  // Each point moves along its ray: p ↦ sensor + (p − sensor) · d' / d.
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double d = frame.depth(i);
    if (depth[i] == d) continue;
    P.row(i) = (sensor + (P.row(i).transpose() - sensor) * (depth[i] / d)).transpose();
    ++rep.points_moved;
  }
  rep.mean_move_steps = rep.points_moved > 0 ? moved_steps.sum() / static_cast<double>(rep.points_moved) : 0;
  return rep;
}

}  // namespace heatcvt
