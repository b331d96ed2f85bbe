// Hole filling of the extracted surface.
#include "heatcvt/mesher/hole_filling.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

#include "heatcvt/closest_point.h"

namespace heatcvt {
namespace {

// The loop's centre is away from every triangle (> clearance·h) but near the sampled surface.
bool is_sampled_hole(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                     const HoleFillingOptions& o) {
  const Eigen::MatrixX3d& S = mesh.V;
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double h = 0;
  for (size_t i = 0; i < loop.size(); ++i) {
    g += S.row(loop[i]).transpose();
    h += (S.row(loop[i]) - S.row(loop[(i + 1) % loop.size()])).norm();
  }
  g /= static_cast<double>(loop.size());
  h /= static_cast<double>(loop.size());
  if (!(surface.distance_to_samples(g) < o.sample_gap * h)) return false;
  for (const MeshFace& f : mesh.faces()) {
    const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
    const Eigen::Vector3d bc = closest_point_barycentric(g, a, b, c);
    if ((bc[0] * a + bc[1] * b + bc[2] * c - g).norm() < o.clearance * h) return false;
  }
  return true;
}

// Beyond enough of the loop's edges, one edge length outward, the surface is sampled.
bool is_surrounded_hole(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                        const HoleFillingOptions& o) {
  const Eigen::MatrixX3d& S = mesh.V;
  int sampled = 0;
  const int L = static_cast<int>(loop.size());
  for (int i = 0; i < L; ++i) {
    const int a = loop[i], b = loop[(i + 1) % L];
    const int fi = mesh.half_edge_face(a, b);
    if (fi < 0) continue;
    const MeshFace& f = mesh.face(fi);
    const Eigen::Vector3d p0 = S.row(f[0]), p1 = S.row(f[1]), p2 = S.row(f[2]);
    const Eigen::Vector3d fn = (p1 - p0).cross(p2 - p0);
    const Eigen::Vector3d e = S.row(b) - S.row(a);
    if (!(fn.norm() > 0) || !(e.norm() > 0)) continue;
    const Eigen::Vector3d out = e.cross(fn).normalized();
    const double len = e.norm();
    const Eigen::Vector3d probe = 0.5 * (S.row(a) + S.row(b)).transpose() + len * out;
    if (surface.distance_to_samples(probe) < o.sample_gap * len) ++sampled;
  }
  return sampled >= o.surrounded_fraction * L;
}

// A 3-loop that is the back of an existing face (its reversed half-edges all on one face).
bool is_back_of_face(const WorkingMesh& mesh, const std::vector<int>& loop) {
  const int f0 = mesh.half_edge_face(loop[1], loop[0]), f1 = mesh.half_edge_face(loop[2], loop[1]),
            f2 = mesh.half_edge_face(loop[0], loop[2]);
  return f0 >= 0 && f1 >= 0 && f2 >= 0 && f0 == f1 && f1 == f2;
}

// One pass: every simple boundary loop that qualifies is triangulated. Returns the loops filled.
int fill_pass(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& o) {
  const int max_loop = o.surrounded_hole_factor * o.max_hole_edges;
  std::unordered_map<int, std::vector<int>> next;  // boundary half-edge a->b (face side) by start vertex
  std::vector<std::pair<int, int>> bedges;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (!mesh.has_half_edge(b, a)) {
        next[a].push_back(b);
        bedges.push_back({a, b});
      }
    }
  if (bedges.empty()) return 0;
  std::sort(bedges.begin(), bedges.end());
  std::unordered_map<long long, char> used;
  std::vector<MeshFace> added;
  int filled = 0;
  for (const auto& [a0, b0] : bedges) {
    if (used.count(WorkingMesh::edge_key(a0, b0))) continue;
    std::vector<int> loop = {a0};
    int cur = b0;
    bool simple = true;
    used[WorkingMesh::edge_key(a0, b0)] = 1;
    while (cur != a0 && static_cast<int>(loop.size()) <= max_loop + 1) {
      auto it = next.find(cur);
      if (it == next.end() || it->second.size() != 1) {
        simple = false;
        break;
      }
      loop.push_back(cur);
      used[WorkingMesh::edge_key(cur, it->second[0])] = 1;
      cur = it->second[0];
    }
    const int L = static_cast<int>(loop.size());
    if (!simple || cur != a0 || L > max_loop || L < 3) continue;
    if (L > o.max_hole_edges && !((L <= o.sampled_hole_factor * o.max_hole_edges && is_sampled_hole(mesh, surface, loop, o)) ||
                                  is_surrounded_hole(mesh, surface, loop, o)))
      continue;
    std::vector<int> sorted = loop;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
    if (L == 3 && is_back_of_face(mesh, loop)) continue;  // would duplicate that face
    std::vector<MeshFace> tris;
    if (!triangulate_loop(mesh, loop, tris)) continue;
    added.insert(added.end(), tris.begin(), tris.end());
    ++filled;
  }
  for (const MeshFace& t : added) mesh.add_face(t);
  return filled;
}

}  // namespace

bool triangulate_loop(const WorkingMesh& mesh, const std::vector<int>& loop, std::vector<MeshFace>& out) {
  const int L = static_cast<int>(loop.size());
  if (L < 3) return false;
  auto is_edge = [&](int i, int j) { return mesh.edge_face_count(loop[i], loop[j]) > 0; };
  const double NEG = -1.0;
  std::vector<double> best(L * L, NEG);
  std::vector<int> split(L * L, -1);
  for (int i = 0; i + 1 < L; ++i) best[i * L + i + 1] = M_PI;  // a polygon edge: neutral
  for (int len = 2; len < L; ++len)
    for (int i = 0; i + len < L; ++i) {
      const int j = i + len;
      // The chord (i, j) must not already be an edge of the mesh (except the closing edge 0..L-1).
      if (!(i == 0 && j == L - 1) && is_edge(i, j)) continue;
      for (int k = i + 1; k < j; ++k) {
        const double a = best[i * L + k], b = best[k * L + j];
        if (a < 0 || b < 0) continue;
        const double q = std::min({a, b, face_min_angle(mesh, {loop[i], loop[k], loop[j]})});
        if (q > best[i * L + j]) {
          best[i * L + j] = q;
          split[i * L + j] = k;
        }
      }
    }
  if (best[0 * L + L - 1] < 0) return false;
  std::vector<std::pair<int, int>> stack = {{0, L - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[i * L + j];
    out.push_back({loop[i], loop[j], loop[k]});  // reversed w.r.t. loop order i<k<j
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

int fill_holes(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& options,
               const ManifoldOptions& manifold, int& removed) {
  int filled = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const int before = mesh.num_faces();
    const int pass_filled = fill_pass(mesh, surface, options);
    if (mesh.num_faces() == before) break;
    filled += pass_filled;
    removed += make_vertices_manifold(mesh, manifold);
  }
  return filled;
}

}  // namespace heatcvt
