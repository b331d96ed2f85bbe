// Untangling of self-intersections.
#include "heatcvt/mesher/untangle.h"

#include "heatcvt/mesher/mesh_checks.h"

#include <unordered_set>

namespace heatcvt {

void untangle(WorkingMesh& mesh, const SurfaceProjector& surface, const UntangleOptions& options,
              const HoleFillingOptions& holes, const ManifoldOptions& manifold, MesherStats& stats) {
  for (int round = 0; round < options.rounds; ++round) {
    const std::vector<int> bad = self_intersecting_faces(mesh);
    if (bad.empty()) break;
    std::vector<char> drop(mesh.num_faces(), 0);
    std::vector<char> vbad(mesh.num_vertices(), 0);
    for (int f : bad) {
      drop[f] = 1;
      for (int v : mesh.face(f)) vbad[v] = 1;
    }
    if (round > 0)
      for (int i = 0; i < mesh.num_faces(); ++i)
        if (vbad[mesh.face(i)[0]] || vbad[mesh.face(i)[1]] || vbad[mesh.face(i)[2]]) drop[i] = 1;
    stats.removed_triangles += mesh.remove_faces(drop);
    stats.removed_triangles += make_vertices_manifold(mesh, manifold);
    stats.border_triangles += grow_borders(mesh, options.regrow);
    stats.holes_filled += fill_holes(mesh, surface, holes, manifold, stats.removed_triangles, &stats.filled_hole_edges);
  }
  // Whatever the last refill left crossing is removed; the holes are refilled once more and the
  // new triangles that cross are taken out again: never an intersection out.
  std::vector<int> bad = self_intersecting_faces(mesh);
  if (bad.empty()) return;
  std::vector<char> drop(mesh.num_faces(), 0);
  for (int f : bad) drop[f] = 1;
  stats.removed_triangles += mesh.remove_faces(drop);
  stats.removed_triangles += make_vertices_manifold(mesh, manifold);
  std::unordered_set<MeshFace, MeshFaceHash> before;
  for (MeshFace f : mesh.faces()) before.insert(f);
  stats.holes_filled += fill_holes(mesh, surface, holes, manifold, stats.removed_triangles, &stats.filled_hole_edges);
  bad = self_intersecting_faces(mesh);
  if (bad.empty()) return;
  drop.assign(mesh.num_faces(), 0);
  for (int f : bad) drop[f] = before.count(mesh.face(f)) == 0;  // the old faces no longer cross each other
  stats.removed_triangles += mesh.remove_faces(drop);
  stats.removed_triangles += make_vertices_manifold(mesh, manifold);
}

}  // namespace heatcvt
