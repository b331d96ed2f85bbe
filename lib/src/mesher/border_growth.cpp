// Growing the borders of the extracted surface over nearby unused sites.
#include "heatcvt/mesher/border_growth.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

#include "heatcvt/mesher/dual_candidates.h"
#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/normals.h"

namespace heatcvt {
namespace {

// The triangle (b, a, s) over the border half-edge a→b, if it passes the shape and normal tests.
bool acceptable(const WorkingMesh& mesh, const MeshFace& t, const BorderGrowthOptions& o) {
  const Eigen::Vector3d p = mesh.V.row(t[0]), q = mesh.V.row(t[1]), r = mesh.V.row(t[2]);
  const Eigen::Vector3d n = (q - p).cross(r - p);
  if (!(n.norm() > 0)) return false;
  for (int k = 0; k < 3; ++k)
    if (!(n.normalized().dot(mesh.N.row(t[k]).transpose()) > o.min_normal_dot)) return false;
  return face_min_angle(mesh, t) >= o.min_angle_deg * M_PI / 180.0;
}

// One front pass: the best triangle of every border half-edge, most regular first.
std::vector<DualCandidate> front(const WorkingMesh& mesh, const Eigen::MatrixXi& knn, const BorderGrowthOptions& o) {
  std::vector<DualCandidate> out;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (mesh.has_half_edge(b, a)) continue;
      DualCandidate best;
      best.quality = -1;
      for (int end : {a, b})
        for (Eigen::Index q = 0; q < knn.cols(); ++q) {
          const int s = knn(end, q);
          if (s == a || s == b) continue;
          const MeshFace t = {b, a, s};
          if (!acceptable(mesh, t, o)) continue;
          const double quality = face_min_angle(mesh, t);
          if (quality > best.quality) best.f = t, best.quality = quality;
        }
      if (best.quality > 0) out.push_back(best);
    }
  std::stable_sort(out.begin(), out.end(), [](const DualCandidate& x, const DualCandidate& y) {
    if (x.quality != y.quality) return x.quality > y.quality;
    return x.f < y.f;
  });
  return out;
}

}  // namespace

int grow_borders(WorkingMesh& mesh, const BorderGrowthOptions& options) {
  const int k = std::min(options.neighbors, mesh.num_vertices() - 1);
  if (!options.enabled || mesh.empty() || k < 2) return 0;
  long border = 0;
  for (const MeshFace& f : mesh.faces())
    for (int q = 0; q < 3; ++q) border += !mesh.has_half_edge(f[(q + 1) % 3], f[q]);
  if (!(static_cast<double>(border) > options.open_surface_fraction * 1.5 * mesh.num_faces())) return 0;
  const Eigen::MatrixXi knn = k_nearest_neighbors(mesh.V, k, options.threads);
  int added = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<DualCandidate> candidates = front(mesh, knn, options);
    if (candidates.empty()) break;
    const int first = mesh.num_faces();
    add_compatible_candidates(mesh, candidates, {});
    if (mesh.num_faces() == first) break;
    std::vector<char> drop(mesh.num_faces(), 0);
    for (int f : self_intersecting_faces(mesh))
      if (f >= first) drop[f] = 1;
    mesh.remove_faces(drop);
    added += mesh.num_faces() - first;
    if (mesh.num_faces() == first) break;
  }
  return added;
}

}  // namespace heatcvt
