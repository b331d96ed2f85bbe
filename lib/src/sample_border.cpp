// Border points of a sampled surface by the angular gap between neighbours.
#include "heatcvt/sample_border.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"

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

}  // namespace heatcvt
