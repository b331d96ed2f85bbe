#pragma once
/// \file remesh.h
/// CVT remeshing of a triangle mesh in one call (paper §7.1): the pipeline of `meshcvt`.
///
///   remesh_cvt(mesh, options)
///     1. orient the input's faces consistently, describe the input surface
///        (topology, genus, orientability)                                    orient_faces_consistently(), describe_surface()
///     2. refine it to min_vertices_per_site vertices per site, slivers of
///        flat regions reshaped (the surface is unchanged)                     refine_surface(), midpoint_subdivide()
///     3. cotan Laplacian (or the anisotropic lifted one), and the relative
///        sizes of the adaptive sizing (curvature)                              laplacian.h, adaptive_sizing.h
///     4. heat CVT (Lloyd iteration, localized solves) and its dual            centroidal_voronoi()
///     5. closed-ball repair: while the dual is not a manifold, a new site in
///        every cell at a non-manifold spot and the CVT again from all sites  repair rounds below
///     6. the shared post-CVT stages on the dual with the input mesh as the
///        projector (manifold extraction, holes, untangle, polish, slivers)    mesh_dual_surface()
///     7. sharp creases of the input kept as lines of the result              recover_creases()
///     8. checks of the result (manifold, closed, genus, self-intersections)   validate_triangle_mesh()
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/adaptive_sizing.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/coverage_repair.h"
#include "heatcvt/mesher/creases.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/surface_mesher.h"
#include "heatcvt/surface_refinement.h"
#include "heatcvt/validate.h"

