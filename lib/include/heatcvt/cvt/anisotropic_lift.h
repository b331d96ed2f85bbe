#pragma once
/// \file cvt/anisotropic_lift.h
/// The lift of the anisotropic CVT (paper §7.1, Fig. 9): each point p with unit normal n becomes
/// (p, λ n) ∈ R⁶, and the cotan Laplacian is built from the lifted edge lengths of the
/// triangles. Used by the mesh path (anisotropic_laplacian(), cvt.h) and by the point path
/// (a point cloud with its normals and the point Laplacian's triangles).
#include <Eigen/Core>

#include "heatcvt/laplacian.h"

namespace heatcvt {

/// Cotan Laplacian of the triangles T over the lifted points (P, λ N):
///   P #P by 3 positions, N #P by 3 unit normals, T #T by 3 triangles (indices into P).
/// `lifted_face_area` (optional) receives the #T lifted triangle areas (Heron's formula in its
/// stable form), to be passed to centroidal_voronoi() as face_metric_area. No rescaling: callers
/// that want λ relative to the shape's size scale P first (anisotropic_laplacian() does).
/// \throw InvalidInputError on mismatched sizes, an index out of range or λ < 0 / non-finite.
Laplacian lifted_laplacian(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixX3i& T,
                           double lambda, Eigen::VectorXd* lifted_face_area = nullptr);

}  // namespace heatcvt
