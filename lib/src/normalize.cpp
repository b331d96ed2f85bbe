// Coordinate normalisation to a centred, unit-diagonal bounding box.
#include "heatcvt/normalize.h"

#include <cmath>

#include "heatcvt/errors.h"

namespace heatcvt {

NormalizationFrame bounding_box_frame(const Eigen::MatrixX3d& P) {
  if (P.rows() == 0) throw InvalidInputError("empty point set");
  if (!P.allFinite()) throw InvalidInputError("non-finite coordinates");
  const Eigen::RowVector3d lo = P.colwise().minCoeff(), hi = P.colwise().maxCoeff();
  NormalizationFrame frame;
  // Halves first: hi − lo and hi + lo may overflow near the ends of the double range.
  frame.centre = (0.5 * lo + 0.5 * hi).transpose();
  const double diag = 2.0 * (0.5 * hi - 0.5 * lo).stableNorm();
  if (!std::isfinite(diag)) throw InvalidInputError("the coordinates span more than the double range");
  frame.scale = diag > 0 ? diag : 1.0;
  return frame;
}

void apply_frame(Eigen::MatrixX3d& V, const NormalizationFrame& frame) {
  V = (V.rowwise() - frame.centre.transpose()) / frame.scale;
}

void restore_frame(Eigen::MatrixX3d& V, const NormalizationFrame& frame) {
  V = (V * frame.scale).rowwise() + frame.centre.transpose();
}

NormalizationFrame normalize_positions(Eigen::MatrixX3d& V) {
  const NormalizationFrame frame = bounding_box_frame(V);
  apply_frame(V, frame);
  return frame;
}

}  // namespace heatcvt
