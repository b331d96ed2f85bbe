// Stray points of a cloud (stray_points.h).
#include "heatcvt/stray_points.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

void check_stray_point_options(const StrayPointOptions& o) {
  if (o.neighbours < 2) throw InvalidInputError("stray points: neighbours must be >= 2");
  if (!std::isfinite(o.ratio) || o.ratio < 0 || (o.ratio > 0 && o.ratio <= 1))
    throw InvalidInputError("stray points: the ratio must be 0 (off) or above 1, got " + std::to_string(o.ratio));
}

std::vector<char> stray_point_mask(const Eigen::MatrixX3d& P, const StrayPointOptions& options, int threads) {
  check_stray_point_options(options);
  const int n = static_cast<int>(P.rows()), k = options.neighbours;
  std::vector<char> stray(n, 0);
  if (!options.enabled() || n <= k) return stray;
  const Eigen::MatrixXi nb = k_nearest_neighbors(P, k, threads);
  std::vector<double> reach(n);  // distance to the k-th neighbour
  const int nt = resolve_threads(threads);
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int i = 0; i < n; ++i) reach[i] = (P.row(nb(i, k - 1)) - P.row(i)).norm();
#pragma omp parallel num_threads(nt)
  {
    std::vector<double> around(k);
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < k; ++j) around[j] = reach[nb(i, j)];
      std::nth_element(around.begin(), around.begin() + k / 2, around.end());
      stray[i] = reach[i] > options.ratio * around[k / 2];
    }
  }
  return stray;
}

}  // namespace heatcvt
