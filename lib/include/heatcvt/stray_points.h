#pragma once
/// \file stray_points.h
/// Stray points of a cloud: single points and small groups far from the sampled surface (dust,
/// reflections, ghost returns, a mis-registered scrap). Left in, each one gets kNN neighbours on
/// the surface that are far away, the point Laplacian gets triangles spanning the gap, and the
/// CVT spends sites on those triangles: the mesh reaches out of the data towards the stray point.
///
/// The rule is local, so it does not depend on how density varies over the cloud (lidar density
/// falls with range): r_i = distance from point i to its k-th nearest neighbour; point i is stray
/// when r_i > `ratio` × the median of r_j over its k neighbours j. On a surface, a curve (a wire,
/// a pole) or at a scan's border the neighbours are sampled like the point and the quotient is
/// about 1–2; a group of fewer than about k/2 points far from the rest has most of its neighbours
/// on the surface, whose r_j are small.
#include <Eigen/Core>

#include <vector>

namespace heatcvt {

/// Options of the stray-point rule (see the file comment).
struct StrayPointOptions {
  /// k: neighbours compared. Groups of fewer than about k/2 points far from the rest are stray.
  /// Default 16.
  int neighbours = 16;
  /// A point is stray when its k-th neighbour is more than this times farther than the median
  /// of the same distance over its neighbours. 0 turns the rule off. Default 8.
  double ratio = 8;
  bool enabled() const { return ratio > 0; }
};

/// \throw InvalidInputError on neighbours < 2, a negative or non-finite ratio, or 0 < ratio <= 1.
void check_stray_point_options(const StrayPointOptions& options);

/// 1 for the stray points of P (all zeros when the rule is off or P has at most `neighbours`
/// points). Deterministic for any `threads` (0 = all cores).
/// \throw InvalidInputError on bad options or a non-finite coordinate.
std::vector<char> stray_point_mask(const Eigen::MatrixX3d& P, const StrayPointOptions& options = {}, int threads = 0);

}  // namespace heatcvt
