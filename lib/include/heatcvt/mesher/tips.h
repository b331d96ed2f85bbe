#pragma once
/// \file tips.h
/// Tips of thin parts: vertices where the mesh turns sharply in every direction (the end of a
/// finger, a claw, a tail or an ear), found by their angle defect 2π − Σ corner angles (the
/// discrete Gaussian curvature). A tip carries a large share of a cap's 2π of total curvature
/// in one vertex; tangential relaxation and the angle polish pull such a vertex towards the
/// middle of its ring, which lies down the thin part, and valence-3 removal replaces it by the
/// triangle of its ring: either cuts the tip off (the one-sided distance from the surface to the
/// mesh grows by the tip's length).
#include <vector>

#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of tip_vertices().
struct TipOptions {
  /// A vertex whose angle defect exceeds this many degrees is a tip (0 = none is). On a smooth
  /// surface sampled at the vertex spacing the defect of a vertex is a few degrees; the caps of
  /// parts about one spacing thick put 120–250° into one vertex. Default 0 (off): on the dual of
  /// a noisy scan, vertices of large defect are as often noise that the polish should smooth
  /// (on the shared clouds at -n 500, holding them lowered φmin on 16 of 30); remesh_cvt() runs the
  /// stages a second time with it on where their first result falls short
  /// (RemeshOptions::tip_defect_deg).
  double min_defect_deg = 0;
};

/// Marks (1) the interior vertices of `mesh` (a closed fan of faces) whose angle defect exceeds
/// options.min_defect_deg; size mesh.num_vertices(). Border and unused vertices are not tips.
std::vector<char> tip_vertices(const WorkingMesh& mesh, const TipOptions& options = {});

}  // namespace heatcvt
