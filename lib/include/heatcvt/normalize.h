#pragma once
/// \file normalize.h
/// Coordinate normalisation: every computation runs on positions centred at the origin with a
/// unit bounding-box diagonal, so that results do not depend on the units or the placement of the
/// input (millimetres, metres, UTM coordinates give the same mesh up to scale). The entry points
/// (tools, reconstruct_surface, NaturalNeighbourCoordinates, remesh_cvt) apply the frame to their
/// input and restore it on their positional output.
#include <Eigen/Core>

namespace heatcvt {

/// Similarity frame: normalized = (original − centre) / scale.
struct NormalizationFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double scale = 1.0;  ///< > 0 and finite
};

/// Frame of a point set: centre = bounding-box centre, scale = bounding-box diagonal (1 if the
/// diagonal is zero). Computed without overflow for coordinates up to the double range.
/// \throw InvalidInputError for an empty or non-finite point set, or a diagonal beyond the
///        double range.
NormalizationFrame bounding_box_frame(const Eigen::MatrixX3d& P);

/// Applies the frame: V ← (V − centre) / scale (rows are points).
void apply_frame(Eigen::MatrixX3d& V, const NormalizationFrame& frame);

/// Undoes the frame: V ← V · scale + centre, e.g. to write a mesh built on normalized positions
/// back in the original coordinates.
void restore_frame(Eigen::MatrixX3d& V, const NormalizationFrame& frame);

/// Moves V into its bounding_box_frame (bounding box centred at the origin, diagonal 1) and
/// returns the frame. \throw InvalidInputError as bounding_box_frame.
NormalizationFrame normalize_positions(Eigen::MatrixX3d& V);

}  // namespace heatcvt
