#pragma once
/// \file mesh_checks.h
/// Validation of the working mesh during meshing (CGAL checks of validate_triangle_mesh() on the
/// referenced vertices): what the "try, and undo if it self-intersects" stages ask.
#include <vector>

#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/validate.h"

namespace heatcvt {

/// validate_triangle_mesh() of the mesh's faces on the vertices they reference (require_closed =
/// false; faces keep their indices), listing at most `max_listed` items per check.
ValidationReport check_working_mesh(const WorkingMesh& mesh, int max_listed);

/// Faces involved in a self-intersection, ascending.
std::vector<int> self_intersecting_faces(const WorkingMesh& mesh);

/// Number of intersecting face pairs (0 for an empty mesh).
long self_intersecting_pairs(const WorkingMesh& mesh);

}  // namespace heatcvt
