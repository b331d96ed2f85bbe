#pragma once
/// \file edge_split.h
/// Splits of the long edges of remaining slivers (a filled hole at a thin tip spans several cell
/// widths).
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/projector.h"

namespace heatcvt {

/// Options of split_long_edges().
struct EdgeSplitOptions {
  double sliver_angle_deg = 25;  ///< a sliver has a smallest angle below this. Default 25°.
  /// A sliver's longest edge is split when longer than this times the mean edge length. Default 1.5.
  double length_factor = 1.5;
  int passes = 3;       ///< split passes per attempt. Default 3.
  int attempts = 4;     ///< attempts, each leaving out the splits that self-intersected. Default 4.
  int polish_rounds = 4;  ///< angle_polish() rounds on the new vertices and their neighbours. Default 4.
  FlipOptions flips;    ///< max-min-angle flips around the new vertices (valence_mode ignored)
  AnglePolishOptions angle;
  int threads = 0;      ///< 0 = all cores; results do not depend on it. Default 0.
  /// Splits stop once the mesh has this many vertices in faces (the vertex budget of the
  /// caller, e.g. cloud2mesh's -n plus 2 %); 0 = no limit. Default 0.
  int max_vertices = 0;
};

/// Each sliver's longest edge, if long and interior, is split at its midpoint projected to the
/// surface (both triangles halved), then max-min-angle flips and an angle polish of the new
/// vertices and their neighbours. When the result self-intersects, the splits whose vertices are
/// in or next to an intersecting face are left out and the rest redone from the start; if none
/// is to blame the mesh is left as it was. Returns the edges split.
int split_long_edges(WorkingMesh& mesh, const SurfaceProjector& surface, const EdgeSplitOptions& options,
                     MesherStats& stats);

}  // namespace heatcvt
