#pragma once
/// \file edge_flips.h
/// Edge flips on a consistently oriented manifold mesh: max-min-angle (Delaunay-like) flips that
/// repair the diagonals the discrete labels got wrong, and valence-equalising flips
/// (Botsch–Kobbelt) for the polish.
#include <vector>

#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of flip_edges().
struct FlipOptions {
  int max_passes = 5;        ///< passes over the faces (stops earlier when one flips nothing). Default 5.
  /// false: flip when the smallest angle of the pair increases. true: flip when it brings the
  /// four valences closer to 6, on nearly flat pairs, keeping the pair's smallest angle above
  /// `valence_min_angle_deg` or improving it. Default false.
  bool valence_mode = false;
  double flat_dihedral_deg = 20;       ///< "nearly flat" for valence flips. Default 20°.
  double valence_min_angle_deg = 30;   ///< Default 30°.
  /// No flip whose new triangles deviate more than this from the old pair's mean normal (no folds).
  /// Default 30°.
  double max_normal_deviation_deg = 30;
};

/// Flips edges (a, b) of face pairs (a, b, c), (b, a, d) into (c, d) when (c, d) is not an edge
/// yet, a and b keep valence ≥ 3 and the rule of `options` holds; with `only_at`, only edges
/// with an end vertex v with (*only_at)[v]. Faces are visited in order, one flip per face per
/// pass. In valence mode the valences move towards 6, or towards (*target_valence)[v] when given
/// (the isotropic remesh asks fewer on a border). Returns the number of flips; `converged`
/// receives whether the last pass flipped nothing (every edge is then rejected by the rule).
/// With `dirty`, the call continues one that converged with the same options and `only_at`:
/// `dirty` marks every vertex that has moved or changed its faces since, and every vertex that
/// shares a face with one (moved_vertex_rings()). Edges with neither end dirty are not looked at
/// again until a flip reaches them; the flips are the same as without it.
/// With `faces`, only those faces are visited (in ascending order): the same flips as a full
/// scan where every face that can hold a flipped edge is listed. With `only_at`, a face gets
/// such an edge only through a flip of one of its own edges, so listing the faces at the
/// only_at vertices suffices.
/// The vertices moved since `before` (changes_since()) and those sharing a face with one: the
/// `dirty` marks of flip_edges() after a smoothing step.
std::vector<char> moved_vertex_rings(const WorkingMesh& mesh, const WorkingMesh::Checkpoint& before);

int flip_edges(WorkingMesh& mesh, const FlipOptions& options = {}, const std::vector<char>* only_at = nullptr,
               const std::vector<int>* target_valence = nullptr, const std::vector<char>* dirty = nullptr,
               bool* converged = nullptr, const std::vector<int>* faces = nullptr);

}  // namespace heatcvt
