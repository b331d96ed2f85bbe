// Noise of a point cloud at the scale of the site spacing (noise_estimate.h).
#include "heatcvt/noise_estimate.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/grid_cell.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

// RMS residual of the least-squares quadratic height field over the PCA plane of the rows `nb`
// of P (coordinates divided by `scale` for the conditioning of the fit), in input units; −1 when
// the quadratic is ill-posed (points on a line or a curve).
double quadratic_residual(const Eigen::MatrixX3d& P, const std::vector<int>& nb, double scale) {
  const auto m = static_cast<Eigen::Index>(nb.size());
  Eigen::Vector3d mu = Eigen::Vector3d::Zero();
  for (const int j : nb) mu += P.row(j).transpose();
  mu /= static_cast<double>(m);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const int j : nb) {
    const Eigen::Vector3d d = (P.row(j).transpose() - mu) / scale;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d n = eig.eigenvectors().col(0), t1 = eig.eigenvectors().col(2), t2 = eig.eigenvectors().col(1);
  Eigen::MatrixXd A(m, 6);
  Eigen::VectorXd h(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Vector3d d = (P.row(nb[static_cast<std::size_t>(k)]).transpose() - mu) / scale;
    const double u = d.dot(t1), v = d.dot(t2);
    A.row(k) << 1.0, u, v, u * u, u * v, v * v;
    h(k) = d.dot(n);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < 6) return -1;
  const Eigen::VectorXd c = qr.solve(h);
  return scale * std::sqrt((A * c - h).squaredNorm() / static_cast<double>(m));
}

// The rows of P by the grid cell (of side a little over `radius`) holding them, for the cells
// within one cell of a query row, ascending in each cell: every point within `radius` of a query
// is in the 27 cells around the query's own. A sample of millions of points is thus indexed only
// where the queries look, without a search tree.
using CellRows = std::unordered_map<GridCell, std::vector<int>, GridCellHash>;

CellRows rows_near_queries(const Eigen::MatrixX3d& P, const std::vector<Eigen::Index>& query_rows, double cell,
                           int threads) {
  CellRows near;
  for (const Eigen::Index row : query_rows) {
    const GridCell c = grid_cell(P.row(row).transpose(), cell);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) near.emplace(GridCell{c[0] + dx, c[1] + dy, c[2] + dz}, std::vector<int>{});
  }
  const Eigen::Index n = P.rows();
  std::vector<std::vector<int>*> slot(static_cast<std::size_t>(n), nullptr);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(threads))
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto it = near.find(grid_cell(P.row(i).transpose(), cell));
    if (it != near.end()) slot[static_cast<std::size_t>(i)] = &it->second;
  }
  for (Eigen::Index i = 0; i < n; ++i)
    if (slot[static_cast<std::size_t>(i)]) slot[static_cast<std::size_t>(i)]->push_back(static_cast<int>(i));
  return near;
}

// The rows of P within `radius` of its row q (a relative 1e-6 of slack against rounding),
// ascending; `near` from rows_near_queries() with q among its query rows (so that the 27 cells
// around q are in it).
std::vector<int> rows_within(const Eigen::MatrixX3d& P, const CellRows& near, double cell, Eigen::Index q,
                             double radius) {
  const Eigen::Vector3d x = P.row(q).transpose();
  const GridCell c = grid_cell(x, cell);
  const double r2 = radius * radius * (1 + 2e-6);
  std::vector<int> out;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = near.find(GridCell{c[0] + dx, c[1] + dy, c[2] + dz});
        for (const int j : it->second)
          if ((P.row(j).transpose() - x).squaredNorm() < r2) out.push_back(j);
      }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

NoiseEstimate estimate_noise(const Eigen::MatrixX3d& P, double spacing, const NoiseEstimateOptions& options) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw InvalidInputError("estimate_noise: spacing must be finite and > 0, got " + std::to_string(spacing));
  if (options.queries < 1 || !(options.radius_spacings > 0) || options.min_neighbors < 6 || options.max_fit_points < 0 ||
      (options.max_fit_points > 0 && options.max_fit_points < options.min_neighbors))
    throw InvalidInputError("estimate_noise: queries must be >= 1, radius_spacings > 0, min_neighbors >= 6 and "
                            "max_fit_points 0 or at least min_neighbors");
  NoiseEstimate out;
  const Eigen::Index n = P.rows();
  if (n < options.min_neighbors) return out;
  const int queries = static_cast<int>(std::min<Eigen::Index>(options.queries, n));
  const double radius = options.radius_spacings * spacing;
  std::vector<Eigen::Index> query_rows(static_cast<std::size_t>(queries));
  for (int q = 0; q < queries; ++q) query_rows[static_cast<std::size_t>(q)] = static_cast<Eigen::Index>(q) * n / queries;
  const double cell = radius * (1 + 1e-5);
  const CellRows near = rows_near_queries(P, query_rows, cell, options.threads);
  std::vector<double> residual(static_cast<std::size_t>(queries), -1.0);
#pragma omp parallel for schedule(dynamic, 16) num_threads(resolve_threads(options.threads))
  for (int q = 0; q < queries; ++q) {
    std::vector<int> nb = rows_within(P, near, cell, query_rows[static_cast<std::size_t>(q)], radius);
    const std::size_t found = nb.size(), keep = static_cast<std::size_t>(options.max_fit_points);
    if (keep > 0 && found > keep) {
      for (std::size_t k = 0; k < keep; ++k) nb[k] = nb[k * found / keep];
      nb.resize(keep);
    }
    if (static_cast<int>(nb.size()) >= options.min_neighbors)
      residual[static_cast<std::size_t>(q)] = quadratic_residual(P, nb, radius);
  }
  residual.erase(std::remove_if(residual.begin(), residual.end(), [](double r) { return r < 0; }), residual.end());
  if (residual.empty()) return out;
  const auto mid = residual.begin() + static_cast<std::ptrdiff_t>(residual.size() / 2);
  std::nth_element(residual.begin(), mid, residual.end());
  out.sigma = *mid;
  out.queries_used = static_cast<int>(residual.size());
  return out;
}

int noise_limited_sites(int sites, double spacing, double sigma, double max_noise_spacings, double max_reduction) {
  if (!(sigma > max_noise_spacings * spacing)) return sites;
  const double ratio = max_noise_spacings * spacing / sigma;
  const double limited = std::max(static_cast<double>(sites) * ratio * ratio, static_cast<double>(sites) / max_reduction);
  return std::min(sites, std::max(4, static_cast<int>(std::lround(limited))));
}

}  // namespace heatcvt
