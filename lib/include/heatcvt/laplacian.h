#pragma once
/// \file laplacian.h
/// The one Laplacian interface every downstream module consumes. Two builders produce it:
/// cotan_laplacian() for triangle meshes (this header) and point_laplacian() for point clouds
/// (point_laplacian.h). The heat solver, Voronoi, centroid and CVT code never know which.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace heatcvt {

/// Stiffness and lumped mass of a surface (paper eq. 5–6).
/// \note Sign convention of the paper: `L` is symmetric NEGATIVE semi-definite,
///       `(L u)_i = 1/2 Σ_j (cot α_ij + cot β_ij)(u_j − u_i)`, and `L·1 = 0`.
struct Laplacian {
  Eigen::SparseMatrix<double> L;  ///< #V by #V stiffness, symmetric, L·1 = 0
  Eigen::VectorXd M;              ///< #V lumped (diagonal) mass, M_ii = 1/3 Σ area of faces at i; > 0
  double mean_edge_length = 0;    ///< h̄ of the underlying triangulation (sets the default t = h̄²)
  std::vector<int> degenerate_faces;  ///< faces with (near) zero area or non-finite angles, skipped
  int num_vertices() const { return static_cast<int>(M.size()); }
};

/// Options of cotan_laplacian().
struct CotanOptions {
  /// Relative area below which a face counts as degenerate: area < eps · h̄². Default 1e-12.
  double degenerate_area_epsilon = 1e-12;
  /// Cotangents are clamped to cot_clamp so needles never produce inf; a face with a corner whose
  /// cotangent is below −cot_clamp (an angle within 1/cot_clamp radians of 180°: its corners are
  /// collinear to rounding) counts as degenerate. Default 1e5.
  double cot_clamp = 1e5;
  /// Mass given to vertices whose incident faces are all degenerate or that are isolated,
  /// as a fraction of the mean vertex mass, so that M stays positive. Default 1e-6.
  double min_mass_fraction = 1e-6;
};

/// Cotan Laplacian and lumped mass of a triangle mesh (paper eq. 5–6).
///   V  #V by 3 positions, F  #F by 3 indices.
/// Works on boundaries, several components, non-manifold edges; degenerate faces are
/// skipped and listed in `degenerate_faces`; the matrices never contain NaN or inf.
/// \throw InvalidInputError on empty F, out-of-range indices, NaN/inf coordinates.
Laplacian cotan_laplacian(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                          const CotanOptions& options = {});

/// Same from per-face edge lengths only (intrinsic): `lengths(f,k)` is the length of the edge
/// opposite corner k of face f. Used for the anisotropic lift to R⁶ (paper §7.1), where only
/// edge lengths of the lifted mesh are known.
Laplacian cotan_laplacian_from_lengths(const Eigen::MatrixX3d& lengths, const Eigen::MatrixX3i& F,
                                       int num_vertices, const CotanOptions& options = {});

/// Per-face edge lengths (`lengths(f,k)` opposite corner k) of an embedding of any dimension.
Eigen::MatrixX3d face_edge_lengths(const Eigen::MatrixXd& X, const Eigen::MatrixX3i& F);

}  // namespace heatcvt
