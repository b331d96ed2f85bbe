#pragma once
/// \file adaptive_sizing.h
/// Curvature-adaptive sizing: a relative target edge length g per point of a surface, smaller
/// where the surface bends, scaled so that a mesh following it keeps the vertex count asked for.
///
/// The rule: with κ the largest normal curvature at a point, a chord of length ℓ deviates from
/// the surface by about ℓ²κ/8, so ℓ ∝ κ^(-1/2) makes that error the same everywhere. The sizing
/// takes g ∝ κ^(-a/2) with the adaptivity a ∈ [0, 2] (0 = uniform, 1 = equal chord error),
/// bounds the ratio of the largest to the smallest size, smooths it over a few site spacings and
/// scales it so that ∫ g⁻² dA equals the area (equilateral triangles of edge ℓ·g then give the
/// uniform count), with thin parts kept at or below the uniform size.
///
/// The CVT reaches it through a density ρ = g⁻⁴ (cells of a CVT with density ρ on a surface have a
/// diameter ∝ ρ^(-1/4): centroidal_voronoi()'s vertex_density), the mesher's sizing stage through
/// g itself (IsotropicRemeshOptions::relative_size).
#include <Eigen/Core>
#include <memory>

namespace heatcvt {

class PointIndex;

/// Options of relative_sizes().
struct AdaptiveSizingOptions {
  /// The exponent a of g ∝ κ^(-a/2): 0 = uniform sizing (every g = 1), 1 = the same chord error
  /// everywhere. Default 0.
  double adaptivity = 0.0;
  /// Largest over smallest relative size (the curvatures are clamped to a range that gives at
  /// most this ratio). Default 3.
  double max_size_ratio = 3.0;
  /// Radius of the curvature estimate, in uniform site spacings sqrt(area / sites): the tips and
  /// rims a mesh at this spacing must follow are about that wide. Default 0.5.
  double radius_spacings = 0.5;
  /// Radius of the smoothing of the sizes (the area-weighted mean of log g within it), in uniform
  /// site spacings: wider than the curvature's, so the sizes change over a few cells and the
  /// triangles between fine and coarse regions keep their shape (at 1,000 vertices, armadillo's
  /// remesh lost 2.8° of φm to the uniform one with 0.5, 0.8° with 1.5; docs/benchmarks.md).
  /// Default 1.5.
  double smoothing_spacings = 1.5;
  /// A point's curvature: this quantile of the normal curvatures towards its neighbours within
  /// the radius. 1 (the largest) is the larger principal curvature in magnitude, the one the
  /// chord error follows: a torus gets one size all over. 0.75 gives the curvature of a sphere
  /// but 0.85 of a cylinder's, and sizes that vary over a torus; at 1,000 vertices of the shared
  /// meshes its remeshes lay farther from the input on the tori and knots than the uniform ones
  /// (docs/benchmarks.md). Default 1.
  double curvature_quantile = 1.0;
  /// ... over the neighbours at least this fraction of the radius away: an error δ of a normal
  /// (a cloud's normals are estimated) changes a normal curvature by about δ / distance, so the
  /// nearest neighbours would decide the largest one. On an ellipsoid (3, 1, 1) sampled by 40,000
  /// points the sizes then span the √3 that the curvatures ask for (1.72–1.76 over five samplings;
  /// 1.55–1.59 with every neighbour). Default 0.7.
  double min_pair_fraction = 0.7;
  /// Thin parts (an ear, a fin, a plate, a finger thinner than this many uniform site spacings):
  /// a point with another point of the surface within this radius such that the segment between
  /// them is within thin_part_angle_deg of both points' normal lines (the other side of the part)
  /// gets no size above the uniform one. Coarser cells there (up to about twice the uniform size)
  /// would span the part's thickness and the dual would open it or join its sides: armadillo's
  /// clean 50k cloud at 3,000 sites had two holes at the ears without the cap, one with a radius
  /// of 1.5 spacings, none with 3 (docs/benchmarks.md). The sizes of the other points are scaled
  /// up to keep the count. 0 = off. Default 3.
  double thin_part_spacings = 3.0;
  /// See thin_part_spacings. Default 60°.
  double thin_part_angle_deg = 60.0;
  /// The finest size goes to the curvatures at and above this quantile over the points (a few
  /// noisy or degenerate points do not set the scale of all the others). Default 0.99.
  double curvature_cap_quantile = 0.99;
  bool enabled() const { return adaptivity > 0; }
};

/// Curvature estimate per point: the `quantile` of |(n_j − n_i)·(p_j − p_i)| / |p_j − p_i|² over
/// the points j within `radius` of p_i and at least `min_distance` from it (the normal curvature
/// along p_j − p_i: 1/R on a sphere of radius R); 0 where a point has no such neighbour. A
/// neighbour's normal facing away from n_i is turned first, so the normals need not be oriented.
///   P #P by 3 positions, N #P by 3 unit normals; index: a PointIndex of P.
/// Parallel over points; the result does not depend on the thread count.
Eigen::VectorXd curvature_estimate(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const PointIndex& index,
                                   double radius, double quantile, double min_distance = 0, int threads = 0);

/// Relative sizes g (#P, all 1 when !options.enabled()) of the points P with unit normals N and
/// areas `weight` (a mesh's lumped vertex areas), for a uniform site spacing `spacing`
/// (see the file comment). Σ weight·g⁻² = Σ weight; max g / min g ≤ max_size_ratio where no
/// thin part is capped (the cap can widen the ratio by the factor the other sizes grow by).
/// \throw InvalidInputError on mismatched sizes, a non-positive spacing or total weight, or
///        options out of range (adaptivity outside [0, 2], max_size_ratio < 1, a non-positive
///        radius, quantiles outside [0, 1], min_pair_fraction outside [0, 1), a negative
///        thin_part_spacings or thin_part_angle_deg outside [0, 90]).
Eigen::VectorXd relative_sizes(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::VectorXd& weight,
                               double spacing, const AdaptiveSizingOptions& options, int threads = 0);

/// The relative size at any point of space: that of the nearest of the points it was built on.
/// Safe for concurrent queries; cheap to copy (the index is shared).
class SizingField {
 public:
  /// P #P by 3 (P.rows() ≥ 1), sizes #P positive values.
  /// \throw InvalidInputError on mismatched sizes, no point or a non-positive size.
  SizingField(const Eigen::MatrixX3d& P, const Eigen::VectorXd& sizes);
  double operator()(const Eigen::Vector3d& x) const;
  const Eigen::VectorXd& sizes() const { return *sizes_; }

