// Removal of interior vertices of valence 3.
#include "heatcvt/mesher/valence3_removal.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <unordered_set>

namespace heatcvt {

int remove_valence3(WorkingMesh& mesh, const Valence3Options& options, const std::vector<char>* only) {
  const Eigen::MatrixX3d& S = mesh.V;
  const int ns = mesh.num_vertices();
  int removed = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<std::vector<int>> vf = mesh.vertex_faces();
    std::unordered_set<MeshFace, MeshFaceHash> present;
    for (MeshFace f : mesh.faces()) {
      std::sort(f.begin(), f.end());
      present.insert(f);
    }
    std::vector<char> drop(mesh.num_faces(), 0), touched(ns, 0);
    std::vector<MeshFace> added;
    const size_t min_faces = static_cast<size_t>(options.min_ring_faces);
    for (int v = 0; v < ns; ++v) {
      if (vf[v].size() != 3 || touched[v] || (only && !(*only)[v])) continue;
      // Ring order: for each face (v, x, y) in rotation, x -> y.
      std::map<int, int> next;
      for (int id : vf[v]) {
        const MeshFace& f = mesh.face(id);
        int k = 0;
        while (f[k] != v) ++k;
        next[f[(k + 1) % 3]] = f[(k + 2) % 3];
      }
      if (next.size() != 3) continue;
      const int a = next.begin()->first, b = next[a], c = next.count(b) ? next[b] : -1;
      if (c < 0 || !next.count(c) || next[c] != a || a == b || b == c || a == c) continue;
      if (touched[a] || touched[b] || touched[c]) continue;
      if (vf[a].size() < min_faces || vf[b].size() < min_faces || vf[c].size() < min_faces) continue;
      MeshFace key = {a, b, c};
      std::sort(key.begin(), key.end());
      if (present.count(key)) continue;
      const Eigen::Vector3d fn = (S.row(b) - S.row(a)).cross(S.row(c) - S.row(a)).transpose();
      Eigen::Vector3d old_n = Eigen::Vector3d::Zero();
      for (int id : vf[v]) {
        const MeshFace& f = mesh.face(id);
        old_n += (S.row(f[1]) - S.row(f[0])).cross(S.row(f[2]) - S.row(f[0])).transpose();
      }
      if (!(fn.dot(old_n) > 0)) continue;
      for (int id : vf[v]) drop[id] = 1;
      touched[v] = touched[a] = touched[b] = touched[c] = 1;
      added.push_back({a, b, c});
      present.insert(key);
    }
    if (added.empty()) break;
    mesh.remove_faces(drop);
    for (const MeshFace& t : added) mesh.add_face(t);
    removed += static_cast<int>(added.size());
  }
  return removed;
}

}  // namespace heatcvt
