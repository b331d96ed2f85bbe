#pragma once
/// \file untangle.h
/// Removing self-intersections: the faces involved are cut out and the holes refilled.
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/mesher_stats.h"

namespace heatcvt {

/// Options of untangle().
struct UntangleOptions {
  /// Rounds of "remove the intersecting faces (from the second round on also every face at one
  /// of their vertices), make manifold, refill holes", until no intersection is left. Default 4.
  int rounds = 4;
};

/// Untangles the mesh as above; holes are refilled by fill_holes() with `holes`.
/// Counts removed faces and filled holes in `stats`.
void untangle(WorkingMesh& mesh, const SurfaceProjector& surface, const UntangleOptions& options,
              const HoleFillingOptions& holes, const ManifoldOptions& manifold, MesherStats& stats);

}  // namespace heatcvt
