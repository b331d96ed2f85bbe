#pragma once
/// \file point_laplacian.h
/// Laplacian of a point cloud (METHOD.md §7), after Sharp & Crane 2020, "A Laplacian for
/// Nonmanifold Triangle Meshes", point-cloud variant. Produces the same heatcvt::Laplacian as
/// cotan_laplacian(), so the heat solver, Voronoi, centroid and CVT code work unchanged.
///
/// Construction, per point i (parallel over points, deterministic):
///  1. its k exact nearest neighbours (FLANN kd-tree);
///  2. the PCA normal of i and its neighbours, and an orthonormal tangent frame;
///  3. the neighbours projected to that tangent plane and their 2D Delaunay triangulation
///     (CGAL, exact predicates), i inserted first;
///  4. the "local triangles": the finite Delaunay triangles incident to i.
/// The union of all local triangles is a non-manifold triangle soup; every local triangle
/// carries weight 1/3 (it would appear in the fans of its three corners if the local
/// triangulations agreed). Then (paper eq. 5–6 on that soup):
///  - stiffness: each local triangle T of point i adds (1/3)·½·cot(angle at corner c) to the
///    weight of the edge opposite c, for all three corners, with the angles measured in the 2D
///    projection of point i's tangent plane (where T is Delaunay);
///  - mass: each local triangle adds (1/3)·(area₃D(T)/3) to each of its three corners.
///
/// Non-negativity — the DOCUMENTED FALLBACK, not the intrinsic Delaunay flips of Sharp & Crane:
/// the intrinsic flip algorithm on the tufted cover is not implemented. Instead the cotangents
/// are taken in each local 2D Delaunay triangulation, where the two angles opposite an interior
/// edge sum to ≤ π, so the contribution of every interior spoke (i, j) of the fan is ≥ 0. Only
/// edges with a single local triangle (rim edges of the fan and spokes on the local convex hull,
/// i.e. an obtuse angle at a boundary of the neighbourhood) can contribute negatively; after
/// summing all contributions, any edge whose total weight is still negative is clamped to 0
/// (counted in PointLaplacian::clamped_edges). The diagonal is then set to minus the row sum,
/// so L·1 = 0 exactly up to rounding.
///
/// Result: L symmetric, off-diagonals ≥ 0, L·1 = 0, negative semi-definite (weakly diagonally
/// dominant), M > 0. Converges like the cotan Laplacian on well-sampled smooth surfaces
/// (tested: planes, unit-sphere spectrum l(l+1) within 5 %).
#include <Eigen/Core>

#include "heatcvt/laplacian.h"

namespace heatcvt {

/// Options of point_laplacian().
struct PointLaplacianOptions {
  /// Neighbours per point (excluding the point itself). Must be ≥ 3. Default 30.
  int k = 30;
  /// Threads for the per-point work; 0 = all hardware threads. Default 0. Results do not
  /// depend on it.
  int threads = 0;
  /// Cotangents are clamped to ±cot_clamp so sliver triangles never produce inf. Default 1e5.
  double cot_clamp = 1e5;
  /// A local triangle whose projected 2D area is below eps · (mean squared neighbour distance
  /// of its centre point) is skipped. Default 1e-12.
  double degenerate_area_epsilon = 1e-12;
  /// Points that end up in no local triangle (e.g. collinear neighbourhoods, exact duplicates)
  /// get this fraction of the mean point mass so that M > 0. Default 1e-6.
  double min_mass_fraction = 1e-6;
};

/// Result of point_laplacian().
struct PointLaplacian {
  /// L (#P by #P), M (#P), mean_edge_length (mean 3D length of the distinct edges of
  /// `triangles`); `degenerate_faces` stays empty (degenerate local triangles are simply
  /// skipped and counted in `degenerate_triangles`).
  Laplacian laplacian;
  /// Distinct local triangles (#T by 3, point indices), duplicates across fans removed (the
  /// first occurrence in point order is kept). Orientation: counter-clockwise around the
  /// PCA normal of the point whose fan produced it, i.e. NOT globally consistent.
  Eigen::MatrixX3i triangles;
  /// Unoriented unit PCA normals (#P by 3) of the point and its k neighbours; orient them with
  /// orient_normals_mst() (normals.h) if needed.
  Eigen::MatrixX3d normals;
  /// Number of edges whose summed weight was negative and was clamped to 0.
  int clamped_edges = 0;
  /// Number of local triangles skipped as degenerate.
  int degenerate_triangles = 0;
  /// Number of points in no local triangle (they got the minimum mass and no edges).
  int isolated_points = 0;
  /// Wall-clock seconds of the whole construction (kNN included).
  double build_seconds = 0;
};

/// Builds the point-cloud Laplacian described in the file comment.
///   P  #P by 3 positions.
/// \throw InvalidInputError if options.k < 3, #P < k + 1, options.threads < 0, a coordinate is
///        NaN or infinite, or the cloud is degenerate so that no local triangle exists at all.
PointLaplacian point_laplacian(const Eigen::MatrixX3d& P, const PointLaplacianOptions& options = {});

}  // namespace heatcvt
