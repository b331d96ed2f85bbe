#pragma once
/// \file hole_filling.h
/// Filling the holes the extraction leaves (cells whose dual triangles were rejected, tips of
/// thin parts) while keeping the real boundaries of open scans.
#include <vector>

#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/hole_sites.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Which boundary loops are holes to close.
///   automatic  loops the extraction leaves (at most max_hole_edges edges) and larger ones whose
///              inside is sampled or whose surroundings are (the tests below): scan holes are
///              closed where the surface around them continues, the border of an open scan stays.
///   fill       every simple loop of up to max_fill_edges edges: watertight output wherever the
///              cloud encloses a volume (3D printing, volumes).
///   keep       only loops whose inside is sampled (is the scanned surface): no invented
///              surface; every scan hole stays open (inspection). Where the surface's own
///              border is known (an input mesh), a loop around a piece of that border (the
///              border passes nearer the loop's centre than its farthest vertex: a hole of the
///              input, however small) is one of its boundaries and stays open.
enum class HolePolicy { automatic, fill, keep };

/// Options of fill_holes(). h is the mean edge length of a loop.
struct HoleFillingOptions {
  HolePolicy policy = HolePolicy::automatic;  ///< Default automatic.
  /// Where the surface's own border is known (SurfaceProjector::border_known(): an input mesh), a
  /// loop of at most max_fill_edges edges whose every vertex is farther than this·h from that
  /// border (every loop, on a closed surface) is a hole inside the surface, not one of its
  /// boundaries: filled under every policy (the surface is there). Default 1.
  double interior_hole_clearance = 1.0;
  /// Where the border of the samples is known instead (SurfaceProjector::distance_to_scan_edge():
  /// a cloud's points at the edge of what was scanned, in chains), a loop of at
  /// most max_fill_edges edges whose every vertex is farther than this·h from that border, and
  /// which is not the outer border of a piece seen from its sites' normals (LoopShape::
  /// outer_border: a fragment), is a hole the extraction left in sampled surface, not the edge
  /// of the scan: filled under every policy, and its fill stays even where it cuts through the
  /// mesh (it is untangled after).
  /// Default 2.
  double sample_border_clearance = 2.0;
  /// With HolePolicy::fill: the longest loop triangulated (the triangulation costs O(L³)). Default 600.
  int max_fill_edges = 600;
  /// Boundary loops of at most this many edges are holes of the extraction: filled (without
  /// the tests below when `fill_short_loops` is set). Default 8.
  int max_hole_edges = 8;
  /// Fill loops of at most max_hole_edges edges whatever the surface looks like there. Default
  /// true (a scan's own holes that small are gaps of the sampling); false keeps every real
  /// boundary of the projector's surface (an input mesh with holes): such loops are then filled
  /// only when the tests below find surface across them.
  bool fill_short_loops = true;
  /// Loops of up to this many times max_hole_edges edges are filled when their centre is more
  /// than `clearance`·h from every triangle yet within `sample_gap`·h of the sampled surface (a
  /// hole in sampled surface, not the border of a scan). Default 4.
  int sampled_hole_factor = 4;
  double clearance = 0.25;   ///< Default 0.25.
  double sample_gap = 0.5;   ///< Default 0.5.
  /// Loops of up to this many times max_hole_edges edges are filled when, for at least
  /// `surrounded_fraction` of their edges, the surface is sampled within `sample_gap` edge
  /// lengths of the point one edge length outward (in the plane of the edge's triangle): the
  /// surface continues beyond the loop (around the tip of a thin part only the edges facing the
  /// tip find it; across the border of an open scan none does). Default 8.
  int surrounded_hole_factor = 8;
  double surrounded_fraction = 0.3;  ///< Default 0.3.
  /// ... where an edge counts only when the surface found beyond it lies along the edge's own
  /// triangle: the absolute cosine between that triangle's normal and the surface normal there
  /// is at least this. Beyond the shadow an object casts on the floor of a scene, what is found
  /// is the object's silhouette, seen edge-on (about 90° from the floor); closing the shadow
  /// would put a floor under the object, through whatever of it touches the floor. Around the
  /// tip of a thin part the surface may turn by nearly as much within one edge length, so the
  /// bound is loose. Default 0.25 (75.5°).
  double surrounded_normal_agreement = 0.25;
  /// On a nearly closed surface (not open, below), loops of up to surrounded_hole_factor·
  /// max_hole_edges edges whose sites' normals cancel out (LoopShape::unknown: the open end of a
  /// tube, where the cells at the tip of a thin part gave no triangles) are filled when the sampled surface is met within `sample_gap`·h of the
  /// loop's axis, at most `tip_reach` loop radii beyond the loop on the side the fill faces: the
  /// tip is there, and the cap stands for it. Across the open border of a scan (the base of a
  /// bust, the rim of a cup) nothing is sampled beyond the loop. Default 2.
  double tip_reach = 2.0;
  /// A loop of more than max_hole_edges edges is filled only when its triangles face the way
  /// their corners' normals do: the area-weighted mean cosine between them is at least this.
  /// Closing the border of a piece of surface would add the piece's back side (mean cosine near
  /// −1). Smaller loops are gaps of the extraction, often at the tips of thin parts where the
  /// corners' normals point every way, and are not tested; nor is a loop whose fill closes its
  /// piece around a volume (below). Default −0.5 (a cap over the tip of a thin part, whose
  /// corners' normals lie across it, scores about 0).
  double min_fill_normal_agreement = -0.5;
  /// A fill closes its piece around a volume when the loop is the piece's only boundary and the
  /// closed piece encloses at least this times its area^(3/2) (a sphere: 0.094; two sides of a
  /// flat piece pressed together: about 0). Default 0.005.
  double min_closed_volume = 0.005;
  /// ... and, where the loop follows the border of a cloud's samples (half of its vertices within
  /// sample_border_clearance·h of it; not under HolePolicy::fill), when the fill's area is at most
  /// this fraction of the piece's: the cap of a closed object (the end of a tube, the base it
  /// stood on). One view of a ball or a can has a rim along the edge of the scan whose fill is
  /// half as large as what was seen or more (but not larger); closing it would stand for the
  /// unseen back. A fill larger than its piece (a ring of surface round a gap of the extraction,
  /// at coarse site counts) and a hole inside sampled surface are not limited. Default 0.25.
  double max_cap_area_fraction = 0.25;
  /// On an open surface (below), the fill of a loop longer than max_hole_edges that runs
  /// counter-clockwise seen from its sites' mean normal (LoopShape::outer_border: the border of a
  /// piece, as between the fragments of a cluttered scan) or whose projection crosses itself, and
  /// whose triangles cut through the mesh, is taken out again, leaving the loop open. Other fills
  /// (gaps of the extraction, caps over the tips of thin parts, the holes of a nearly closed
  /// surface) are kept and untangled after, and so is every fill under HolePolicy::fill.
  /// Default true.
  bool reject_intersecting_fills = true;
  /// The surface counts as open when more than this fraction of its edges are on its boundary.
  /// Default 0.05.
  double open_surface_fraction = 0.05;
  /// Rounds of "find loops, fill, make the vertices manifold again". Default 3.
  int passes = 3;
  /// Closing holes with the unused sites inside them (hole_sites.h). A loop of at most
  /// max_fill_edges edges that holds enough of them (HoleSiteOptions::sampled_fraction) is
  /// sampled surface and is closed under every policy.
  HoleSiteOptions sites;
};

/// Max-min-angle triangulation (dynamic programming over the polygon) of the loop of vertices
/// `loop` of `mesh`, avoiding diagonals that are already edges of the mesh. The triangles are
/// oriented against the loop's direction (a boundary loop followed along its faces' half-edges
/// is closed by triangles facing the same way as those faces). Returns false when no such
/// triangulation exists.
bool triangulate_loop(const WorkingMesh& mesh, const std::vector<int>& loop, std::vector<MeshFace>& out);

/// Boundary loops of the mesh (followed along the faces' half-edges) that are simple and that
/// the policy selects are triangulated; then make_vertices_manifold(). Returns the loops filled;
/// faces removed by make_vertices_manifold() are added to `removed`, and the edge count of each
/// filled loop to `filled_edges` if given.
int fill_holes(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& options,
               const ManifoldOptions& manifold, int& removed, std::vector<int>* filled_edges = nullptr);

}  // namespace heatcvt