namespace heatcvt {

/// Topology of an input surface as remesh_cvt() checks its output against it.
struct SurfaceDescription {
  MeshTopology topology;
  int genus = -1;               ///< mesh_genus(); −1 when not an orientable manifold
  bool non_orientable = false;  ///< an edge manifold admitting no consistent orientation (Klein bottle, Möbius strip)
  double diagonal = 0;          ///< bounding-box diagonal of the vertices that faces use
  bool closed() const { return topology.boundary_edges == 0; }
  /// "genus 3", "non-orientable, Euler characteristic 0" or "genus undefined (not a manifold)".
  std::string genus_text() const;
};

/// Topology, genus and orientability of a triangle mesh (V #V by 3, F #F by 3). A non-orientable
/// input (Klein bottle, Möbius strip) is valid for the intrinsic method; its dual is then checked
/// as a non-orientable surface (ValidationOptions::allow_non_orientable) instead of failing the
/// orientation check. Only inputs with inconsistently oriented edges need that (costlier) test.
SurfaceDescription describe_surface(const TriangleMesh& mesh);

/// The angle defect above which a vertex of the dual of an input mesh is the tip of a thin part
/// (TipOptions::min_defect_deg) in remesh_cvt()'s second run of the post-CVT stages: 120°. On a smooth
/// surface at the site spacing a vertex's defect is a few degrees; the caps of parts about one
/// spacing thick put 120–250° into one vertex; the corners of a box put 90° each, and holding
/// those keeps a crease vertex off its line.
constexpr double kRemeshTipDefectDeg = 120;

/// Options of remesh_cvt(). Defaults are `meshcvt`'s (see its --help).
struct RemeshOptions {
  /// Options of the CVT; `cvt.sites` is the number of output vertices (any count ≥ 1: more than the
  /// input's vertices is an upsampling, served by refining the input). Default
  /// fast_cvt_options(1000) (meshcvt's defaults; CvtOptions{} is the paper's plain Lloyd).
  ///
  /// The CVT's quality stop asks only φm ≥ cvt.target_phi_mean_deg (target_phi_min_deg = 0): the
  /// φmin of the output is the post-CVT stages' work (sliver collapse and repair, angle polish).
  /// On bunny00_cgal at 10,000 sites, the heat iterations run for the dual's φmin lowered its φm
  /// from 52.5° (the surface-Lloyd start) to 50.2° and took most of the time.
  CvtOptions cvt = [] {
    CvtOptions c = fast_cvt_options(1000);
    c.target_phi_min_deg = 0;
    return c;
  }();
  /// λ of the anisotropic lift (p, λn) (paper §7.1, Fig. 9: 0.05); 0 = isotropic. Default 0.
  double anisotropy = 0.0;
  /// Curvature-adaptive sizing (adaptive_sizing.h): where adaptive.adaptivity > 0, relative sizes
  /// g are estimated on the input's own vertices (not its refinement) at the uniform site
  /// spacing (surface_sizing()), the CVT on the refined input runs with the
  /// density g⁻⁴ (smaller cells where the surface bends) and the post-CVT stages' sizing follows
  /// g (mesher.sizing.relative_size); the vertex count stays cvt.sites. The quality targets and
  /// the coverage rules keep their uniform spacing. Default uniform (adaptivity 0).
  AdaptiveSizingOptions adaptive;
  /// Refine the input, its surface unchanged, until it has at least this many vertices per site,
  /// so the heat diffusion resolves every cell; 0 = never refine (then cvt.sites ≤ #V is
  /// required). By midpoint subdivision (1-to-4: every triangle keeps its shape), except an
  /// oriented edge manifold with needles (needle_area_share), which refine_surface() refines
  /// (long edges split, flat pairs of faces flipped to Delaunay: `refinement`), reshaping the
  /// needles of CAD meshes, at any vertex count. Default 8. Measured with meshcvt's defaults on
  /// ../shared/data/meshes: spot, elephant and torus at 1,000 sites (2.3–2.9 vertices per site)
  /// end with φm 43.7–45.3° after heat iterations, once refined (9–12 per site) the start meets
  /// φm ≥ 51°, φmin ≥ 25° with no heat iteration; max_planck_decimated at 1,000 sites misses it at
  /// 5.3 per site and meets it at 21; knot1, fandisk, spot and torus meet it from 3.2–9.8.
  double min_vertices_per_site = 8.0;
  /// At most this many midpoint subdivisions (each multiplies #F by 4; they stop as soon as
  /// min_vertices_per_site is reached, so the cap only binds on inputs far coarser than the
  /// count: a 2-face square reaches about 10^6 vertices, 130,000 sites); 0 also turns
  /// refine_surface() off, which otherwise refines to min_vertices_per_site vertices per site
  /// whatever the input's count (a 12-face box reaches any count). Default 10.
  int max_refinement_levels = 10;
  /// The refinement stops before it would pass this many vertices (memory: the Laplacian and its
  /// factor grow with them), whatever min_vertices_per_site asks for; 4,000,000 is 8 per site for
  /// 500,000 sites. Default 4,000,000.
  int max_refined_vertices = 4000000;
  /// How the input is refined: by refine_surface() where it has needles (default), or always by
  /// midpoint subdivision (the triangles keep their shapes, needles included).
  enum class Refinement { splits_and_flips, midpoint };
  Refinement refinement_method = Refinement::splits_and_flips;
  /// An oriented edge manifold is refined by refine_surface(), at any vertex count, when more
  /// than this share of its area lies in needles, faces with an angle below needle_angle_deg: a
  /// CAD mesh's fans and strips (12–80 % on the CAD shapes of scripts/make_shapes.py; at most
  /// 0.4 % on the meshes of ../shared/data/meshes, which keep the midpoint subdivision: on them
  /// the splits and flips gained and lost about as often). Defaults 0.05 and 5°.
  double needle_area_share = 0.05;
  double needle_angle_deg = 5;
  /// The splits and flat flips of refine_surface() (its target_vertices is set from
  /// min_vertices_per_site). Defaults: split above 4/3 of the target
  /// edge length, flip where the faces' normals differ by less than 0.01°.
  SurfaceRefinementOptions refinement;
  /// Closed-ball repair: at most this many rounds of "a new site at the farthest point of every
  /// cell at a non-manifold spot of the dual (cells wrapping a thin part, touching themselves or
  /// split), the sites in no dual triangle (a cell enclosed by another) dropped, then the CVT
  /// again from these sites" while the dual is not a manifold (on inputs without non-manifold
  /// edges); each round also adds sites on the input's boundary loops that lack cells of their
  /// own (a loop needs three cells, a cell may touch one loop). 0 = off. Default 3.
  int repair_rounds = 3;
  /// Further rounds of the repair for the boundary loops alone, once the dual is a manifold or
  /// the repair_rounds are spent: sites on the loops that lack cells of their own, then the CVT
  /// without splits or heat iterations (the count grows only by the loops' sites); its
  /// surface-Lloyd iterations settle the sites, except in the last such round, which keeps them
  /// where they are put (a Lloyd step can draw a site off a loop again). Default 3.
  int loop_repair_rounds = 3;
  /// Heat Lloyd iterations of the CVT of a repair round, at most (its start from the previous
  /// sites plus the new ones is already near a CVT: the round is there to give every cell a
  /// site, the start's surface-Lloyd iterations settle them). Default 4.
  int repair_iterations = 4;
  /// Boundary loops of the input shorter than this many site spacings (sqrt(area / sites)) are
  /// holes below the resolution asked for: the repair gives them no cells of their own and the
  /// post-CVT stages may close them (the boundary_loops check still counts them, and its detail
  /// says how many are that short). Longer loops are kept. Default 1.
  double min_loop_spacings = 1.0;
  /// Sites added by the repair rounds, at most this fraction of cvt.sites in total. Default 0.1.
  double max_repair_fraction = 0.1;
  /// The post-CVT stages' result is kept only where it covers the input about as well as a dual
  /// that passes every check: the input vertex farthest from it is at most max_coverage_ratio times
  /// farther than from the dual, plus coverage_slack site spacings sqrt(area / sites) (a lost
  /// ear or a cavity capped by a hole fill is not). Defaults 1.5 and 0.25.
  double max_coverage_ratio = 1.5;
  double coverage_slack = 0.25;
  /// ... and, wherever the dual covers every input vertex within this many site spacings, so
  /// must the stages' result (the output reaches every part of the input within one spacing:
  /// the same bound as max_tip_run_gap's). Default 1.
  double max_coverage_spacings = 1.0;
  /// ... except where the dual's vertex count is off the sites asked for by more than this
  /// fraction (sites added to cells too big for thin parts: armadillo at 300 sites has a valid
  /// dual of 555 vertices) and the stages' result is within mesher.sizing.count_tolerance of it
  /// with the dual's components and Euler characteristic: that result is kept when it passes
  /// every check the dual passed, whatever its coverage (a coarser mesh covers thin parts
  /// less). Default 0.25.
  double far_count_error = 0.25;
  /// Where the post-CVT stages' result is refused (the dual is then the output), the CVT goes on
  /// from its sites with the φmin target raised to this (heat iterations until the dual's own
  /// φmin reaches it, or the CVT's stops), then the stages run again on the new dual. This second
  /// result is kept where it passes every check the first passed and meets every target of
  /// mesher.sizing the first meets (the count within count_tolerance, φmin ≥ min_angle_deg,
  /// φm ≥ mean_angle_deg), and then one more, or the same ones with a larger φmin.
  /// 0 = off. Default 25.
  double fallback_phi_min_deg = 25.0;
  /// Where the post-CVT stages' result is refused or misses a target of mesher.sizing, they run
  /// once more with the tips of thin parts held (vertices of the dual whose angle defect is above
  /// this, mesher/tips.h: not relaxed, polished, valence-3-removed or collapsed), and that result
  /// replaces the first where it is kept and better (the same rule as the fallback's). 0 = no
  /// second run. Default kRemeshTipDefectDeg (120°).
  double tip_defect_deg = kRemeshTipDefectDeg;
  /// Where that run does not replace the result or it still misses a target, the stages run a
  /// third time with the vertices of defect above this held (the same rule). At finer spacings
  /// the cap of a finger spreads its defect over several vertices, none above 120°: at 10,000
  /// sites the armadillo's fingertips and toes are cut off otherwise. 0 = no third run; there is
  /// none either where tip_defect_deg is 0 (no run with tips held at all). Default 40°.
  double tip_defect_retry_deg = 40.0;
  /// ... and only where every input vertex is within this many site spacings of it (its purpose
  /// is to keep the tips). Default 1.
  double max_tip_run_gap = 1.0;
  /// Run the shared post-CVT stages (mesh_dual_surface(), mesher/surface_mesher.h) on the dual with
  /// the input mesh as the projector: the vertices are then projected onto the input and may be
  /// fewer or more than the sites (unused sites dropped, slivers collapsed, long edges split).
  /// Their result is kept unless it fails a check that the dual passed (RemeshResult::post_cvt_kept).
  /// Not run on non-orientable inputs (the stages orient closed pieces outward), nor where the
  /// dual of a closed input passes every check with the vertex count, φmin and φm of
  /// mesher.sizing's targets (their relaxation would only round off tips).
  /// false = the output is the dual itself (vertex i = site i). Default true.
  bool post_cvt_stages = true;
  /// Options of those stages (threads: cvt.threads is used). Default SurfaceMesherOptions{} with
  /// holes.policy = keep: the boundary loops of an input mesh are real, so only holes inside the
  /// input surface (missing dual triangles) are closed; and min_piece_vertex_fraction = 0: every
  /// component of an input mesh is real, however small; sizing.remove_flying = false: no face
  /// of the dual is taken for one across a depth jump; and sizing.min_angle_deg = 30 with
  /// sizing.repair.sliver_angle_deg = 30: a remesh aims at φmin ≥ 30° (a scan's mesh at 25°), so
  /// the stages run on a dual below that and treat faces below it as slivers; and
  /// keep_manifold_dual = true: a dual that is an oriented manifold keeps its faces where the
  /// extraction would change its topology (the triangles around thin parts coarser than the site
  /// spacing, which it would cut off); and polish.spoiled_border_angle_deg = 20: the relaxation
  /// polish lays no face at the border flat (two border stretches closer than a spacing).
  SurfaceMesherOptions mesher = [] {
    SurfaceMesherOptions m;
    m.holes.policy = HolePolicy::keep;
    m.min_piece_vertex_fraction = 0;
    m.sizing.remove_flying = false;  // an input mesh's faces are its surface
    m.sizing.min_angle_deg = 30;
    m.sizing.repair.sliver_angle_deg = 30;
    m.keep_manifold_dual = true;
    m.polish.spoiled_border_angle_deg = 20;
    return m;
  }();
  /// Sharp creases of the input (dihedral angle above creases.min_dihedral_deg, default 60°) kept
  /// as edge paths of the result, corners fixed (mesher/creases.h); undone where the result then
  /// fails a check it passed. creases.enabled = false (`--no-features`) turns it off; it does not
  /// run where post_cvt_stages is false (the output is then the dual itself). threads:
  /// cvt.threads is used.
  CreaseOptions creases;
  /// Coverage repair of the post-CVT stages' result (mesher/coverage_repair.h): vertices moved
  /// back onto the input vertices farther than coverage.max_gap site spacings from it (tips and
  /// ridges that the relaxation rounded off). Runs where the stages run; coverage.rounds = 0 turns
  /// it off.
  /// The ring drag (CoverageRepairOptions::ring_drag) is off here: this repair has no φm bound
  /// (the cloud path undoes its repair where φm falls), and dragged rings can take φm below its
  /// target; it runs only as a retry (coverage_retry_ring_drag). Otherwise the defaults of
  /// CoverageRepairOptions.
  CoverageRepairOptions coverage = [] {
    CoverageRepairOptions c;
    c.ring_drag = 0;
    return c;
  }();
  /// Where the result after that repair would be refused because it covers the input less well
  /// than the dual (max_coverage_ratio: a tip still cut off), the repair runs again on the
  /// stages' result with ring_drag set to this, and that result is taken where it is not
  /// refused and its φm is at mesher.sizing.mean_angle_deg and at most 1° below the first
  /// repair's. Only such results change: the others keep the vertex alone. 0 = no retry.
  /// Default 0.5 (CoverageRepairOptions::ring_drag's default).
  double coverage_retry_ring_drag = 0.5;
  /// ... and undone where the input vertex farthest from the result is more than this many times
  /// farther than from the mesh before (snapping a tip's vertex onto a short crease near the tip
  /// of an organic shape cuts the tip off). Default 1.1.
  double max_crease_gap_growth = 1.1;
  /// The final check "covers_input": the share of the input's area (each input vertex weighs a
  /// third of its faces' area) farther than covered_spacings site spacings (sqrt(input area /
  /// sites)) from the result must not exceed max_uncovered_area_share. A remesh that passes every
  /// other check can still leave surface out: fins of a non-manifold edge, a piece the dual lost.
  /// Defaults 1 and 0.05.
  double covered_spacings = 1.0;
  double max_uncovered_area_share = 0.05;
};

/// Result of remesh_cvt().
struct RemeshResult {
  /// The remeshed surface (input units): the dual triangulation of the CVT after the post-CVT
  /// stages, or the dual itself (vertex i = sites[i]) when post_cvt_stages is false.
  TriangleMesh mesh;
  std::vector<SurfacePoint> sites;   ///< the CVT's final sites on the input mesh (faces and barycentric coordinates of the input)
  TriangleQuality quality;           ///< φmin, φm of `mesh`
  /// validate_triangle_mesh() of `mesh` against the input's topology; a dual without triangles
  /// gets the one failed check "has_triangles" instead.
  ValidationReport checks;
  /// Share of the input's area farther than RemeshOptions::covered_spacings site spacings from
  /// `mesh` (the check "covers_input"); 1 for a result without faces.
  double uncovered_area_share = 0;
  SurfaceDescription input;          ///< topology of the input
  int iterations = 0;                ///< heat Lloyd iterations run (last CVT)
  bool converged = false;            ///< stopped by the tolerance (last CVT)
  int refinement_levels = 0;         ///< midpoint subdivisions of the input before the CVT
  int refinement_splits = 0;         ///< edges of the input split by refine_surface() before the CVT
  int refinement_flips = 0;          ///< flat edges flipped by refine_surface() before the CVT
  /// Faces of the input reversed so that it is consistently oriented (orient_faces_consistently();
  /// each piece keeps the orientation most of its faces have); 0 where it already was or admits none.
  int reoriented_faces = 0;
  double size_ratio = 1;             ///< largest over smallest relative size of the adaptive sizing (1 = uniform)
  int cvt_vertices = 0;              ///< vertices of the mesh the CVT ran on
  int degenerate_faces = 0;          ///< faces without heat conduction (Laplacian::degenerate_faces)
  /// Face pairs of the input that intersect each other, counted only where `mesh` fails its
  /// no_self_intersections check (−1 otherwise, or where CGAL cannot check the input). Where it
  /// is > 0 the input itself crosses itself (lips or folds pressed through each other, an
  /// immersed surface), a remesh that follows it closely crosses itself too, and the check's
  /// detail says so.
  long input_self_intersections = -1;
  int repair_rounds = 0;             ///< closed-ball repair rounds run
  int repair_sites = 0;              ///< sites added by them
  int repair_dropped_sites = 0;      ///< sites in no dual triangle dropped by them (a cell enclosed by another)
  MesherStats mesher;                ///< counts of the post-CVT stages (empty when not run)
  CreaseStats creases;               ///< what the crease recovery did (zero when the input has no creases)
  CoverageRepairStats coverage;      ///< what the coverage repair did (zero when it did not run)
  bool coverage_ring_dragged = false;  ///< the kept repair dragged rings (RemeshOptions::coverage_retry_ring_drag)
  /// the defect above which the output's tips were held (RemeshOptions::tip_defect_deg or
  /// tip_defect_retry_deg); 0 where no run with tips held is the output
  double tips_held_deg = 0;
  /// The post-CVT stages ran and their result is `mesh`; false when they did not run, their
  /// result failed a check that the dual passed or covers the input less well than the dual
  /// (RemeshOptions::max_coverage_ratio; then `mesh` is the dual).
  bool post_cvt_kept = false;
  /// Why the post-CVT stages' result was not kept, in words (empty when it was or they did not run).
  std::string post_cvt_refusal;
  /// The last CVT: its heat Voronoi diagram lives on the refined mesh (cvt_vertices vertices),
  /// its sites on the refined mesh's faces; statistics of every iteration.
  CvtResult cvt;
  /// Wall time of each stage in pipeline order (name, seconds), as ReconstructionResult's.
  std::vector<std::pair<std::string, double>> stage_seconds;
};

/// CVT remeshing (paper §7.1), the pipeline of `meshcvt` (see the file comment): the same mesh and
/// options give the same output mesh as the tool.
///   mesh V #V by 3, F #F by 3 (valid triangle mesh).
///   progress: called after every heat Lloyd iteration (return false to stop), as centroidal_voronoi().
/// \throw InvalidInputError (invalid mesh, cvt.sites < 1, more sites than the refined input's
///        vertices, bad CvtOptions, λ < 0, ...); SolverError; StagesCancelled where
///        options.mesher.cancelled returns true (mesher/cancellation.h).
RemeshResult remesh_cvt(const TriangleMesh& mesh, const RemeshOptions& options = {},
                        const CvtCallback& progress = {});

}  // namespace heatcvt
