#pragma once
/// \file shapes.h
/// Shapes built in code for experiments and tests (paper Fig. 3; intrinsic surfaces of §7.1).
#include <cstdint>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// Random triangulation of the unit sphere (paper Fig. 3): the 6 octahedron vertices plus
/// `num_random` points drawn as normalised Gaussian vectors (std::mt19937 seeded with `seed`),
/// triangulated by their convex hull (CGAL convex_hull_3), faces oriented outward.
/// With `biased` the Gaussian x-coordinate is scaled by `bias` (> 1) before normalisation, so the
/// points concentrate toward the ±x poles and the triangulation has many obtuse triangles.
///   returns V #V by 3 (unit length rows), F #F by 3; #V = num_random + 6 (duplicates removed).
/// \throw InvalidInputError if num_random < 0 or bias is not finite and > 0.
TriangleMesh random_sphere_mesh(int num_random, uint32_t seed = 1, bool biased = false, double bias = 4.0);

/// Welded, closed Klein bottle: the standard "figure-8" immersion in R³ (self-intersecting along
/// one circle),
///   x = (r + cos(u/2) sin v − sin(u/2) sin 2v) cos u,  y = (…) sin u,
///   z = sin(u/2) sin v + cos(u/2) sin 2v,              u, v ∈ [0, 2π),
/// sampled on an nu × nv grid (v offset by half a step, so no two vertices coincide in space)
/// and welded by the parameter identifications (u, v + 2π) ~ (u, v) and (u + 2π, v) ~ (u, −v),
/// never by position: the two sheets that cross along the circle v ∈ {0, π} stay apart.
/// Faces follow the (u, v) orientation, so the edges across the seam u = 0 are traversed twice in
/// the same direction (no consistent orientation exists).
///   returns #V = nu·nv, #F = 2·nu·nv: a closed 2-manifold, Euler characteristic 0, non-orientable.
/// Defaults nu = 160, nv = 64 (10,240 vertices; well-shaped triangles for r = 2).
/// \throw InvalidInputError if nu < 3, nv < 4, nv odd, or r ≤ 1 (the immersion needs r > 1).
TriangleMesh klein_bottle_mesh(int nu = 160, int nv = 64, double r = 2.0);

/// Two interpenetrating square sheets in one mesh (a self-intersecting input): sheet 0 is the
/// square [−size/2, size/2]² of the plane z = 0, sheet 1 the same square rotated by `angle`
/// (radians) about the x axis and shifted by half a grid step along x (no coincident vertices);
/// they pass through each other along the x axis and are closer than size·sin(angle)/2 anywhere.
/// Each sheet is an n × n grid of quads split into two triangles (alternating diagonals).
///   returns vertices [0, (n+1)²) and faces [0, 2n²) on sheet 0, the rest on sheet 1.
/// Defaults n = 40, angle = 0.3, size = 2.
/// \throw InvalidInputError if n < 1, size ≤ 0, or angle is not finite.
TriangleMesh interpenetrating_sheets_mesh(int n = 40, double angle = 0.3, double size = 2.0);

}  // namespace heatcvt
