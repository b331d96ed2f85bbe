// Welding coincident boundary vertices (weld.h).
#include "heatcvt/weld.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace heatcvt {

namespace {

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

// Faces at each undirected edge of F.
std::unordered_map<std::uint64_t, int> edge_face_counts(const Eigen::MatrixX3i& F) {
  std::unordered_map<std::uint64_t, int> count;
  count.reserve(static_cast<std::size_t>(3 * F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++count[edge_key(F(f, k), F(f, (k + 1) % 3))];
  return count;
}

// For each vertex, the vertex it merges into: the smallest index among the boundary vertices at
// exactly its position (itself where it is alone or interior).
std::vector<int> coincident_boundary_groups(const TriangleMesh& mesh) {
  const auto count = edge_face_counts(mesh.F);
  std::vector<char> boundary(static_cast<std::size_t>(mesh.V.rows()), 0);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      if (count.at(edge_key(a, b)) == 1) boundary[a] = boundary[b] = 1;
    }
  std::vector<int> order;
  for (int v = 0; v < static_cast<int>(boundary.size()); ++v)
    if (boundary[v]) order.push_back(v);
  const auto at = [&](int v) { return std::array<double, 3>{mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2)}; };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return at(a) < at(b); });
  std::vector<int> into(static_cast<std::size_t>(mesh.V.rows()));
  std::iota(into.begin(), into.end(), 0);
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    while (j < order.size() && !(at(order[i]) < at(order[j]))) ++j;
    const int keep = *std::min_element(order.begin() + static_cast<std::ptrdiff_t>(i), order.begin() + static_cast<std::ptrdiff_t>(j));
    for (std::size_t r = i; r < j; ++r) into[order[r]] = keep;
    i = j;
  }
  return into;
}

}  // namespace

WeldStats weld_coincident_borders(TriangleMesh& mesh) {
  WeldStats stats;
  const std::vector<int> into = coincident_boundary_groups(mesh);
  int merged = 0;
  for (int v = 0; v < static_cast<int>(into.size()); ++v) merged += into[v] != v;
  if (merged == 0) return stats;
  Eigen::MatrixX3i F = mesh.F;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = into[F(f, k)];
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    stats.bad_faces += F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 0) == F(f, 2);
  if (stats.bad_faces == 0)
    for (const auto& [edge, faces] : edge_face_counts(F)) stats.bad_edges += faces > 2;
  if (stats.bad_faces > 0 || stats.bad_edges > 0) {
    stats.refused = merged;
    return stats;
  }
  // Drop the merged vertices; the others keep their order.
  std::vector<int> index(into.size(), -1);
  int next = 0;
  for (int v = 0; v < static_cast<int>(into.size()); ++v)
    if (into[v] == v) index[v] = next++;
  Eigen::MatrixX3d V(next, 3);
  for (int v = 0; v < static_cast<int>(into.size()); ++v)
    if (index[v] >= 0) V.row(index[v]) = mesh.V.row(v);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = index[F(f, k)];
  mesh.V = std::move(V);
  mesh.F = std::move(F);
  stats.welded = merged;
  return stats;
}

}  // namespace heatcvt