 private:
  std::shared_ptr<const PointIndex> index_;
  std::shared_ptr<const Eigen::VectorXd> sizes_;
};

/// The adaptive sizing of a triangulated surface for a number of sites: what the CVT and the
/// mesher read (RemeshOptions::adaptive, ReconstructionOptions::adaptive).
struct SurfaceSizing {
  SizingField field;  ///< g at any point, for IsotropicRemeshOptions::relative_size
  double ratio = 1;   ///< largest over smallest g
  /// The densities g⁻⁴ at the rows of P, for centroidal_voronoi()'s vertex_density (the vertices
  /// the CVT runs on: the surface's own, or those of its refinement).
  Eigen::VectorXd density_at(const Eigen::MatrixX3d& P) const;
};

/// relative_sizes() of the vertices of (V, F) (a mesh, or a cloud's point triangles) with unit
/// normals N, weighted by their lumped areas, at the spacing sqrt(area / sites). The curvature's
/// radius is at least 1.5 mean edge lengths of (V, F) (its inner distance unchanged), so that
/// every vertex of a mesh coarser than the sites has its one-ring to measure it by (the sizes of
/// a coarse mesh come from its own vertices and smooth normals, not from the flat faces of its
/// refinement).
/// \throw InvalidInputError as relative_sizes(), or on sites < 1 or a surface without area.
SurfaceSizing surface_sizing(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Eigen::MatrixX3d& N, int sites,
                             const AdaptiveSizingOptions& options, int threads = 0);

}  // namespace heatcvt
