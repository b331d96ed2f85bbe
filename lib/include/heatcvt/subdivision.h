#pragma once
/// \file subdivision.h
/// 1-to-4 subdivision of triangle meshes: Loop subdivision (smooth; builds large test and
/// benchmark meshes, Table 1 sizes, from the bundled ones) and midpoint subdivision (linear; adds
/// resolution without changing the surface, e.g. under the cells of a CVT with more sites than
/// input vertices).
///
/// Both number the output the same way: the old vertices keep their indices, the new edge
/// points follow in order of first appearance in F, and face f = (a, b, c) becomes the faces
/// 4f … 4f+3 = (a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca).
#include "heatcvt/mesh.h"

namespace heatcvt {

/// One step of Loop subdivision (Loop 1987, Warren's β for valence n: 3/(8n), n > 3; 3/16 for
/// n = 3). Boundary edges and vertices use the cubic B-spline boundary rules. Every triangle
/// becomes four; #V grows to #V + #E.
TriangleMesh loop_subdivide(const TriangleMesh& mesh);

/// Applies loop_subdivide until the mesh has at least `min_vertices` vertices.
TriangleMesh loop_subdivide_to(const TriangleMesh& mesh, int min_vertices);

/// One step of midpoint (linear) subdivision: a new vertex at the midpoint of every edge, every
/// triangle split into four congruent ones lying in it, so the surface (as a point set), its
/// boundary and its topology are unchanged; #V grows to #V + #E.
TriangleMesh midpoint_subdivide(const TriangleMesh& mesh);

/// The point of the mesh before one midpoint_subdivide() (or loop_subdivide(), up to the smoothing
/// of the positions) that corresponds to the point `p` of the subdivided mesh: face p.face / 4,
/// barycentric coordinates composed with those of the child face's corners. Exact for the
/// midpoint rule (the same 3D position).
SurfacePoint subdivision_parent(const SurfacePoint& p);

}  // namespace heatcvt
