#pragma once
/// \file mesher_stats.h
/// What the post-CVT stages of the surface mesher did: counts shared by the stages (several
/// stages flip, remove or add faces) and the wall time of each stage.
#include <string>
#include <utility>
#include <vector>

namespace heatcvt {

/// Counters of the surface mesher's stages (ReconstructionResult carries the same figures).
struct MesherStats {
  int candidate_triangles = 0;  ///< dual candidates that span one sheet of the surface
  int rejected_triangles = 0;   ///< candidates not kept (non-manifold or orientation conflict)
  int removed_triangles = 0;    ///< kept, then removed (non-manifold vertices, small pieces, intersections)
  int star_triangles = 0;       ///< triangles of the sites' own stars added where the dual had none (star_candidates())
  int holes_filled = 0;         ///< boundary loops triangulated by fill_holes()
  std::vector<int> filled_hole_edges;  ///< edge count of each filled loop, in filling order
  int flipped_edges = 0;        ///< edge flips
  bool polish_fallback = false;      ///< the valence-flip polish self-intersected; redone with Delaunay flips only
  bool angle_polish_undone = false;  ///< the angle polish self-intersected and was undone
  int collapsed_edges = 0;      ///< edges of slivers collapsed
  int pieces_removed = 0;       ///< small or stray pieces removed at the end (remove_small_pieces())
  int border_triangles = 0;     ///< triangles added by growing the borders over unused sites (grow_borders())
  int trimmed_faces = 0;        ///< slivers flat along the border removed (trim_boundary_slivers())
  int split_edges = 0;          ///< long edges of slivers split
  int flying_faces = 0;         ///< faces off the surface (across depth jumps) removed by the sizing
  bool sized = false;           ///< the mesh was remeshed to the vertex count asked for (size_to_target())
  long crossing_after_sizing = 0;  ///< intersecting face pairs the sizing left, untangled after it
  int faces_turned_outward = 0; ///< faces of closed pieces reversed to face outward
  int unused_vertices = 0;      ///< vertices in no face (dropped by compaction)
  /// Wall time of each stage in pipeline order (name, seconds).
  std::vector<std::pair<std::string, double>> stage_seconds;
};

}  // namespace heatcvt
