#pragma once
/// \file angle_polish.h
/// Angle polish: vertices moved within their tangent plane to maximise the smallest angle of
/// their one-ring, projected back to the surface.
#include <vector>

#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of angle_polish().
struct AnglePolishOptions {
  /// A ring's smallest angle counts only up to this cap; above it the sum of the ring's smallest
  /// angles (what φm averages) decides. Default 35°.
  double angle_cap_deg = 35;
  double initial_step = 0.1;   ///< pattern-search step, times the ring's mean edge length. Default 0.1.
  double final_step = 0.005;   ///< search stops below this step (times mean edge). Default 0.005.
  int max_search_steps = 24;   ///< Default 24.
  /// Boundary vertices move too, along the chord of their two boundary neighbours (so boundary
  /// triangles are polished like interior ones and the border keeps its course). Default true.
  bool boundary = true;
  /// ... but only where the border turns by at most this much at the vertex. Default 30°.
  double max_boundary_turn_deg = 30;
  /// A boundary vertex near the border of the samples (the edge of an open scan: border points
  /// within its ring's mean edge length, SurfaceProjector::sample_border_mean()) searches in
  /// every direction, like an interior one, wherever the border turns, but only among positions
  /// within this many mean edge lengths of the samples' border (or no farther from it than it
  /// is): its triangles are shaped as well as interior ones while the border stays on the scan's
  /// edge. 0 = such vertices move along their border chord like the others. Default 1 (the
  /// site spacing: the border stays within one spacing of the scan's edge).
  double sample_border_band = 1.0;
  /// ... and no farther out than this many mean edge lengths beyond the averaged edge (the line
  /// along the vertex's border chord through the mean of those border points): the band does
  /// not reach out beyond the scan, while a ragged edge leaves the vertex some room. Default 0.25.
  double sample_border_overshoot = 0.25;
};

/// Gauss–Seidel rounds over the vertices in a fixed colouring (a greedy colouring of the vertex
/// graph in index order; the vertices of one colour move in parallel, so the result does not
/// depend on the thread count). Each interior vertex not `frozen` is moved by an 8-direction
/// pattern search from the ring's area-weighted centroid and its position, in its tangent plane
/// (a boundary vertex by a 2-direction search along its border, options.boundary, or within a
/// band along the samples' border, options.sample_border_band);
/// the target is projected to the surface and kept only if, measured in 3D, (ring min capped,
/// ring sum) improves and no ring triangle turns against the vertex normal. Stops after `rounds`
/// or a round without moves. Returns the moves kept.
///
/// A search depends only on the vertex's ring (its faces, their corners' positions), its normal
/// and its projector hint, which a rejected move leaves as they were. So a vertex whose last
/// search kept no move is passed over until a vertex of its ring moves: the result is the same
/// as searching again. `settled` (optional, #V entries) carries these marks between calls: on
/// entry, vertices marked 1 are passed over until their ring changes; on return, it marks the
/// vertices whose last search kept no move and whose ring has not moved since. A caller that
/// changes faces between calls (flips) clears the marks of those faces' corners
/// (unsettle_changed_faces()); without `settled` every vertex is searched in the first round.
int angle_polish(WorkingMesh& mesh, const SurfaceProjector& surface, int rounds, const std::vector<char>& frozen,
                 const AnglePolishOptions& options = {}, int threads = 0, std::vector<char>* settled = nullptr);

/// Clears the `settled` marks (see angle_polish()) of the corners of every face of `mesh` that
/// differs from `before` (the faces before a change that kept their number and vertices, such as
/// edge flips), old corners and new; clears every mark when the numbers differ.
void unsettle_changed_faces(const std::vector<MeshFace>& before, const WorkingMesh& mesh, std::vector<char>& settled);

/// Clears the `settled` marks (see angle_polish()), valid for the state `before`, wherever `mesh`
/// has changed since: at the vertices moved or added, or with another normal or projector hint,
/// at the vertices sharing a face with one, and at the corners of faces made or removed (any
/// edit: flips, splits, collapses, removals). The marks are resized to the vertex count. A
/// polish with the marks so cleared moves the same vertices as one that searches every vertex.
void unsettle_changes_since(const WorkingMesh::Checkpoint& before, const WorkingMesh& mesh, std::vector<char>& settled);

}  // namespace heatcvt
