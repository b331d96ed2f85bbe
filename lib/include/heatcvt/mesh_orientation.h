#pragma once
/// \file mesh_orientation.h
/// Consistent orientation of an edge-manifold triangle mesh whose faces were written with mixed
/// orientations (a common defect of exported CAD and STL meshes).
#include <Eigen/Core>

namespace heatcvt {

/// Reverses faces of F so that every interior edge is traversed once in each direction. Each
/// edge-connected piece keeps the orientation of the larger share of its faces (ties: the
/// orientation of its first face in F), so a mesh with a few flipped faces keeps the user's
/// orientation. Returns the number of faces reversed, or −1 (F unchanged) where the mesh has an
/// edge with more than two faces or a piece admits no consistent orientation (a Möbius strip,
/// a Klein bottle).
int orient_faces_consistently(Eigen::MatrixX3i& F);

}  // namespace heatcvt
