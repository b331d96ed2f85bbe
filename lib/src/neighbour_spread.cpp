#include "heatcvt/neighbour_spread.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

constexpr int kFirstSize = 8;  // an isotropic sampling spans the surface by here

void check(const NeighbourSpreadOptions& o) {
  if (!(o.min_spread > 0 && o.min_spread <= 1) || !(o.quantile >= 0 && o.quantile <= 1) || !(o.factor >= 0) ||
      !std::isfinite(o.factor) || o.samples < 1 || o.max_neighbors < kFirstSize)
    throw InvalidInputError("neighbour spread: min_spread must be in (0, 1], quantile in [0, 1], factor >= 0, samples >= 1 and "
                            "max_neighbors >= " + std::to_string(kFirstSize));
}

// The smallest size m >= kFirstSize at which the point x and its first m − 1 neighbours (rows
// of `nearest`, nearest first) span the surface; max_neighbors + 1 when none does. The
// covariance is accumulated one neighbour at a time (coordinates relative to x).
int spanning_size(const Eigen::MatrixX3d& P, const Eigen::Vector3d& x, const Eigen::Ref<const Eigen::RowVectorXi>& nearest,
                  const NeighbourSpreadOptions& o) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  for (Eigen::Index q = 0; q < nearest.size(); ++q) {
    const Eigen::Vector3d d = P.row(nearest[q]).transpose() - x;
    sum += d;
    outer += d * d.transpose();
    const double m = static_cast<double>(q + 2);  // the neighbours so far and x itself
    if (q + 2 < kFirstSize) continue;
    const Eigen::Matrix3d cov = outer / m - (sum / m) * (sum / m).transpose();
    eigen.computeDirect(cov, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d& ev = eigen.eigenvalues();  // ascending
    if (ev[2] > 0 && ev[1] >= o.min_spread * ev[2]) return static_cast<int>(q + 2);
  }
  return o.max_neighbors + 1;
}

}  // namespace

int spanning_neighbours(const Eigen::MatrixX3d& P, const NeighbourSpreadOptions& options, int threads) {
  check(options);
  const Eigen::Index n = P.rows();
  const int k = static_cast<int>(std::min<Eigen::Index>(options.max_neighbors, n));
  if (k < kFirstSize) return options.max_neighbors + 1;
  const Eigen::Index stride = std::max<Eigen::Index>(1, n / options.samples);
  const Eigen::Index m = (n + stride - 1) / stride;
  Eigen::MatrixX3d Q(m, 3);
  for (Eigen::Index i = 0; i < m; ++i) Q.row(i) = P.row(i * stride);
  const Eigen::MatrixXi nearest = nearest_neighbors_of(P, Q, k, threads);  // includes the point itself
  std::vector<int> size(m);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (Eigen::Index i = 0; i < m; ++i)
    size[i] = spanning_size(P, Q.row(i).transpose(), nearest.row(i).tail(k - 1), options);
  const size_t at = std::min<size_t>(size.size() - 1, static_cast<size_t>(options.quantile * static_cast<double>(size.size())));
  std::nth_element(size.begin(), size.begin() + static_cast<std::ptrdiff_t>(at), size.end());
  return size[at];
}

int neighbours_for_spread(const Eigen::MatrixX3d& P, int k, const NeighbourSpreadOptions& options, int threads) {
  check(options);
  if (options.factor == 0 || P.rows() <= kFirstSize) return k;
  const int spanning = spanning_neighbours(P, options, threads);
  if (spanning <= kFirstSize) return k;  // spans at the first size looked at: isotropic
  const double wanted = std::ceil(options.factor * spanning);
  const int spread = static_cast<int>(std::min<double>(options.max_neighbors, wanted));
  return static_cast<int>(std::min<Eigen::Index>(std::max(k, spread), P.rows() - 1));
}

}  // namespace heatcvt
