#pragma once
/// \file mesh_checks.h
/// Self-intersections of the working mesh during meshing: what the "try, and undo if it
/// self-intersects" stages ask.
#include <utility>
#include <vector>

#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Pairs (f, g), f < g, ascending, of faces of the mesh that intersect other than along what they
/// share, by the rule of CGAL's Polygon_mesh_processing::self_intersections(): faces with a
/// common edge intersect when they are coplanar and on the same side of it (they overlap); faces
/// with one common vertex when the edge of either opposite it meets the other; other faces when
/// the triangles meet (exact predicates). Faces whose corners are collinear are skipped, as there.
/// Beyond CGAL's rule, faces that come within 1e-9 of the mesh's bounding-box diagonal of each
/// other apart from what they share count too: such a near contact can become a real one when
/// the mesh is scaled back to its input's frame, and CGAL's check of the written mesh would fail.
/// Candidate pairs come from CGAL's box intersection of the faces' bounding boxes; no topology
/// is checked, so the cost is that of the boxes alone.
std::vector<std::pair<int, int>> intersecting_face_pairs(const WorkingMesh& mesh);

/// Faces involved in a self-intersection (intersecting_face_pairs()), ascending.
std::vector<int> self_intersecting_faces(const WorkingMesh& mesh);

/// Number of intersecting face pairs (0 for an empty mesh).
long self_intersecting_pairs(const WorkingMesh& mesh);

/// A pair of faces by their corners: it names the same faces after edits that renumber them.
using FacePair = std::pair<MeshFace, MeshFace>;

/// The intersecting face pairs (intersecting_face_pairs()) by their corners.
std::vector<FacePair> crossing_face_pairs(const WorkingMesh& mesh);

/// The intersecting face pairs of `mesh` after an edit from the state `before`, whose pairs were
/// `pairs_before`. A face the edit left alone (same corners, none moved) still crosses what it
/// crossed; so the pairs of two such faces are kept, and only the faces the edit made or moved are
/// checked, against every face: a grid of their boxes is met by each face's box. Where more than
/// `max_changed_fraction` of the faces changed (a smoothing of the whole mesh), it is
/// crossing_face_pairs(). The pairs are those of crossing_face_pairs(mesh), but for a pair of
/// faces that only just meets, whose verdict depends on the contact tolerance the bounding box
/// sets (a box changed by the edit).
std::vector<FacePair> crossing_face_pairs_after(const WorkingMesh& mesh, const WorkingMesh::Checkpoint& before,
                                                const std::vector<FacePair>& pairs_before,
                                                double max_changed_fraction = 0.1);

/// The faces of `mesh` named in `pairs`, ascending, each once.
std::vector<int> faces_in_pairs(const WorkingMesh& mesh, const std::vector<FacePair>& pairs);

/// The topology a mesh is to keep through the mesher's stages: its edge-connected components,
/// boundary loops and Euler characteristic (an input mesh's, for its remesh). components < 0:
/// no target.
struct TopologyTarget {
  int components = -1;
  int boundary_loops = 0;
  int euler_characteristic = 0;
  bool enabled() const { return components >= 0; }
  bool operator==(const TopologyTarget& o) const {
    return components == o.components && boundary_loops == o.boundary_loops &&
           euler_characteristic == o.euler_characteristic;
  }
};

/// Components, boundary loops and Euler characteristic of the mesh's faces (mesh_topology()).
TopologyTarget topology_of(const WorkingMesh& mesh);

/// Whether a step that took the mesh from topology `before` to `after` breaks `target`: the mesh
/// had the target's topology and lost it, or it now has fewer boundary loops than both before and
/// the target (a real hole closed, or two joined). Never with a target that is not enabled().
bool breaks_topology(const TopologyTarget& target, const TopologyTarget& before, const TopologyTarget& after);

/// Boundary loop of each vertex of the mesh (boundary_loop_labels() of its faces: −1 off the
/// border); returns the number of loops.
int boundary_loop_labels(const WorkingMesh& mesh, std::vector<int>& loop);

/// Vertices of the loops of `before` (labels from boundary_loop_labels() of an earlier state)
/// that the mesh no longer has as loops of their own: loops none of whose vertices is on the
/// border any more (collapsed or closed), and loops that now share a loop with another (joined).
/// Empty when every loop of `before` is still there.
std::vector<int> lost_loop_vertices(const WorkingMesh& mesh, const std::vector<int>& before);

}  // namespace heatcvt
