#pragma once
/// \file closest_point.h
/// Snapping points in space to the surface (e.g. user-given generators, `--sites-file`).
#include <Eigen/Core>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// For every row of `points` (#P by 3) the closest point on the triangle mesh (V, F), as a
/// face and barycentric coordinates (CGAL AABB tree; exact point-triangle distance).
/// \throw InvalidInputError on an empty mesh or non-finite query points.
std::vector<SurfacePoint> closest_surface_points(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                                 const Eigen::MatrixX3d& points);

/// Barycentric coordinates of the point of triangle (a, b, c) closest to p (clamped to the
/// triangle; robust for degenerate triangles).
Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Surface points located exactly at the given vertices (an incident face, barycentric unit
/// vector). One pass over F whatever the number of vertices.
/// \throw InvalidInputError if a vertex is out of range or no face references it.
std::vector<SurfacePoint> surface_points_at_vertices(const Eigen::MatrixX3i& F, int num_vertices,
                                                     const std::vector<int>& vertices);

}  // namespace heatcvt
