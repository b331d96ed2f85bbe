#pragma once
/// \file sliver_repair.h
/// The last repair of the slivers the other stages leave: for each face whose smallest angle is
/// below a threshold, every local edit that could remove it is scored on the faces around it and
/// the best one is applied if it raises their smallest angle.
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

#include <vector>

namespace heatcvt {

/// Options of repair_slivers().
struct SliverRepairOptions {
  double sliver_angle_deg = 25;  ///< a sliver has a smallest angle below this. Default 25°.
  /// Passes over the slivers (each edits faces that share no vertex, then looks again). Default 6.
  int passes = 6;
  /// An edited face must face within this of each of its corners' surface normals, or (the
  /// surface's normals are noisy on scans, and may be flipped on a patch) turn by at most this
  /// against the face it replaces and face against no more corner normals than it did: no edit
  /// folds the mesh. A moved vertex keeps its normal where the surface's normal at its new place
  /// turns by more than this. Default 60°.
  double max_normal_turn_deg = 60;
  /// A corner normal within this of a face's plane counts as faced against before an edit and as
  /// faced along after it (a normal lying in the plane does not decide). Default 6°.
  double side_margin_deg = 6;
  /// A border face is cut off only where its height over its border edge is at most this times
  /// the mesh's mean edge length (the border moves by less than that), or where the midpoint of
  /// that edge is farther than that from the surface (the face spans a gap). Default 0.5.
  double max_trim_height = 0.5;
  /// A flip's new edge must have its midpoint within this times its length of the surface, or
  /// no farther than the old edge's midpoint. Default 0.25.
  double max_flip_offset = 0.25;
  /// Whether a simple border corner may slide along the chord between its border neighbours.
  /// Default true.
  bool move_border = true;
};

/// For each face with its smallest angle below options.sliver_angle_deg (smallest first, none
/// sharing a vertex with a face edited in the same pass, no corner `frozen`), the candidate
/// edits are:
/// - collapse of one of its edges into the midpoint projected to the surface or into one end
///   (link condition; an inner edge between two border vertices never; an interior vertex only
///   into a border one, which keeps its place; a border edge only between simple border
///   vertices);
/// - flip of one of its inner edges (the new edge not in the mesh yet, both ends of the old one
///   keeping valence above 3);
/// - move of one of its interior corners to the centroid of its neighbours, or half-way there,
///   projected to the surface;
/// - move of one of its simple border corners along the chord between its two border
///   neighbours to the chord's midpoint, or half-way there, projected to the surface (only along
///   the border, which keeps its course: where scans overlap, a move across the border could
///   take the vertex onto the other scan's layer);
/// - for a face on the border, cutting it off (its corners keep faces and stay manifold; its
///   height over the border edge at most max_trim_height mean edges, or the midpoint of that
///   edge farther than that from the surface).
/// Each edit is scored by the smallest angle of the faces around the face's corners after it;
/// the best is applied when that beats the smallest angle there before, no edited face folds
/// (max_normal_turn_deg) and the mesh keeps at least `min_vertices` vertices in faces.
/// Faces keep a consistent orientation; the genus is kept (collapses under the link condition,
/// flips and moves do not change it; a cut face takes at most one border vertex with it).
/// Self-intersections are not checked here: the caller undoes what makes faces cross.
/// Returns the edits applied.
int repair_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverRepairOptions& options,
                   const std::vector<char>& frozen, int min_vertices);

/// The same edits one at a time, each checked for crossings: for the slivers smallest first, the
/// candidate edits that raise the smallest angle around the sliver are made best first, and the
/// first that adds no intersecting face pair to `pairs` (the mesh's pairs now,
/// crossing_face_pairs(); crossing_face_pairs_after() checks only the faces the edit made or
/// moved) is kept; then the slivers are looked for again. Where the best edit makes faces cross
/// (the two sides of a thin part within an edge length), the next best is kept instead, so the
/// sliver is not left as it was. At most options.passes edits per sliver found at the start.
/// Returns the edits kept.
int repair_slivers_without_crossings(WorkingMesh& mesh, const SurfaceProjector& surface,
                                     const SliverRepairOptions& options, const std::vector<char>& frozen,
                                     int min_vertices, std::vector<FacePair> pairs);

}  // namespace heatcvt
