#pragma once
/// \file border_growth.h
/// Growing the borders of the extracted surface over the sites left out next to them. Where the
/// dual is torn (cluttered scans: depth jumps, flying pixels, layered depth), the extraction
/// leaves pieces with sites in no triangle around and between them. Each border edge takes the
/// nearby site that makes the best-shaped triangle facing the way the surface does, as an
/// advancing front over the sites: pieces grow towards each other and close the gaps.
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of grow_borders().
struct BorderGrowthOptions {
  bool enabled = true;  ///< Default true.
  int passes = 8;       ///< front passes (each over every border edge). Default 8.
  /// Sites considered for a border edge: the nearest sites of its two ends. Default 12.
  int neighbors = 12;
  /// A new triangle's smallest angle is at least this. Default 20°.
  double min_angle_deg = 20;
  /// ... and its normal has more than this dot product with each corner's normal (the dual's
  /// coherence rule; a triangle across a depth jump stands on edge and fails it). Default 0.25.
  double min_normal_dot = 0.25;
  int threads = 0;  ///< kNN threads; 0 = all cores. Results do not depend on it. Default 0.
  /// Only an open surface grows: one with more than this fraction of its edges on a border
  /// (pieces of a cluttered scan). A nearly closed surface's gaps are left to the hole filling,
  /// whose triangulations keep the dual's shape. Default 0.05.
  double open_surface_fraction = 0.05;
};

/// Adds, pass by pass, for each border half-edge a→b (its face on the left) the triangle (b, a, s)
/// over the best nearby site s (largest smallest angle) that passes the tests above, keeps every
/// edge on at most two faces and every vertex on one fan. The triangles of a pass that
/// self-intersect the mesh are taken out again. Returns the triangles added.
int grow_borders(WorkingMesh& mesh, const BorderGrowthOptions& options);

}  // namespace heatcvt
