// Dense pieces of a cloud: parts too small by area for the sites their points support. See
// dense_pieces.h.
#include "heatcvt/dense_pieces.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "heatcvt/disjoint_sets.h"
#include "heatcvt/errors.h"

namespace heatcvt {

void check_dense_piece_options(const DensePieceOptions& o) {
  auto bad = [](const std::string& m) { throw InvalidInputError("dense pieces: " + m); };
  if (!(o.min_point_fraction >= 0 && o.min_point_fraction <= 1)) bad("min_point_fraction must be in [0, 1]");
  if (!(o.max_site_fraction >= 0 && o.max_site_fraction <= 1)) bad("max_site_fraction must be in [0, 1]");
  if (o.min_sites < 4) bad("min_sites must be >= 4");
  if (!(o.min_points_per_site >= 0) || !std::isfinite(o.min_points_per_site))
    bad("min_points_per_site must be finite and >= 0");
}

namespace {

// One connected component of the triangles: its area, the cloud points its points stand for and
// its first point (the order of the pieces).
struct Component {
  double area = 0;
  long points = 0;
  int first = -1;
};

}  // namespace

DensePieces dense_pieces(const Eigen::MatrixX3d& PC, const Eigen::MatrixX3i& T, const std::vector<int>& weight,
                         int sites, double min_piece_vertex_fraction, const DensePieceOptions& options) {
  check_dense_piece_options(options);
  const int n = static_cast<int>(PC.rows());
  if (static_cast<int>(weight.size()) != n) throw InvalidInputError("dense pieces: one weight per point is needed");
  if (T.size() > 0 && (T.minCoeff() < 0 || T.maxCoeff() >= n))
    throw InvalidInputError("dense pieces: a triangle index is out of range");
  DensePieces out;
  out.piece.assign(n, -1);
  if (!options.enabled() || T.rows() == 0 || sites < 1) return out;

  DisjointSets sets(n);
  for (Eigen::Index t = 0; t < T.rows(); ++t) sets.unite(T(t, 0), T(t, 1)), sets.unite(T(t, 0), T(t, 2));
  std::vector<int> root(n);
  for (int i = 0; i < n; ++i) root[i] = sets.find(i);
  std::vector<char> on_triangle(n, 0);
  for (Eigen::Index k = 0; k < T.size(); ++k) on_triangle[T.data()[k]] = 1;
  std::vector<Component> comp(n);
  double total_area = 0;
  long total_points = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const Eigen::Vector3d a = PC.row(T(t, 0)), b = PC.row(T(t, 1)), c = PC.row(T(t, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    comp[root[T(t, 0)]].area += area;
    total_area += area;
  }
  for (int i = 0; i < n; ++i) {
    total_points += weight[i];
    if (!on_triangle[i]) continue;
    Component& c = comp[root[i]];
    c.points += weight[i];
    if (c.first < 0) c.first = i;
  }
  if (!(total_area > 0)) return out;

  // The rest: the component of the largest area. Candidates: the others under their floor with
  // the points for it, the most points first (ties: the first point).
  int rest = -1;
  for (int r = 0; r < n; ++r)
    if (comp[r].first >= 0 && (rest < 0 || comp[r].area > comp[rest].area)) rest = r;
  const int floor_sites =
      std::max(options.min_sites, static_cast<int>(std::ceil(2 * min_piece_vertex_fraction * sites)));
  std::vector<int> candidates;
  for (int r = 0; r < n; ++r) {
    const Component& c = comp[r];
    if (c.first < 0 || r == rest) continue;
    const double share = sites * c.area / total_area;
    if (share < floor_sites && c.points >= options.min_point_fraction * static_cast<double>(total_points) &&
        c.points >= options.min_points_per_site * floor_sites)
      candidates.push_back(r);
  }
  std::sort(candidates.begin(), candidates.end(), [&](int a, int b) {
    return comp[a].points != comp[b].points ? comp[a].points > comp[b].points : comp[a].first < comp[b].first;
  });
  const int budget = static_cast<int>(std::floor(options.max_site_fraction * sites));
  std::vector<int> chosen;
  for (int r : candidates)
    if (static_cast<int>(chosen.size() + 1) * floor_sites <= budget) chosen.push_back(r);
  std::sort(chosen.begin(), chosen.end(), [&](int a, int b) { return comp[a].first < comp[b].first; });
  std::vector<int> index_of(n, -1);
  for (size_t k = 0; k < chosen.size(); ++k) index_of[chosen[k]] = static_cast<int>(k);
  for (int i = 0; i < n; ++i)
    if (on_triangle[i]) out.piece[i] = index_of[root[i]];
  out.sites.assign(chosen.size(), floor_sites);
  return out;
}

}  // namespace heatcvt
