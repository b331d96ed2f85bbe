#pragma once
/// \file vertex_attributes.h
/// Per-point attributes of a cloud carried to the vertices of a mesh reconstructed from it.
/// A reconstructed vertex lies on the surface fitted to the cloud, between input points; its
/// colour is interpolated from the nearest input points (Shepard's inverse-distance weighting),
/// so colour edges of the scan stay as sharp as the vertex spacing allows.
#include <Eigen/Core>

namespace heatcvt {

/// Options of transfer_colours().
struct ColourTransferOptions {
  int neighbors = 6;      ///< input points averaged per vertex. Default 6.
  double power = 2.0;     ///< weight 1 / distance^power (Shepard); a vertex on a point takes its colour. Default 2.
  int threads = 0;        ///< 0 = all hardware threads; the result does not depend on it. Default 0.
};

/// Colour of every vertex of V from the colours C of the cloud P (same frame):
/// c(v) = Σ_j w_j C_j / Σ_j w_j over the `neighbors` nearest points, w_j = 1 / |v − p_j|^power.
///   P #P by 3, C #P by 3 (any range; typically [0,1]), V #V by 3. Returns #V by 3.
/// \throw InvalidInputError if the sizes differ, P has fewer than 1 point, a coordinate is not
///        finite, neighbors < 1 or power < 0.
Eigen::MatrixX3d transfer_colours(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C, const Eigen::MatrixX3d& V,
                                  const ColourTransferOptions& options = {});

}  // namespace heatcvt
