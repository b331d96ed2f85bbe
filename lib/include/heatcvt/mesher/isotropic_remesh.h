#pragma once
/// \file isotropic_remesh.h
/// Sizing to the requested vertex count: isotropic remeshing of the working mesh on its surface
/// (Botsch & Kobbelt 2004: split long edges, collapse short ones, valence flips, tangential
/// relaxation, all projected to the SurfaceProjector), with borders resampled along their own
/// course. It runs where the dual left sites out (cluttered and partial scans, thin parts) or
/// the shape targets are not met, so the output has the vertex count asked for, spread over all
/// of the meshed surface in proportion to area (every piece gets its share), and the angle polish
/// that follows starts from near-equilateral triangles, on the border too.
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/cancellation.h"
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/sliver_collapse.h"
#include "heatcvt/mesher/sliver_repair.h"
#include "heatcvt/mesher/tips.h"
#include "heatcvt/mesher/working_mesh.h"

#include <Eigen/Core>
#include <cmath>
#include <functional>

namespace heatcvt {

/// Options of size_to_target().
struct IsotropicRemeshOptions {
  /// Vertices (in faces) asked for; 0 turns the stage off. The reconstruction and the remesher
  /// set it to their site count. Default 0.
  int target_vertices = 0;
  /// The count may be off by this fraction of the target. The stage aims at half of it: it runs
  /// when the vertex count is off by more than count_aim × count_tolerance (or the shape targets
  /// below are not met), and its count adjustment stops within that, so that the result ends
  /// inside the tolerance with room to spare. Defaults 0.02 (2 %) and 0.5.
  double count_tolerance = 0.02;
  double count_aim = 0.5;
  /// ... or the mesh's smallest angle is below this. Default 25°.
  double min_angle_deg = 25;
  /// ... or the mean of the triangles' smallest angles (φm) is below this. Default 52°.
  double mean_angle_deg = 52;
  /// Where the surface's own border is known (SurfaceProjector::has_border(): an input mesh's
  /// boundary), border vertices within this many target edge lengths of it are moved onto it
  /// after each relaxation and polish, so the output's border runs on the input's (farther
  /// ones border holes of the mesh itself). Default 3.
  double max_border_gap = 3.0;
  /// ... and the stage runs when such a vertex is farther than this many target edge lengths
  /// from it. Default 0.02.
  double border_tolerance = 0.02;
  /// ... or when the midpoint of a border edge between two such vertices is farther than this
  /// many target edge lengths from it: the edge cuts across a corner of the surface's border
  /// (a hole narrower than a few spacings left with too few border vertices). A straight edge
  /// of the target length on a circular border of radius r is off by 1/(8r) of them. Default 0.25.
  double border_chord_tolerance = 0.25;
  /// A result that brings the border onto the surface's own is kept even where φmin or φm end
  /// up to this much lower than before (or than their targets): the inset border's triangles
  /// were shaped for a border that is not the surface's. Default 1°.
  double border_fit_angle_slack_deg = 1.0;
  /// A mesh whose count is off by more than this fraction of the target is mostly missing
  /// (the dual left most sites out): a result nearer the count is kept even where φmin drops
  /// (φm may not). Default 0.25.
  double count_first_error = 0.25;
  /// ... and where such a result keeps φmin ≥ traded_min_angle_deg, its φm may be up to this
  /// much lower than before: a coarse dual of a scene (a room at 150 sites) that keeps 40 % of
  /// its sites is worse than a complete mesh with a slightly lower φm. Default 2°.
  double count_first_mean_slack_deg = 2.0;
  /// A result that meets more of the three targets (count within count_tolerance, φmin ≥
  /// min_angle_deg, φm ≥ mean_angle_deg) than the mesh before is kept even where it is worse
  /// on the other, as long as its φmin is at least this (and its border no farther from the
  /// surface's). Default 20°.
  double traded_min_angle_deg = 20;
  /// A mesh that meets the shape targets and whose count is off by at most this fraction of the
  /// target only has its count adjusted (no remeshing rounds). Default 0.05.
  double reshape_count_error = 0.05;
  /// The target edge length at a point of the surface as a multiple of the uniform one
  /// (adaptive_sizing.h: SizingField); empty = uniform. Where given, edges are split, collapsed
  /// and ordered by their length over this factor at their midpoint, and the uniform length is
  /// the one whose local lengths give the target count. Default empty.
  std::function<double(const Eigen::Vector3d&)> relative_size;
  /// Split, collapse, flip and relax rounds; the target edge length is corrected after each
  /// round by the ratio of the vertex count to the target. Default 8.
  int rounds = 8;
  /// An edge is split when longer than this times the target length. Default 4/3.
  double long_factor = 4.0 / 3.0;
  /// An edge is collapsed when shorter than this times the target length (and no edge of the
  /// collapsed ring becomes long). Default 4/5.
  double short_factor = 4.0 / 5.0;
  /// Where the count adjustment's collapses stall (every ring would get an edge longer than
  /// long_factor times the target length), that limit grows by 25 % per round up to this factor.
  /// Default 2.
  double max_collapse_growth = 2.0;
  /// A split is refused where the edge's midpoint projects farther than this times the edge's
  /// length from it (the edge spans a gap or a depth jump of the surface). Default 0.25.
  double max_split_offset = 0.25;
  /// Where the surface's border is known, a border edge is split at the point of that border
  /// nearest its midpoint (the new vertex stays on the border, and a chord across a corner of it
  /// gets a vertex at the corner), refused where that point is farther than this times the
  /// edge's length from the midpoint (half of it at a right-angled corner). Default 0.75.
  double max_border_split_offset = 0.75;
  /// remove_flying_faces(): faces whose centroid projects to the surface farther than this times
  /// their longest edge do not lie on it (they span a depth jump or the gap between two sheets:
  /// flying triangles). Default 0.25.
  double max_face_offset = 0.25;
  /// ... and whose normal is tilted from its corners' surface normals by more than this on
  /// average (it stands across the surface rather than along it). Default 60°.
  double min_flying_tilt_deg = 60;
  /// Whether the surface mesher calls remove_flying_faces() before size_to_target() (false where
  /// a watertight result is asked for: hole policy fill; and for an input mesh, whose faces are
  /// its surface). size_to_target() itself never removes them. Default true.
  bool remove_flying = true;
  /// A split or collapse is refused when a ring triangle would turn by more than this. Default 45°.
  double max_normal_turn_deg = 45;
  /// A border vertex where the border turns by more than this (it nearly turns back) is a corner:
  /// relaxation leaves it in place and collapses keep it; below it, border vertices move towards
  /// the middle of their border neighbours, which smooths a ragged border at the site spacing.
  /// Default 120°.
  double corner_turn_deg = 120;
  /// Where the surface's border is known (an input mesh's boundary), a border vertex where the
  /// border turns by more than this and whose two border edges run along the surface's border
  /// (midpoints within border_chord_tolerance) sits at a corner of it: kept in place like the
  /// corners above. Default 60°.
  double known_border_corner_turn_deg = 60;
  /// In the relaxation, border vertices near the edge of the samples follow it
  /// (RelaxationBorder::follow_sample_border); an input mesh has no such edge. Default true.
  bool follow_sample_border = true;
  /// The topology to keep (an input mesh's, for its remesh): a step that breaks it
  /// (breaks_topology(): the mesh had it and loses it, or a real hole is closed or joined to
  /// another) is undone and retried with the region of a lost loop frozen, like one that makes
  /// faces cross. Not enabled (a cloud: its border is the scan's edge, which the hole policy
  /// handles). Set by the surface mesher from SurfaceMesherOptions::keep_topology.
  TopologyTarget keep_topology;
  /// A border vertex with several faces whose surface angle (the sum of its face angles) is
  /// below this is a spike of the border (noise at the site spacing: each of its faces has a
  /// smaller angle there) and is collapsed into its nearer border neighbour. Default 60°.
  double spike_angle_deg = 60;
  /// A border vertex whose two border edges make an angle below this, with the surface around
  /// the rest (a notch or crack of the border at the site spacing), gets the face across the
  /// notch (a face on p–n where that edge is on the border already closes a three-edge hole).
  /// Default 60°.
  double notch_angle_deg = 60;
  /// Close the notches (false where no surface may be invented: hole policy keep). Default true.
  bool fill_notches = true;
  /// A face with a single border vertex of valence 2 (an ear on the border) whose angle there is
  /// below this is cut off when the border is cleaned (the border moves onto its opposite edge,
  /// by less than the face's height). Default 25°.
  double ear_angle_deg = 25;
  /// Rounds of max-min-angle flips + angle polish after the sizing. Default 6.
  int polish_cycles = 6;
  AnglePolishOptions angle;  ///< the angle polish of the last step
  /// Tips of thin parts in the mesh the sizing starts from (tip_vertices()) stay in place: not
  /// relaxed, not polished, no edge at them collapsed to reach the count or the edge length.
  /// The sliver passes below may still collapse an edge at a tip whose own triangles are
  /// slivers (a part thinner than the spacing can have no better ones).
  TipOptions tips;
  /// Slivers left after the polish: flipped over creases and folds, flat ones along the border
  /// and ears trimmed, the others collapsed; then the count is restored and the polish repeated.
  SliverFlipOptions sliver_flips;
  BoundaryTrimOptions border_slivers;
  SliverCollapseOptions slivers;
  /// The best local edit per sliver still left after the sliver passes, on the pass kept
  /// (repair_slivers()); its collapses may take the count down to the count tolerance.
  SliverRepairOptions repair;
  /// Slivers that repair leaves are then given, one at a time, the best edit that makes no faces
  /// cross (repair_slivers_without_crossings()): where an edit of the repair made faces cross,
  /// the whole repair is undone and its region frozen, so a sliver on the rim of a thin part
  /// (its two sides within an edge length) would otherwise stay as it is. Default true.
  bool repair_without_crossings = true;
  /// The faces of open pieces still below min_angle_deg after every repair are cut out
  /// (cut_unrepairable_slivers()): a part thinner than the spacing crumpled into faces whose
  /// every edit makes faces cross, or a strip bridging a gap between two surfaces, leaves a
  /// small hole instead of slivers. Where the count falls below count_tolerance, it is restored
  /// by splits polished locally; the cut is kept only where the count is then within
  /// count_tolerance, fewer faces are below min_angle_deg and φmin has not fallen. Never on a
  /// closed piece (but see max_cut_closed_fraction), nor on a surface whose border is known (an
  /// input mesh, which has no hole there), nor where a topology is kept or every hole is to be
  /// filled (hole policy fill: the surface mesher turns it off). Default true.
  bool cut_unrepairable = true;
  /// ... and a closed piece with fewer than this fraction of the mesh's vertices is cut like an
  /// open one: a part thinner than the spacing wrapped into a closed blob whose faces no edit
  /// can shape (a closed object of a scan carries more of the count). Default 0.05.
  double max_cut_closed_fraction = 0.05;
  /// Where the splits that restore the count after a cut leave slivers, the repairs and the cut
  /// run again, up to this many times. Default 2.
  int cut_rounds = 2;
  /// Times the trim, collapse, count restoration and polish are repeated while slivers are left
  /// (each polish can expose new flat border triangles or ears). Default 8.
  int sliver_passes = 8;
  /// Pieces the collapses cut off are removed as remove_small_pieces() does with these (the
  /// surface mesher sets them to its own min_piece_faces and min_piece_vertex_fraction).
  /// Defaults 20 and 0.01.
  int min_piece_faces = 20;
  double min_piece_vertex_fraction = 0.01;
  FlipOptions flips;         ///< flip rules (max_passes and valence_mode are set per call)
  int threads = 0;           ///< 0 = all cores; results do not depend on it. Default 0.
  /// Asked before each of the sizing's steps: where it returns true, size_to_target() stops with
  /// StagesCancelled (mesher/cancellation.h). Default none.
  CancelQuery cancelled;
};

/// Vertex count, shape and border of a mesh, as the sizing's targets measure them.
struct SizingFigures {
  /// Largest distance, in target edge lengths, from a border vertex to the surface's own border
  /// (among those within max_border_gap of it); 0 where the surface's border is not known.
  double border_gap = 0;
  /// Largest distance, in target edge lengths, from the midpoint of a border edge between two
  /// such vertices to the surface's own border; 0 where that border is not known.
  double border_chord_gap = 0;
  int vertices = 0;                         ///< vertices in faces
  double min_angle = M_PI, mean_angle = 0;  ///< φmin, φm (radians)
  double below = 0;  ///< fraction of the faces with a smallest angle below min_angle_deg
};
SizingFigures sizing_figures(const WorkingMesh& mesh, const SurfaceProjector& surface,
                             const IsotropicRemeshOptions& options);

/// Whether `after` is no worse than `before` on any target, the rule by which size_to_target()
/// keeps its result: the count is within count_tolerance or nearer; φmin meets its target if it
/// did, else the share of faces below it is no larger; φm meets its target or is no lower than
/// before (both less border_fit_angle_slack_deg where the border was brought onto the surface's
/// own; φmin not at all where the count was off by more than count_first_error, and then φm
/// count_first_mean_slack_deg less where φmin stays ≥ traded_min_angle_deg); the border is on
/// the surface's border within border_tolerance (its edges' midpoints within
/// border_chord_tolerance) or no farther off than before. Or: it meets more
/// of the three targets than before with φmin ≥ traded_min_angle_deg, the border no farther off.
bool sizing_no_worse(const SizingFigures& after, const SizingFigures& before, const IsotropicRemeshOptions& options);

/// The fewest vertices (in faces) a repair may leave: target_vertices less count_tolerance of it.
int count_floor(const IsotropicRemeshOptions& options);

/// Whether the mesh misses the targets of `options` (count, smallest angle, φm, border), i.e.
/// whether size_to_target() would work on it.
bool needs_sizing(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options);

/// Removes the faces of open pieces (pieces with a border) that do not lie on the surface: their
/// centroid projects farther than options.max_face_offset times their longest edge away and they
/// are tilted from their corners' normals by more than options.min_flying_tilt_deg (they span a
/// depth jump or the gap between two sheets); then, as make_vertices_manifold() does, the smaller
/// fans of the vertices left pinched and the edge-connected pieces of at most 4 faces. Returns
/// the faces removed.
int remove_flying_faces(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options);

/// Removes the faces of open pieces (pieces with a border) and of closed pieces with fewer than
/// options.max_cut_closed_fraction of the vertices whose smallest angle is below
/// options.min_angle_deg, then, as make_vertices_manifold() does, the smaller fans of the vertices
/// left pinched. Larger closed pieces keep every face. The faces left keep their angles, so no
/// face of the pieces cut is then below min_angle_deg. Returns the faces removed.
int cut_unrepairable_slivers(WorkingMesh& mesh, const IsotropicRemeshOptions& options);

/// Whether size_to_target() remeshes `mesh` (the shape targets are missed, or the count is off by
/// more than reshape_count_error) rather than only adjusting its count. The flying faces are
/// removed only then: a mesh of the right shape keeps every face (the hole fills included).
bool sizing_reshapes(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options);

/// Remeshes `mesh` on `surface` to options.target_vertices vertices when needs_sizing().
/// Where the shape targets are missed, the border is cleaned (notches closed, spikes collapsed,
/// ears cut) and the target edge length L comes from the mesh's area (V ≈ 2A / (√3 L²) for
/// equilateral triangles) for `rounds` of: edges longer than long_factor·L split at their midpoint
/// projected to the surface (border edges too), edges shorter than short_factor·L collapsed (link
/// condition; an interior vertex into a border one; never an inner edge between two border
/// vertices; border corners stay), valence flips towards 6 inside and towards 1 + (surface angle
/// / 60°) on the border, and tangential relaxation (border vertices towards the middle of their
/// border neighbours); the border is cleaned again. Then (and alone where the shape targets are
/// met and the count is off by at most reshape_count_error) the count is brought within
/// count_aim × count_tolerance of the target by splitting the longest or collapsing the shortest edges,
/// angle polish + max-min-angle flips follow, and the slivers left are flipped over creases,
/// the border's notches closed (fill_notches), slivers trimmed (flat along the border, ears,
/// spikes) or collapsed before the count is restored and polished once more, up to
/// sliver_passes times; the pass with the largest φmin is kept, and each sliver still left gets
/// the best of its local edits (repair_slivers()).
/// Faces keep a consistent orientation and the genus of each piece is kept (splits, collapses
/// with the link condition and flips do not change it; the border cleaning moves borders by less
/// than a face and may close a three-edge hole; pieces cut off by the sliver collapses are removed
/// as min_piece_faces and min_piece_vertex_fraction say); a step that makes faces cross is redone with the region around them frozen. The result
/// is kept only when it is no worse on any target (the count within the tolerance or nearer to
/// it; φmin at its target if it was, else no larger a share of faces below the target; φm at its
/// target or no lower than before). Where a count-only adjustment is worse, the whole remesh is
/// tried instead; otherwise the mesh is left as it was.
/// Returns whether the mesh was remeshed.
bool size_to_target(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options,
                    MesherStats& stats);

}  // namespace heatcvt
