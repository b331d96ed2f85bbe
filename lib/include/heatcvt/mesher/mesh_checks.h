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

}  // namespace heatcvt
