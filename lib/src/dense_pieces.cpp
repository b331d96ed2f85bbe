// Dense pieces of a cloud: parts too small by area for the sites their points support. See
// dense_pieces.h.
#include "heatcvt/dense_pieces.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <string>
#include <unordered_map>

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
  if (!(o.split_below > 0 && o.split_below <= 1)) bad("split_below must be in (0, 1]");
  if (!(o.min_density_ratio >= 0) || !std::isfinite(o.min_density_ratio)) bad("min_density_ratio must be finite and >= 0");
}

namespace {

// One piece: its area, the cloud points its points stand for and its first point (the order of
// the pieces).
struct Component {
  double area = 0;
  long points = 0;
  int first = -1;
};

}  // namespace

int dense_piece_sites(int sites, double min_piece_vertex_fraction, const DensePieceOptions& options) {
  return std::max(options.min_sites, static_cast<int>(std::ceil(2 * min_piece_vertex_fraction * sites)));
}

bool dense_piece_possible(const std::vector<int>& weight, int sites, double min_piece_vertex_fraction,
                          const DensePieceOptions& options) {
  if (!options.enabled() || weight.empty() || sites < 1) return false;
  const double share =
      options.split_below * dense_piece_sites(sites, min_piece_vertex_fraction, options) / static_cast<double>(sites);
  const std::size_t most = std::min(weight.size(), static_cast<std::size_t>(std::ceil(share * weight.size())));
  std::vector<int> w = weight;
  std::nth_element(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(most) - 1, w.end(), std::greater<int>());
  const double heaviest = std::accumulate(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(most), 0.0);
  const double total = std::accumulate(w.begin(), w.end(), 0.0);
  return heaviest >= options.min_point_fraction * total;
}

DensePieces dense_pieces_of_components(const std::vector<int>& component, const std::vector<double>& area,
                                       const std::vector<int>& weight, int sites, double min_piece_vertex_fraction,
                                       const DensePieceOptions& options) {
  check_dense_piece_options(options);
  const int n = static_cast<int>(component.size());
  if (static_cast<int>(area.size()) != n || static_cast<int>(weight.size()) != n)
    throw InvalidInputError("dense pieces: one label, area and weight per point are needed");
  DensePieces out;
  out.piece.assign(n, -1);
  if (!options.enabled() || sites < 1) return out;
  int labels = 0;
  for (int c : component) labels = std::max(labels, c + 1);
  std::vector<Component> comp(labels);
  double total_area = 0;
  long total_points = 0;
  for (int i = 0; i < n; ++i) {
    total_points += weight[i];
    total_area += area[i];
    if (component[i] < 0) continue;
    Component& c = comp[component[i]];
    c.area += area[i];
    c.points += weight[i];
    if (c.first < 0) c.first = i;
  }
  if (!(total_area > 0) || total_points <= 0) return out;

  // The rest: the piece of the largest area. Candidates: the others under their floor with the
  // points for it, the most points first (ties: the first point).
  int rest = -1;
  for (int r = 0; r < labels; ++r)
    if (comp[r].first >= 0 && (rest < 0 || comp[r].area > comp[rest].area)) rest = r;
  const int floor_sites = dense_piece_sites(sites, min_piece_vertex_fraction, options);
  std::vector<int> candidates;
  for (int r = 0; r < labels; ++r) {
    const Component& c = comp[r];
    if (c.first < 0 || r == rest) continue;
    const double area_share = c.area / total_area, point_share = static_cast<double>(c.points) / total_points;
    if (sites * area_share < options.split_below * floor_sites && point_share >= options.min_point_fraction &&
        point_share >= options.min_density_ratio * area_share && c.points >= options.min_points_per_site * floor_sites)
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
  std::vector<int> index_of(labels, -1);
  for (size_t k = 0; k < chosen.size(); ++k) index_of[chosen[k]] = static_cast<int>(k);
  for (int i = 0; i < n; ++i)
    if (component[i] >= 0) out.piece[i] = index_of[component[i]];
  out.sites.assign(chosen.size(), floor_sites);
  return out;
}

DensePieces dense_pieces(const Eigen::MatrixX3d& PC, const Eigen::MatrixX3i& T, const std::vector<int>& weight,
                         int sites, double min_piece_vertex_fraction, const DensePieceOptions& options) {
  check_dense_piece_options(options);
  const int n = static_cast<int>(PC.rows());
  if (static_cast<int>(weight.size()) != n) throw InvalidInputError("dense pieces: one weight per point is needed");
  if (T.size() > 0 && (T.minCoeff() < 0 || T.maxCoeff() >= n))
    throw InvalidInputError("dense pieces: a triangle index is out of range");
  // Components of the triangles (points on none: −1) and the lumped area of each point.
  DisjointSets sets(n);
  for (Eigen::Index t = 0; t < T.rows(); ++t) sets.unite(T(t, 0), T(t, 1)), sets.unite(T(t, 0), T(t, 2));
  std::vector<double> area(n, 0.0);
  std::vector<char> on_triangle(n, 0);
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const Eigen::Vector3d a = PC.row(T(t, 0)), b = PC.row(T(t, 1)), c = PC.row(T(t, 2));
    const double third = (b - a).cross(c - a).norm() / 6;
    for (int k = 0; k < 3; ++k) area[T(t, k)] += third, on_triangle[T(t, k)] = 1;
  }
  std::vector<int> label(n, -1), component(n, -1);
  int labels = 0;
  for (int i = 0; i < n; ++i) {
    if (!on_triangle[i]) continue;
    int& l = label[sets.find(i)];
    if (l < 0) l = labels++;
    component[i] = l;
  }
  return dense_pieces_of_components(component, area, weight, sites, min_piece_vertex_fraction, options);
}

std::vector<int> voxel_components(const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3>& cells) {
  const int n = static_cast<int>(cells.rows());
  const auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL) ^ (static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4FULL) ^
           (static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ULL);
  };
  std::unordered_multimap<std::uint64_t, int> index;
  index.reserve(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) index.emplace(key(cells(i, 0), cells(i, 1), cells(i, 2)), i);
  const auto find = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto range = index.equal_range(key(x, y, z));
    for (auto it = range.first; it != range.second; ++it)
      if (cells(it->second, 0) == x && cells(it->second, 1) == y && cells(it->second, 2) == z) return it->second;
    return -1;
  };
  DisjointSets sets(n);
  for (int i = 0; i < n; ++i)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx < 0 || (dx == 0 && (dy < 0 || (dy == 0 && dz <= 0)))) continue;  // each pair once
          const int j = find(cells(i, 0) + dx, cells(i, 1) + dy, cells(i, 2) + dz);
          if (j >= 0) sets.unite(i, j);
        }
  std::vector<int> label(n, -1), out(n);
  int labels = 0;
  for (int i = 0; i < n; ++i) {
    int& l = label[sets.find(i)];
    if (l < 0) l = labels++;
    out[i] = l;
  }
  return out;
}

}  // namespace heatcvt
