#pragma once
/// \file neighbour_spread.h
/// How many nearest neighbours a point needs before they spread over the surface instead of
/// along a line. A rotating lidar samples a floor in rings (points a few centimetres apart along
/// a ring, rings up to metres apart), a line scanner in stripes: the k nearest neighbours of such
/// a point all lie on its own ring, so its PCA normal, its tangent-plane triangulation (the point
/// Laplacian) and its border test (a 180° gap on either side) see a curve, not a surface. The
/// neighbourhood size that spans the surface is measured on the cloud itself, so an isotropic
/// sampling keeps the default k and a ring scan gets what it needs.
#include <Eigen/Core>

namespace heatcvt {

/// Options of spanning_neighbours() and neighbours_for_spread().
struct NeighbourSpreadOptions {
  /// A neighbourhood spans the surface once the second eigenvalue of its covariance is at least
  /// this fraction of the largest (0 on a line; 1 on a disc; 0.28 on a half disc, the border of
  /// a scan). Default 0.05: the rows of a ring scan a quarter of the ring spacing apart.
  double min_spread = 0.05;
  /// The quantile, over the points examined, of the smallest spanning neighbourhood. Default
  /// 0.9: a wire or a pole (one in ten points or fewer) does not enlarge every neighbourhood.
  double quantile = 0.9;
  /// The neighbourhoods used hold this many times the spanning size: the spanning size reaches
  /// just across to the next ring on one side, while a tangent-plane triangulation and a border
  /// test need neighbours on both sides. An isotropic sampling spans at 8 points or fewer, so
  /// the default 30 neighbours stay. 0 turns the adjustment off. Default 2.
  double factor = 2.0;
  /// Points examined (evenly spaced in the input order; all of them below this). Default 4000.
  int samples = 4000;
  /// Largest neighbourhood looked at, and the largest returned. Default 200.
  int max_neighbors = 200;
};

/// The options.quantile of the smallest k (from 8) at which the k nearest neighbours of a point
/// of P (each examined point with itself) span the surface (NeighbourSpreadOptions::min_spread);
/// points whose max_neighbors neighbours never do count as max_neighbors + 1. Deterministic for
/// any `threads` (0 = all cores).
/// \throw InvalidInputError on a non-finite coordinate or invalid options.
int spanning_neighbours(const Eigen::MatrixX3d& P, const NeighbourSpreadOptions& options = {}, int threads = 0);

/// The neighbourhood size to use on P where `k` is asked for: max(k, min(max_neighbors,
/// ⌈factor · spanning_neighbours()⌉)), and at most #P − 1. `k` itself where factor is 0, where P
/// has too few points to look at, and where the neighbourhoods span the surface at the first size
/// looked at (8 points: an isotropic sampling, whatever `k`).
int neighbours_for_spread(const Eigen::MatrixX3d& P, int k, const NeighbourSpreadOptions& options = {},
                          int threads = 0);

}  // namespace heatcvt
