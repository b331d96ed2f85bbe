#pragma once
/// \file shapes.h
/// Shapes built in code for experiments and tests (paper Fig. 3).
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

}  // namespace heatcvt
