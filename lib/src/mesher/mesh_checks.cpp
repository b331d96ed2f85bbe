// CGAL checks of the working mesh.
#include "heatcvt/mesher/mesh_checks.h"

#include <algorithm>
#include <limits>

namespace heatcvt {

ValidationReport check_working_mesh(const WorkingMesh& mesh, int max_listed) {
  const int ns = mesh.num_vertices();
  std::vector<int> map(ns, -1);
  int m = 0;
  for (const MeshFace& f : mesh.faces())
    for (int v : f)
      if (map[v] < 0) map[v] = m++;
  Eigen::MatrixX3d VV(m, 3);
  for (int v = 0; v < ns; ++v)
    if (map[v] >= 0) VV.row(map[v]) = mesh.V.row(v);
  Eigen::MatrixX3i FF(mesh.num_faces(), 3);
  for (int i = 0; i < mesh.num_faces(); ++i)
    for (int k = 0; k < 3; ++k) FF(i, k) = map[mesh.face(i)[k]];
  ValidationOptions vo;
  vo.require_closed = false;
  vo.max_listed = max_listed;
  return validate_triangle_mesh(VV, FF, vo);
}

std::vector<int> self_intersecting_faces(const WorkingMesh& mesh) {
  std::vector<int> out;
  if (mesh.empty()) return out;
  const ValidationReport rep = check_working_mesh(mesh, std::numeric_limits<int>::max());
  for (const auto& c : rep.checks)
    if (c.name == "no_self_intersections")
      for (const auto& w : c.where)
        for (int f : w) out.push_back(f);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

long self_intersecting_pairs(const WorkingMesh& mesh) {
  if (mesh.empty()) return 0;
  return std::max(0L, check_working_mesh(mesh, 1).self_intersecting_pairs);
}

}  // namespace heatcvt
