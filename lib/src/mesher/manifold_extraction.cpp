// Manifold extraction from candidate triangles.
#include "heatcvt/mesher/manifold_extraction.h"

#include <algorithm>
#include <map>
#include <unordered_set>
#include <utility>

namespace heatcvt {
namespace {

bool fits_edges(const WorkingMesh& mesh, const MeshFace& f) {
  for (int k = 0; k < 3; ++k) {
    const int a = f[k], b = f[(k + 1) % 3];
    if (mesh.has_half_edge(a, b) || mesh.edge_face_count(a, b) >= 2) return false;
  }
  return true;
}

MeshFace sorted(MeshFace f) {
  std::sort(f.begin(), f.end());
  return f;
}

}  // namespace

std::vector<std::vector<int>> vertex_fans(const WorkingMesh& mesh, int v, const std::vector<int>& faces) {
  const int m = static_cast<int>(faces.size());
  DisjointSets sets(m);
  std::map<int, int> first_with_other;  // other vertex -> face slot
  for (int i = 0; i < m; ++i)
    for (int o : mesh.face(faces[i])) {
      if (o == v) continue;
      auto [it, fresh] = first_with_other.emplace(o, i);
      if (!fresh) sets.unite(i, it->second);
    }
  std::vector<std::vector<int>> out;
  std::vector<int> fan_of_root(m, -1);
  for (int i = 0; i < m; ++i) {
    int& fan = fan_of_root[sets.find(i)];
    if (fan < 0) fan = static_cast<int>(out.size()), out.emplace_back();
    out[fan].push_back(faces[i]);
  }
  return out;
}

int extract_manifold(WorkingMesh& mesh, const std::vector<DualCandidate>& candidates) {
  int rejected = 0;
  for (const DualCandidate& c : candidates) {
    if (fits_edges(mesh, c.f)) mesh.add_face(c.f);
    else ++rejected;
  }
  return rejected;
}

int make_vertices_manifold(WorkingMesh& mesh, const ManifoldOptions& options) {
  int removed = 0;
  for (int round = 0; round < options.max_fan_rounds; ++round) {
    const std::vector<std::vector<int>> vf = mesh.vertex_faces();
    std::vector<char> drop(mesh.num_faces(), 0);
    bool changed = false;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (vf[v].size() < 2) continue;
      const auto fans = vertex_fans(mesh, v, vf[v]);
      if (fans.size() < 2) continue;
      size_t keep = 0;
      for (size_t i = 1; i < fans.size(); ++i)
        if (fans[i].size() > fans[keep].size()) keep = i;
      for (size_t i = 0; i < fans.size(); ++i)
        if (i != keep)
          for (int f : fans[i]) drop[f] = 1, changed = true;
    }
    if (!changed) break;
    removed += mesh.remove_faces(drop);
  }
  // Pieces connected through shared edges.
  const FaceComponents pieces = face_components(mesh, false);
  int largest = 0;
  for (int s : pieces.size) largest = std::max(largest, s);
  if (largest > options.max_dropped_piece_faces) {
    std::vector<char> drop(mesh.num_faces(), 0);
    for (int f = 0; f < mesh.num_faces(); ++f)
      drop[f] = pieces.size[pieces.of_face[f]] <= options.max_dropped_piece_faces;
    removed += mesh.remove_faces(drop);
  }
  return removed;
}

int add_compatible_candidates(WorkingMesh& mesh, const std::vector<DualCandidate>& first,
                              const std::vector<DualCandidate>& second) {
  std::unordered_set<MeshFace, MeshFaceHash> present;
  for (const MeshFace& f : mesh.faces()) present.insert(sorted(f));
  std::vector<std::vector<int>> vf = mesh.vertex_faces();
  int added = 0;
  for (const std::vector<DualCandidate>* list : {&first, &second})
    for (const DualCandidate& c : *list) {
      if (present.count(sorted(c.f)) || !fits_edges(mesh, c.f)) continue;
      const int id = mesh.add_face(c.f);
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        std::vector<int> faces = vf[c.f[k]];
        faces.push_back(id);
        if (vertex_fans(mesh, c.f[k], faces).size() > 1) ok = false;
      }
      if (!ok) {
        mesh.pop_face();
        continue;
      }
      present.insert(sorted(c.f));
      for (int v : c.f) vf[v].push_back(id);
      ++added;
    }
  return added;
}

}  // namespace heatcvt
