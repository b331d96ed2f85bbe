// Stray points of a cloud (stray_points.h).
#include "heatcvt/stray_points.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "heatcvt/disjoint_sets.h"
#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

void check_stray_point_options(const StrayPointOptions& o) {
  if (o.neighbours < 2) throw InvalidInputError("stray points: neighbours must be >= 2");
  if (!std::isfinite(o.ratio) || o.ratio < 0 || (o.ratio > 0 && o.ratio <= 1))
    throw InvalidInputError("stray points: the ratio must be 0 (off) or above 1, got " + std::to_string(o.ratio));
  const auto fraction = [](double x) { return std::isfinite(x) && x >= 0 && x <= 1; };
  if (!fraction(o.sparse_group_fraction) || !fraction(o.sparse_density_ratio))
    throw InvalidInputError("stray points: the sparse group fraction and density ratio must lie in [0, 1]");
  if (o.min_group_points < 0) throw InvalidInputError("stray points: min_group_points must be >= 0");
}

namespace {

// Marks the points of the kNN graph's components (over the points not marked yet) that hold
// fewer than min_group_points points, or fewer than sparse_group_fraction of those points and a
// share of them below sparse_density_ratio × their share of the area Σ reach² (stray_points.h).
void mark_groups(const Eigen::MatrixXi& nb, const std::vector<double>& reach, const StrayPointOptions& o,
                        std::vector<char>& stray) {
  const int n = static_cast<int>(stray.size());
  DisjointSets groups(n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < nb.cols() && !stray[i]; ++j)
      if (!stray[nb(i, j)]) groups.unite(i, nb(i, j));
  std::vector<int> count(n, 0);
  std::vector<double> area(n, 0.0);
  int points = 0;
  double total_area = 0;
  for (int i = 0; i < n; ++i) {
    if (stray[i]) continue;
    const int g = groups.find(i);
    ++count[g];
    area[g] += reach[i] * reach[i];
    ++points;
    total_area += reach[i] * reach[i];
  }
  if (points == 0 || !(total_area > 0)) return;
  // The largest component is the rest the others are far from: never stray itself.
  const int largest = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  std::vector<char> sparse(n, 0);
  for (int g = 0; g < n; ++g) {
    if (g == largest) continue;
    const double point_share = static_cast<double>(count[g]) / points;
    sparse[g] = count[g] > 0 && (count[g] < o.min_group_points || (point_share < o.sparse_group_fraction &&
                                                                   point_share < o.sparse_density_ratio * area[g] / total_area));
  }
  for (int i = 0; i < n; ++i)
    if (!stray[i] && sparse[groups.find(i)]) stray[i] = 1;
}

}  // namespace

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
      stray[i] = options.ratio > 0 && reach[i] > options.ratio * around[k / 2];
    }
  }
  if (options.sparse_group_fraction > 0 || options.min_group_points > 0) mark_groups(nb, reach, options, stray);
  return stray;
}

}  // namespace heatcvt
