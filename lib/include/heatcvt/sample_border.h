#pragma once
/// \file sample_border.h
/// The border of a sampled surface: the points of a cloud at the edge of what was scanned (the
/// border of a partial view, the rim of an occlusion shadow, the end of a scanned tube). A
/// closed object sampled all round has none. The hole filling tells a hole the extraction left
/// in sampled surface (no border nearby) from the border of the scan itself by them.
#include <Eigen/Core>
#include <vector>

#include "heatcvt/mesh.h"

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

/// The border points (`on_border`, as sample_border_points() gives them) that belong to a chain
/// of at least `min_points`: points with a gap linked through their first `neighbors` nearest
/// neighbours (`knn`, the table sample_border_points() read). The edge of a scan is a chain as
/// long as the edge, while chance leaves gaps round the voids of a random sampling (the rate of
/// SampleBorderOptions::max_gap_deg, per point) in clusters of a few points: on a closed cloud of
/// 10⁶ points a few hundred of them, spread all over the surface.
/// \throw InvalidInputError when the lengths differ.
std::vector<char> border_chains(const std::vector<char>& on_border, const Eigen::MatrixXi& knn, int neighbors,
                                int min_points);

/// How closely a mesh made from a cloud follows the border of the samples, in units of a length
/// (the mesh's site spacing): for each border point of the cloud, its distance to the mesh (an
/// inset or ragged mesh border leaves the scan's edge uncovered); for each border vertex of the
/// mesh, its distance to the nearest border point of the cloud (a border drawn in lies off the
/// edge). Each as the fraction of the points within the length and the `quantile` of the
/// distances. A mesh without faces or a cloud without border gives zero counts.
struct BorderFit {
  int edge_points = 0;            ///< border points of the cloud
  double edge_covered = 0;        ///< fraction of them within one length of the mesh
  double edge_distance = 0;       ///< the quantile of their distances to the mesh, in lengths
  int mesh_border_vertices = 0;   ///< vertices on a boundary edge of the mesh
  double mesh_border_on_edge = 0; ///< fraction of them within one length of a border point
  double mesh_border_distance = 0;///< the quantile of their distances to the border points, in lengths
};

/// BorderFit of `mesh` against the border points `border` of a cloud (sample_border_points()'s
/// rows), in units of `length` (> 0), at the `quantile` in [0, 1].
/// \throw InvalidInputError when `length` is not positive or `quantile` not in [0, 1].
BorderFit border_fit(const Eigen::MatrixX3d& border, const TriangleMesh& mesh, double length, double quantile = 0.9);

/// The same against the cloud P whose border points are flagged by `on_border`.
/// \throw InvalidInputError also when `on_border` and P differ in length.
BorderFit border_fit(const Eigen::MatrixX3d& P, const std::vector<char>& on_border, const TriangleMesh& mesh,
                     double length, double quantile = 0.9);

}  // namespace heatcvt
