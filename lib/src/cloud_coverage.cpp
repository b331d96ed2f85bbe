// Coverage of a point cloud by the mesh made from it (cloud_coverage.h).
#include "heatcvt/cloud_coverage.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/disjoint_sets.h"
#include "heatcvt/errors.h"
#include "heatcvt/grid_cell.h"
#include "heatcvt/noise_estimate.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

}  // namespace

void check_cloud_coverage_options(const CloudCoverageOptions& o) {
  auto bad = [](const std::string& m) { throw InvalidInputError("cloud_coverage: " + m); };
  if (o.max_queries < 1) bad("max_queries must be >= 1");
  if (!(o.covered_spacings > 0) || !std::isfinite(o.covered_spacings)) bad("covered_spacings must be finite and > 0");
  if (!(o.group_spacings > 0) || !std::isfinite(o.group_spacings)) bad("group_spacings must be finite and > 0");
  if (!(o.partial_share >= 0 && o.partial_share <= 1)) bad("partial_share must be in [0, 1]");
  if (!(o.volume_thickness > 0) || !std::isfinite(o.volume_thickness)) bad("volume_thickness must be finite and > 0");
  if (o.max_radius_doublings < 0) bad("max_radius_doublings must be >= 0");
  if (!(o.volume_radius_spacings >= 1) || !std::isfinite(o.volume_radius_spacings))
    bad("volume_radius_spacings must be finite and >= 1");
}

namespace {

// The rows of P measured: all of them, or an even stride down to at most max_queries.
Eigen::MatrixX3d query_rows(const Eigen::MatrixX3d& P, int max_queries) {
  const Eigen::Index stride = std::max<Eigen::Index>(1, (P.rows() + max_queries - 1) / max_queries);
  Eigen::MatrixX3d Q((P.rows() + stride - 1) / stride, 3);
  for (Eigen::Index i = 0; i < Q.rows(); ++i) Q.row(i) = P.row(i * stride);
  return Q;
}

// Groups of the points Q: two points are in one group where their grid cells (of side `cell`)
// touch (the 26 neighbours of a cell). Returns the group of each point, numbered from 0 in the
// order of their first point.
std::vector<int> point_groups(const Eigen::MatrixX3d& Q, double cell, int& groups) {
  std::unordered_map<GridCell, int, GridCellHash> cell_index;
  std::vector<int> cell_of(static_cast<std::size_t>(Q.rows()));
  for (Eigen::Index i = 0; i < Q.rows(); ++i) {
    const auto [it, added] = cell_index.try_emplace(grid_cell(Q.row(i).transpose(), cell), static_cast<int>(cell_index.size()));
    cell_of[static_cast<std::size_t>(i)] = it->second;
  }
  DisjointSets sets(static_cast<int>(cell_index.size()));
  for (const auto& [c, index] : cell_index)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cell_index.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it != cell_index.end()) sets.unite(index, it->second);
        }
  std::unordered_map<int, int> number;  // set representative -> group number
  std::vector<int> group(cell_of.size());
  for (std::size_t i = 0; i < cell_of.size(); ++i)
    group[i] = number.try_emplace(sets.find(cell_of[i]), static_cast<int>(number.size())).first->second;
  groups = static_cast<int>(number.size());
  return group;
}

// The largest group of the uncovered points U (by point count, the first such group on ties):
// its point count and bounding-box diagonal.
void largest_group(const Eigen::MatrixX3d& U, double cell, CloudCoverage& out, double& points, double& diagonal) {
  const std::vector<int> group = point_groups(U, cell, out.groups);
  std::vector<int> count(static_cast<std::size_t>(out.groups), 0);
  for (int g : group) ++count[static_cast<std::size_t>(g)];
  const int best = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (Eigen::Index i = 0; i < U.rows(); ++i)
    if (group[static_cast<std::size_t>(i)] == best) {
      lo = lo.cwiseMin(U.row(i).transpose());
      hi = hi.cwiseMax(U.row(i).transpose());
    }
  points = count[static_cast<std::size_t>(best)];
  diagonal = (hi - lo).norm();
}

// The thickness of the points P at `spacing` (CloudCoverage::thickness_spacings): the noise
// estimate within one spacing, or within 2, 4, ... spacings where most of its queries find too few
// points (a sparse cloud), in spacings.
void measure_thickness(const Eigen::MatrixX3d& P, double spacing, const CloudCoverageOptions& options,
                       CloudCoverage& out) {
  NoiseEstimateOptions noise;
  noise.threads = options.threads;
  for (int doubling = 0;; ++doubling) {
    const NoiseEstimate e = estimate_noise(P, spacing, noise);
    const int asked = static_cast<int>(std::min<Eigen::Index>(noise.queries, P.rows()));
    if (2 * e.queries_used >= asked || doubling == options.max_radius_doublings) {
      out.thickness_spacings = e.sigma / spacing;
      out.thickness_radius_spacings = noise.radius_spacings;
      return;
    }
    noise.radius_spacings *= 2;
  }
}

}  // namespace

CloudCoverage cloud_coverage(const TriangleMesh& mesh, const Eigen::MatrixX3d& P, double site_spacing,
                             const CloudCoverageOptions& options) {
  check_cloud_coverage_options(options);
  if (!(site_spacing >= 0) || !std::isfinite(site_spacing))
    throw InvalidInputError("cloud_coverage: site_spacing must be finite and >= 0");
  if (mesh.F.rows() == 0) throw InvalidInputError("cloud_coverage: the mesh has no faces");
  CloudCoverage out;
  out.partial_share = options.partial_share;
  out.volume_thickness = options.volume_thickness;
  out.volume_radius_spacings = options.volume_radius_spacings;
  if (P.rows() == 0) return out;
  out.spacing = mean_edge_length(mesh.V, mesh.F);
  const Eigen::MatrixX3d Q = query_rows(P, options.max_queries);
  out.queries = static_cast<int>(Q.rows());
  const ClosestPointTree tree(mesh.V, mesh.F);
  const double reach = options.covered_spacings * out.spacing;
  std::vector<char> far(static_cast<std::size_t>(Q.rows()), 0);
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(dynamic, 256)
  for (Eigen::Index i = 0; i < Q.rows(); ++i) {
    const Eigen::Vector3d q = Q.row(i).transpose();
    far[static_cast<std::size_t>(i)] = (position(mesh.V, mesh.F, tree.closest(q)) - q).norm() > reach;
  }
  const long uncovered = std::count(far.begin(), far.end(), 1);
  out.uncovered_share = static_cast<double>(uncovered) / static_cast<double>(Q.rows());
  const double at = site_spacing > 0 ? site_spacing : out.spacing;
  if (at > 0) measure_thickness(P, at, options, out);
  if (uncovered == 0 || !(out.spacing > 0)) return out;
  Eigen::MatrixX3d U(uncovered, 3);
  for (Eigen::Index i = 0, r = 0; i < Q.rows(); ++i)
    if (far[static_cast<std::size_t>(i)]) U.row(r++) = Q.row(i);
  double points = 0, diagonal = 0;
  // Joined at the larger of the two spacings: a mesh of a small part of the cloud, sized to all the
  // vertices asked for, has edges far shorter than the spacing the points were sampled for.
  largest_group(U, options.group_spacings * std::max(out.spacing, site_spacing), out, points, diagonal);
  out.largest_group_share = points / static_cast<double>(Q.rows());
  out.largest_group_spacings = diagonal / out.spacing;
  return out;
}

}  // namespace heatcvt
