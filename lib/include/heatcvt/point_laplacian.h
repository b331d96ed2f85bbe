#pragma once
/// \file point_laplacian.h
/// Laplacian of a point cloud (METHOD.md §7), after Sharp & Crane 2020, "A Laplacian for
/// Nonmanifold Triangle Meshes", point-cloud variant. Produces the same heatcvt::Laplacian as
/// cotan_laplacian(), so the heat solver, Voronoi, centroid and CVT code work unchanged.
///
/// Construction, per point i (parallel over points, deterministic):
///  1. its k exact nearest neighbours (k_nearest_neighbors(), normals.h);
///  2. the PCA normal of i and its neighbours, and an orthonormal tangent frame;
///  3. the neighbours projected to that tangent plane and their 2D Delaunay triangulation
///     (CGAL, exact predicates), i inserted first;
///  4. the "local triangles": the finite Delaunay triangles incident to i.
/// The union of all local triangles, WITH repetitions (a triangle usually appears in the fans of
/// its three corners), is a non-manifold triangle soup; every soup triangle carries weight 1/3.
///
/// Default (`intrinsic_delaunay = true`), Sharp & Crane's construction: the tufted cover of the
/// soup (front and back sheet per triangle; around every edge the faces are sorted by the
/// dihedral angle of their third vertex, interleaved so that faces on opposite sides alternate,
/// and consecutive ones glued — a closed oriented manifold), 3D edge lengths mollified (every
/// triangle inequality gets a slack ≥ mollify_factor·h̄ by adding the same δ to all lengths),
/// then intrinsic Delaunay edge flips (Lawson, degree-1 vertices allowed) until every edge has
/// cot α + cot β ≥ 0, then the cotan Laplacian and lumped barycentric mass of that intrinsic
/// triangulation (paper eq. 5–6), halved for the two sheets and multiplied by 1/3. Off-diagonals
/// are non-negative by construction; a final safeguard clamps any summed off-diagonal that is
/// still negative (rounding in cocircular configurations, or the flip cap) to 0 and counts it in
/// `clamped_edges` (measured: 0 on random clouds and the kitten; rounding-level, > −1e-9, on the
/// latitude–longitude grid of sphere926.pwn).
///
/// Caveat (inherent to the local-triangulation approach): on grid-like samplings with many
/// cocircular quadruples the local Delaunay fans pick inconsistent diagonals, each fan tending
/// to take the diagonal through its centre, so the soup over-covers the surface: on
/// sphere926.pwn ΣM is 1.32 × the sphere area, while the spectrum is still right (L scales
/// alike; eigenvalues l ≤ 2 within 1 %). On random samples ΣM is within 1–2 % of the area.
///
/// Fallback (`intrinsic_delaunay = false`, no flips, ~1.5× faster): each local triangle T of
/// point i adds (1/3)·½·cot(angle at corner c) to the edge opposite c, the angles measured in
/// the 2D projection to i's tangent plane, where T belongs to a Delaunay triangulation: the two
/// angles opposite an interior spoke (i, j) sum to ≤ π, so those contributions are ≥ 0; only
/// edges with a single local triangle (fan rim edges, spokes on the local hull) can be negative.
/// Mass: each local triangle adds (1/3)·(area₃D/3) to its corners. Summed off-diagonals that
/// are still negative are clamped to 0 (counted in PointLaplacian::clamped_edges; ~0.1–0.3 %
/// of the edges on random samples).
///
/// Measured accuracy (random uniform samples, k = 30): unit-sphere eigenvalues l ≤ 3 within
/// 0.6 % (tufted) / 0.5 % (fallback) at 8000 points; linear functions on a plane reproduced
/// to a mean relative residual of 1e-4 in both modes.
///
/// In both modes the diagonal is minus the row sum, so L·1 = 0 up to rounding.
/// Result: L symmetric, off-diagonals ≥ 0, L·1 = 0, negative semi-definite (weakly diagonally
/// dominant), M > 0. Converges like the cotan Laplacian on well-sampled smooth surfaces
/// (tested: planes, unit-sphere spectrum l(l+1) within 5 %, in both modes).
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
  /// Sharp & Crane's intrinsic Delaunay Laplacian of the tufted cover (true) or the cheaper
  /// local-2D-cotangent fallback (false); see the file comment. Default true.
  bool intrinsic_delaunay = true;
  /// Mollification slack ε as a fraction of the mean soup edge length (Sharp & Crane §4.5).
  /// Only used with intrinsic_delaunay. Default 1e-5.
  double mollify_factor = 1e-5;
  /// Points that end up in no local triangle (e.g. collinear neighbourhoods, exact duplicates)
  /// get this fraction of the mean point mass so that M > 0. Default 1e-6.
  double min_mass_fraction = 1e-6;
  /// Optional consistently oriented unit normals (#P by 3, e.g. from orient_normals_mst()). When
  /// given, a neighbour j is left out of point i's local triangulation if n_i · n_j < 0, and a
  /// local triangle is skipped if two of its corners have opposite normals: the two sides of a
  /// part thinner than the neighbourhood are not connected (the PCA `normals` still use all k
  /// neighbours). Default nullptr (all neighbours).
  const Eigen::MatrixX3d* oriented_normals = nullptr;
  /// With `oriented_normals`: two points of opposite normal are kept apart only where the
  /// second lies off the first's tangent plane by at least this fraction of their distance (the
  /// other side of a thin part), so that normals flipped within one sheet (an orientation error)
  /// keep their links. 0 = every pair of opposite normal is kept apart. Default 0.
  double across_min_offset = 0;
  /// ... and, with across_min_offset > 0, only where their normals' dot product is at most this
  /// (the two faces of a slab face opposite ways; at a crease whose normals an orientation error
  /// flipped they are nearer perpendicular). Default −0.5 (more than 120° apart).
  double across_max_dot = -0.5;
  /// Optional precomputed neighbours (#P by ≥ k, nearest first, as k_nearest_neighbors()
  /// returns them; the first k columns are used), so that a caller who already searched does not
  /// search again. Default nullptr (searched here).
  const Eigen::MatrixXi* neighbors = nullptr;
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
  /// The k nearest neighbours of each point (#P by k, nearest first, as k_nearest_neighbors()
  /// returns them), kept so that callers needing the same neighbourhoods do not search again.
  Eigen::MatrixXi neighbors;
  /// Number of edges whose summed weight was negative and was clamped to 0 (in the default
  /// intrinsic mode only rounding-level negatives from cocircular configurations, see
  /// `most_negative_weight`).
  int clamped_edges = 0;
  /// The most negative summed off-diagonal weight before clamping (0 if none was negative).
  double most_negative_weight = 0;
  /// Intrinsic edge flips performed (intrinsic_delaunay mode).
  long long intrinsic_flips = 0;
  /// Non-Delaunay edges that could not be flipped (both sides in one face, or the flip cap
  /// reached; intrinsic_delaunay mode). 0 on every test cloud.
  long long unflippable_edges = 0;
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

/// Whether point b (unit oriented normal nb) is on the other side of a thin part from a (na), as
/// point_laplacian() decides with oriented normals: opposite normals, and where `min_offset` > 0
/// also normals at most `max_dot` apart (their dot product) and b off a's tangent plane by at
/// least `min_offset` of their distance (PointLaplacianOptions::across_min_offset,
/// across_max_dot).
bool across_thin_part(const Eigen::RowVector3d& a, const Eigen::RowVector3d& na, const Eigen::RowVector3d& b,
                      const Eigen::RowVector3d& nb, double min_offset, double max_dot);

}  // namespace heatcvt
