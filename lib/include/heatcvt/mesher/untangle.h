#pragma once
/// \file untangle.h
/// Removing self-intersections: the faces involved are cut out and the holes refilled.
#include "heatcvt/mesher/border_growth.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/mesher_stats.h"

namespace heatcvt {

/// Options of untangle().
struct UntangleOptions {
  /// Rounds of "remove the intersecting faces (from the second round on also every face at one
  /// of their vertices), make manifold, refill holes", until no intersection is left. Default 4.
  int rounds = 4;
  /// After each removal the borders regrow over the sites it left out (grow_borders(), which adds
  /// no intersecting triangle) before the holes are refilled.
  BorderGrowthOptions regrow;
};

/// Untangles the mesh as above; holes are refilled by fill_holes() with `holes`. Faces still
/// crossing after the last round are removed without refilling.
/// Counts removed faces and filled holes in `stats`.
void untangle(WorkingMesh& mesh, const SurfaceProjector& surface, const UntangleOptions& options,
              const HoleFillingOptions& holes, const ManifoldOptions& manifold, MesherStats& stats);

}  // namespace heatcvt
