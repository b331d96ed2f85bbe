#pragma once
/// \file subdivision.h
/// Loop subdivision, used to build large test and benchmark meshes (Table 1 sizes) from the
/// bundled ones.
#include "heatcvt/mesh.h"

namespace heatcvt {

/// One step of Loop subdivision (Loop 1987, Warren's β for valence n: 3/(8n), n > 3; 3/16 for
/// n = 3). Boundary edges and vertices use the cubic B-spline boundary rules. Every triangle
/// becomes four; #V grows to #V + #E.
TriangleMesh loop_subdivide(const TriangleMesh& mesh);

/// Applies loop_subdivide until the mesh has at least `min_vertices` vertices.
TriangleMesh loop_subdivide_to(const TriangleMesh& mesh, int min_vertices);

}  // namespace heatcvt
