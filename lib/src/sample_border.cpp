// Border points of a sampled surface by the angular gap between neighbours.
#include "heatcvt/sample_border.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "heatcvt/closest_point.h"
#include "heatcvt/disjoint_sets.h"
#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"
#include "heatcvt/point_index.h"

namespace heatcvt {
namespace {

// The widest angle between consecutive directions to the neighbours of point i in its tangent plane.
double widest_gap(const Eigen::MatrixX3d& P, const Eigen::Vector3d& n, const Eigen::MatrixXi& knn, int i, int k,
                  std::vector<double>& angles) {
  const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
  angles.clear();
  for (int q = 0; q < k; ++q) {
    const Eigen::Vector3d d = P.row(knn(i, q)).transpose() - P.row(i).transpose();
    const double x = d.dot(u), y = d.dot(w);
    if (x != 0 || y != 0) angles.push_back(std::atan2(y, x));
  }
  if (angles.size() < 2) return 2 * M_PI;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2 * M_PI - angles.back();
  for (size_t a = 1; a < angles.size(); ++a) gap = std::max(gap, angles[a] - angles[a - 1]);
  return gap;
}

// The q-quantile of d (sorted in place) and the fraction of it at or below 1.
std::pair<double, double> quantile_and_within_one(std::vector<double>& d, double q) {
  if (d.empty()) return {0.0, 0.0};
  std::sort(d.begin(), d.end());
  const auto at = static_cast<std::size_t>(std::floor(q * static_cast<double>(d.size() - 1)));
  const double within = static_cast<double>(std::upper_bound(d.begin(), d.end(), 1.0) - d.begin());
  return {d[at], within / static_cast<double>(d.size())};
}

}  // namespace

std::vector<char> sample_border_points(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixXi& knn,
                                       const SampleBorderOptions& options) {
  if (N.rows() != P.rows() || knn.rows() != P.rows())
    throw InvalidInputError("sample_border_points: points, normals and neighbour table differ in length");
  if (knn.cols() < 3) throw InvalidInputError("sample_border_points: need at least 3 neighbours per point");
  if (!(options.max_gap_deg > 0 && options.max_gap_deg < 360) || options.neighbors < 3)
    throw InvalidInputError("sample_border_points: max_gap_deg must be in (0, 360) and neighbors at least 3");
  const int n = static_cast<int>(P.rows());
  const int k = std::min(options.neighbors, static_cast<int>(knn.cols()));
  const double max_gap = options.max_gap_deg * M_PI / 180.0;
  std::vector<char> border(n, 0);
#pragma omp parallel num_threads(resolve_threads(options.threads))
  {
    std::vector<double> angles;
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d nrm = N.row(i).transpose();
      border[i] = nrm.norm() > 0 && widest_gap(P, nrm.normalized(), knn, i, k, angles) > max_gap;
    }
  }
  return border;
}

std::vector<char> border_chains(const std::vector<char>& on_border, const Eigen::MatrixXi& knn, int neighbors,
                                int min_points) {
  const int n = static_cast<int>(on_border.size());
  if (knn.rows() != n) throw InvalidInputError("border_chains: border flags and neighbour table differ in length");
  const int k = std::clamp(neighbors, 0, static_cast<int>(knn.cols()));
  DisjointSets chains(n);
  for (int i = 0; i < n; ++i)
    if (on_border[i])
      for (int q = 0; q < k; ++q)
        if (on_border[knn(i, q)]) chains.unite(i, knn(i, q));
  std::vector<int> size(n, 0);
  for (int i = 0; i < n; ++i)
    if (on_border[i]) ++size[chains.find(i)];
  std::vector<char> kept(n, 0);
  for (int i = 0; i < n; ++i) kept[i] = on_border[i] && size[chains.find(i)] >= min_points;
  return kept;
}

BorderFit border_fit(const Eigen::MatrixX3d& border, const TriangleMesh& mesh, double length, double quantile) {
  if (!(length > 0) || !(quantile >= 0 && quantile <= 1))
    throw InvalidInputError("border_fit: the length must be positive and the quantile in [0, 1]");
  BorderFit fit;
  if (border.rows() == 0 || mesh.F.rows() == 0) return fit;
  const std::vector<SurfacePoint> closest = closest_surface_points(mesh.V, mesh.F, border);
  std::vector<double> d(static_cast<std::size_t>(border.rows()));
  for (Eigen::Index r = 0; r < border.rows(); ++r)
    d[static_cast<std::size_t>(r)] =
        (position(mesh.V, mesh.F, closest[static_cast<std::size_t>(r)]) - border.row(r).transpose()).norm() / length;
  fit.edge_points = static_cast<int>(border.rows());
  std::tie(fit.edge_distance, fit.edge_covered) = quantile_and_within_one(d, quantile);
  std::vector<char> on_mesh_border(static_cast<std::size_t>(mesh.V.rows()), 0);
  for (const auto& [a, b] : boundary_edges(mesh.F)) on_mesh_border[a] = on_mesh_border[b] = 1;
  const PointIndex index(border);
  d.clear();
  for (int v = 0; v < static_cast<int>(mesh.V.rows()); ++v) {
    if (!on_mesh_border[v]) continue;
    double dist = 0;
    index.nearest(mesh.V.row(v).transpose(), dist);
    d.push_back(dist / length);
  }
  fit.mesh_border_vertices = static_cast<int>(d.size());
  std::tie(fit.mesh_border_distance, fit.mesh_border_on_edge) = quantile_and_within_one(d, quantile);
  return fit;
}

BorderFit border_fit(const Eigen::MatrixX3d& P, const std::vector<char>& on_border, const TriangleMesh& mesh,
                     double length, double quantile) {
  if (on_border.size() != static_cast<std::size_t>(P.rows()))
    throw InvalidInputError("border_fit: the border flags and the points differ in length");
  std::vector<int> rows;
  for (int i = 0; i < static_cast<int>(on_border.size()); ++i)
    if (on_border[i]) rows.push_back(i);
  return border_fit(Eigen::MatrixX3d(P(rows, Eigen::all)), mesh, length, quantile);
}

}  // namespace heatcvt
