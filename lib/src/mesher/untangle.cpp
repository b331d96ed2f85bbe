// Untangling of self-intersections.
#include "heatcvt/mesher/untangle.h"

#include "heatcvt/mesher/mesh_checks.h"

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
  // Whatever the last refill left crossing is removed without refilling: never an intersection out.
  const std::vector<int> bad = self_intersecting_faces(mesh);
  if (bad.empty()) return;
  std::vector<char> drop(mesh.num_faces(), 0);
  for (int f : bad) drop[f] = 1;
  stats.removed_triangles += mesh.remove_faces(drop);
  stats.removed_triangles += make_vertices_manifold(mesh, manifold);
}

}  // namespace heatcvt
