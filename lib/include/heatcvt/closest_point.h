#pragma once
/// \file closest_point.h
/// Snapping points in space to the surface (e.g. user-given generators, `--sites-file`).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// Closest-point queries on one triangle mesh (CGAL AABB tree built once; exact point-triangle
/// distance). Safe for concurrent queries.
class ClosestPointTree {
 public:
  /// \throw InvalidInputError on a mesh without faces.
  ClosestPointTree(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);
  ~ClosestPointTree();
  /// The point of the mesh closest to p, as a face and barycentric coordinates.
  SurfacePoint closest(const Eigen::Vector3d& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

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
