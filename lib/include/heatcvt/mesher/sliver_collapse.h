#pragma once
/// \file sliver_collapse.h
/// Collapse of short edges of slivers the polish could not reach (filled holes at thin tips,
/// frozen vertices).
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/valence3_removal.h"

namespace heatcvt {

/// Options of collapse_slivers().
struct SliverCollapseOptions {
  double sliver_angle_deg = 25;  ///< a sliver has a smallest angle below this. Default 25°.
  int passes = 6;                ///< collapse passes (each followed by flips). Default 6.
  /// No triangle of the new ring may turn by more than this against its old normal. Default 60°.
  double max_normal_turn_deg = 60;
  FlipOptions flips;             ///< max-min-angle flips after each pass (valence_mode ignored)
  Valence3Options valence3;
};

/// In each pass, every sliver away from the boundary (faces visited in order, none sharing a
/// vertex with an edited ring) has its edges tried shortest first: an edge (a, b) is collapsed
/// when the link condition holds, the two opposite vertices keep valence ≥ 3, no ring triangle
/// turns more than max_normal_turn_deg and the ring's smallest angle improves; the merged vertex
/// goes to the best of the midpoint projected to the surface, a, or b. Undone as a whole when
/// the result self-intersects. Then the valence-3 vertices of remaining slivers are removed
/// (undone if that self-intersects). Returns the edges collapsed; flips are added to stats.
int collapse_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverCollapseOptions& options,
                     MesherStats& stats);

}  // namespace heatcvt
