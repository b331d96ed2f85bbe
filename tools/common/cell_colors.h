#pragma once
// Distinct, deterministic colours for cell ids (golden-ratio hue steps), −1 → grey.
#include <Eigen/Core>

namespace heatcvt::cli {
/// #labels by 3 colours in [0,1].
Eigen::MatrixX3d cell_colors(const Eigen::VectorXi& labels);
}  // namespace heatcvt::cli
