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

/// Options of trim_boundary_slivers().
struct BoundaryTrimOptions {
  bool enabled = true;           ///< Default true.
  double sliver_angle_deg = 25;  ///< a sliver has a smallest angle below this. Default 25°.
  /// The sliver lies flat along the border: its angle opposite its boundary edge is at least
  /// this (its height is then at most tan(90° − apex/2) / 2 ≈ 0.29 of that edge). Default 120°.
  double min_apex_angle_deg = 120;
  int passes = 1;                ///< Default 1 (each pass exposes new border triangles: more passes eat into the surface).
  /// Also cut such a sliver where its apex is on the border too: the surface is one triangle wide
  /// there (a ribbon or a neck narrower than the site spacing, which no vertex move can open); the
  /// apex keeps its largest fan of faces and the others go. Default true.
  bool cut_necks = true;
  /// Also cut a spike of the border: a border vertex with two faces, a sliver among them, whose
  /// surface angle is below this and whose inner edge goes to an interior vertex. Below twice the
  /// sliver angle the two faces cannot both meet it there, a flip would leave a lone ear (and is
  /// impossible where the pair is concave at the interior vertex): both faces go and the interior
  /// vertex becomes the border's. 0 = never. Default 50°.
  double spike_angle_deg = 50;
};

/// Options of flip_sliver_edges().
struct SliverFlipOptions {
  double sliver_angle_deg = 25;  ///< a sliver has a smallest angle below this. Default 25°.
  /// The new edge's midpoint may lie this far from the surface, times the edge's length (or as
  /// far as the old edge's midpoint). Default 0.25.
  double max_offset = 0.25;
};

/// An edge collapse the rules allow (collapse_topology()): `gone` goes into `kept`; `shared` are
/// the faces on the edge (they go), `others` the other faces of `gone` (they take `kept` instead).
struct EdgeCollapse {
  int kept = -1, gone = -1;
  bool border_edge = false;  ///< the edge has one face
  bool keep_place = false;   ///< an interior vertex goes into a border one, which keeps its place
  std::vector<int> shared, others;
};

/// Whether edge (a, b) may be collapsed, and how: an inner edge between two border vertices
/// never (it would pinch the surface); a border edge only between two simple border vertices
/// (the border loses a vertex and keeps its course); a border vertex takes in an interior one and
/// keeps its place; the link condition holds (the ends share exactly the opposite vertices of the
/// edge's faces), those keep valence ≥ 4, and the two ends have at least 7 faces between them (4
/// on a border edge). `vf`: the faces at each vertex, current for a, b and their faces; `links`:
/// the border.
bool collapse_topology(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, const BorderLinks& links,
                       int a, int b, EdgeCollapse& collapse);

/// Distance from the midpoint of (a, b) to its projection on the surface (infinite where it has
/// none): how far an edge strays from the surface, e.g. across a gap.
double midpoint_offset(const WorkingMesh& mesh, const SurfaceProjector& surface, int a, int b);

/// Flips the inner edges (a, b) of slivers into (c, d) where the pair bends over a crease or a
/// fold, so that the flat-pair rules of flip_edges() refuse it: the pair's smallest angle grows,
/// the new edge's midpoint lies on the surface (within max_offset of its length, or no farther
/// than the old edge's), each new triangle faces like its corners' normals, a and b keep valence
/// above 3, and no corner is `frozen`. Returns the flips.
int flip_sliver_edges(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverFlipOptions& options,
                      const std::vector<char>& frozen);

/// Removes the slivers that lie flat along the border, where the border of a scan turns between
/// sites and no vertex move can open them:
/// - one boundary edge, obtuse apex (at least min_apex_angle_deg) opposite it, every corner
///   keeping a face and the apex a single fan: the border moves onto the apex, by less than the
///   sliver's height, and no vertex is lost;
/// - the same where the apex is on the border as well (cut_necks): the apex keeps its largest fan,
///   the faces of its other fans go with the sliver (what is cut off a ribbon narrower than the
///   spacing is left as small pieces, which the caller removes);
/// - two boundary edges (an ear, whose lone corner is on both) where the other two corners keep
///   faces: the border moves onto the third edge, by less than the ear's longest edge, and the
///   lone corner leaves the mesh (a sliver ear is a spike or a notch of the border at the site
///   spacing: no vertex move opens it);
/// - a spike (spike_angle_deg): the border moves onto the spike's interior vertex, by less than
///   the spike's shorter side, and the spike's tip leaves the mesh.
/// Returns the faces removed.
int trim_boundary_slivers(WorkingMesh& mesh, const BoundaryTrimOptions& options);

/// In each pass, every sliver (faces visited in order, none sharing a vertex with an edited ring)
/// has its edges tried shortest first: an edge (a, b) is collapsed when it is a border edge
/// between two simple border vertices or an inner edge with at most one end on the border (an
/// interior vertex goes into a border one, which keeps its place), the link condition holds, the two opposite vertices keep valence ≥ 3, no ring triangle
/// turns more than max_normal_turn_deg and the ring's smallest angle improves; the merged vertex
/// goes to the best of the midpoint projected to the surface, a, or b. Undone as a whole when
/// the result has more self-intersecting face pairs than the input. Slivers with a `frozen`
/// corner (if given) are left alone and the flips keep off frozen vertices. Then the valence-3
/// vertices of remaining slivers are removed (undone if that self-intersects). Returns the edges
/// collapsed; flips are added to stats.
int collapse_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverCollapseOptions& options,
                     MesherStats& stats, const std::vector<char>* frozen = nullptr);

}  // namespace heatcvt
