#pragma once
/// \file sample_border.h
/// The border of a sampled surface: the points of a cloud at the edge of what was scanned (the
/// border of a partial view, the rim of an occlusion shadow, the end of a scanned tube). A
/// closed object sampled all round has none. The hole filling tells a hole the extraction left
/// in sampled surface (no border nearby) from the border of the scan itself by them.
#include <Eigen/Core>
#include <vector>

namespace heatcvt {

/// Options of sample_border_points().
struct SampleBorderOptions {
  /// Nearest neighbours looked at around each point (the first ones of its kNN row, all of them
  /// when it is shorter). Default 30.
  int neighbors = 30;
  /// A point is on the border when the directions to its neighbours, projected to its tangent
  /// plane and sorted by angle around its normal, leave a gap wider than this (on one side there
  /// is no surface: 180° on a straight border). Default 120°: k directions spread at random (an
  /// unstructured or noisy sampling) leave a gap that wide with probability about k·(2/3)^(k−1),
  /// 2·10⁻⁴ at k = 30, where PCL's 90° would flag one interior point in five at k = 16.
  double max_gap_deg = 120;
  int threads = 0;  ///< 0 = all cores; the result does not depend on it. Default 0.
};

/// Whether each point of P (#P by 3, unit normals N, nearest neighbours `knn` nearest first as
/// k_nearest_neighbors() returns them) is on the border of the sampled surface.
/// \throw InvalidInputError when the shapes differ or `knn` has fewer than 3 columns.
std::vector<char> sample_border_points(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixXi& knn,
                                       const SampleBorderOptions& options = {});

}  // namespace heatcvt
