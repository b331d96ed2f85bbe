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
///
/// Larger groups far from the rest are judged as a whole: the kNN graph's connected components
/// (points linked to their k neighbours) each cover an area, estimated as Σ r_i² over their points
/// (a disk of radius r_i holds k points), and the CVT spends sites on a component in proportion
/// to that area. A component holding a small share of the points but a far larger share of the
/// area (a scatter of ghost returns or a few points of a distant scrap, spread over metres) would
/// get sites that no sample supports: its mesh would be invented. Such sparse groups are stray too,
/// and so are components with fewer points than the point Laplacian's neighbourhoods hold: each of
/// their neighbourhoods would reach across the gap to the rest, and the Laplacian, the heat and the
/// dual would bridge it (a group of fewer than k + 1 points is not a component of the kNN graph:
/// the first rule is the one that finds it). The largest component is never stray: it is the rest.
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
  /// A kNN component with fewer than this fraction of the points is a sparse group (stray) when
  /// its share of the points is also below sparse_density_ratio × its share of the area (it is
  /// that much sparser than the cloud on average). 0 turns the group rule off (cloud2mesh
  /// --keep-small). Default 0.01, the mesher's smallest piece (min_piece_vertex_fraction).
  double sparse_group_fraction = 0.01;
  /// See sparse_group_fraction. Lidar density falls with the square of the range: 0.25 keeps a
  /// small group scanned from twice the cloud's typical range. Default 0.25.
  double sparse_density_ratio = 0.25;
  /// A kNN component with fewer points than this is stray. reconstruct_surface() raises it to
  /// its point Laplacian's `neighbors`. 0 turns the rule off. Default 30.
  int min_group_points = 30;
  bool enabled() const { return ratio > 0 || sparse_group_fraction > 0 || min_group_points > 0; }
};

/// \throw InvalidInputError on neighbours < 2, a negative or non-finite ratio, 0 < ratio <= 1,
/// sparse_group_fraction or sparse_density_ratio outside [0, 1], or a negative min_group_points.
void check_stray_point_options(const StrayPointOptions& options);

/// 1 for the stray points of P, single (ratio) or in small or sparse groups (min_group_points,
/// sparse_group_fraction); all zeros when the rules are off or P has at most `neighbours` points. Deterministic for any `threads` (0 = all cores).
/// \throw InvalidInputError on bad options or a non-finite coordinate.
std::vector<char> stray_point_mask(const Eigen::MatrixX3d& P, const StrayPointOptions& options = {}, int threads = 0);

}  // namespace heatcvt
