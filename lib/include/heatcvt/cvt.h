#pragma once
/// \file cvt.h
/// Centroidal Voronoi tessellations by Lloyd iteration with heat Voronoi cells and heat
/// centroids (paper §7.1), with localized solves (paper §6) so that each iteration costs
/// about (number of sites) × (size of a few cells), not (number of sites) × #V.
///
/// One engine, two Laplacian builders: centroidal_voronoi() only needs (V, F) for geometry
/// (positions, the tessellation's triangles) and a Laplacian. Triangle meshes use
/// cotan_laplacian() (or anisotropic_laplacian() below); point clouds pass their point Laplacian
/// and its triangle set F (point_laplacian.h).
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// How the initial sites are chosen when none are given.
enum class CvtInitialization {
  random,          ///< area-uniform random points (std::mt19937 seeded with `seed`)
  farthest_point,  ///< random first vertex, then repeatedly the vertex farthest (graph geodesic) from all sites
};


/// The numeric constants of the CVT's safeguards and heuristics (CvtOptions::tuning). Lengths
/// are in units of the site spacing sqrt(area / sites).
struct CvtTuning {
  /// A site is settled (its Voronoi diffusion needs only voronoi_rings_settled rings) once it and
  /// its neighbours moved less than this. Default 0.25.
  double settled_move = 0.25;
  /// Over-relaxed and Anderson steps (and the surface Lloyd's) go at most this far beyond the
  /// centroid. Default 0.5.
  double max_extra_step = 0.5;
  /// Safeguard of the over-relaxation: when the energy proxy grows, ω − 1 is multiplied by this
  /// (default 0.5) and ω drops to 1 once ω − 1 falls below relaxation_floor (default 0.05).
  double relaxation_decay = 0.5;
  double relaxation_floor = 0.05;
  /// Index set of the Voronoi diffusion of a site whose cell is empty: a graph ball of this
  /// radius around its face. Default 3.
  double empty_cell_radius = 3.0;
  /// split_nonmanifold_cells stops for good when the spots exceed spot_growth_factor × the fewest
  /// seen + spot_growth_slack. Defaults 2 and 10.
  double spot_growth_factor = 2.0;
  int spot_growth_slack = 10;
  /// quality_patience: an evaluation counts as progress when φm grows by more than this
  /// (degrees). Default 0.02.
  double patience_gain_deg = 0.02;
  /// refine_small_angles: at most this fraction of the sites (at least one) per round. Default 0.01.
  double refine_fraction_per_round = 0.01;
  /// A split cell's new site must be farther than split_min_distance × spacing from the cell's
  /// site. Default 1e-6.
  double split_min_distance = 1e-6;
  /// Greedy closest-point walks (over-relaxed steps): at most this many face moves, each must
  /// lower the squared distance by a relative walk_min_gain. Defaults 256 and 1e-12.
  int walk_max_steps = 256;
  double walk_min_gain = 1e-12;
  /// Blocks of faces per thread in the per-iteration clipping of the cells (load balance; the
  /// result does not depend on it). Default 64.
  int face_blocks_per_thread = 64;
};

/// Options of centroidal_voronoi(). Defaults follow the paper (100 iterations, t = h̄²).
struct CvtOptions {
  /// Number of sites (generators). Default 1000.
  int sites = 1000;
  /// Maximum number of Lloyd iterations. Default 100.
  int iterations = 100;
  /// Stop early when no site moved more than `tolerance · spacing`, spacing = sqrt(area / sites).
  /// 0 = always run all iterations. Default 0.
  double tolerance = 0.0;
  /// Stop early when the mean site move of an iteration is below `mean_move_tolerance · spacing`:
  /// the sites are centroids of their heat cells up to noise (over-relaxed steps on a noisy
  /// sampling keep a few sites moving, so the mean and not the largest move decides).
  /// 0 = off. Default 0.
  double mean_move_tolerance = 0.0;
  /// Seed of the random initialisation. Default 1.
  std::uint32_t seed = 1;
  /// Initial sampling when no initial sites are given. Default random (as in the paper).
  CvtInitialization initialization = CvtInitialization::random;
  /// Threads (OpenMP, parallel over sites); 0 = all hardware threads. Results do not depend on it.
  int threads = 0;
  /// t = time_coefficient · h̄² of the Laplacian's mean edge length. Default 1 (paper).
  double time_coefficient = 1.0;
  /// Fill-reducing ordering of the heat factor (HeatSolverOptions::ordering). Less fill makes
  /// every localized solve cheaper. Default automatic.
  FillOrdering ordering = FillOrdering::automatic;
  /// Index set of a site's Voronoi diffusion: its cell plus this many rings of neighbouring cells
  /// (previous iteration's adjacency). Default 2 (paper: cell, neighbours, their neighbours).
  int voronoi_rings = 2;
  /// Index set of a cell's centroid diffusion: the cell plus this many rings of cells. Default 1.
  int centroid_rings = 1;
  /// Index set of the Voronoi diffusions once the sites have settled: the cell plus this many
  /// rings, for every site once all moved less than tuning.settled_move spacings, and before that
  /// for each site that moved that little together with all its neighbouring sites (each
  /// bisector then moved less than that, so one ring of cells covers the new cell). Default 1.
  /// Set it to voronoi_rings to keep the paper's 2 rings throughout.
  int voronoi_rings_settled = 1;
  /// Quadratic sub-vertex refinement of the centroid (§7.1 "Centroids on faces"). Default true.
  bool quadratic_refinement = true;
  /// Forward-solve pruning of the localized solves (localized_solve.h). The heat only feeds
  /// comparisons (labels, hottest vertex), so relative errors of 1e-9 are immaterial. Default 1e-9.
  double drop_tolerance = 1e-9;
  /// Sites kept per vertex in the heat field. Default 8.
  int keep_sites_per_vertex = 8;
  /// Build the dual triangulation of the final diagram. Default true.
  bool build_dual = true;
  /// Every this many iterations, build the exact diagram and dual of the current sites and record
  /// φmin / φm in the iteration's stats (costs about one final step each). 0 = never. Default 0.
  int quality_every = 0;
  /// Stop at the first quality evaluation where φm ≥ target_phi_mean_deg and φmin ≥
  /// target_phi_min_deg, and the dual has no non-manifold spot (needs quality_every > 0). A target
  /// ≤ 0 is not required; with both ≤ 0 there is no such stop. The evaluated diagram becomes the
  /// result. Default 0 (off).
  double target_phi_mean_deg = 0.0;
  double target_phi_min_deg = 0.0;

  // --- accelerations (all off by default: the defaults above are the paper's plain Lloyd) ---
  /// Lloyd over-relaxation ω ∈ [1, 2): s ← closest surface point (greedy walk from c) to
  /// c + (ω − 1)(c − s), the extra step capped at half the site spacing; c = heat centroid.
  /// Safeguard: whenever the cell-area variance (energy proxy) grows from one iteration to the
  /// next, ω − 1 is halved (and dropped below 0.05). 1 = plain Lloyd (paper). Default 1.
  double relaxation = 1.0;
  /// Anderson acceleration of the Lloyd map x ↦ G(x) (heat centroids) with this many previous
  /// iterations (type II, least squares on the area-weighted residuals w_s (G(x)_s − x_s),
  /// w_s = sqrt(cell area)); the mixed positions are projected onto the surface (greedy walk from
  /// the centroid), each at most half a spacing beyond its centroid. Safeguard: when the residual
  /// grows, or a cell vanished or sites were added, the history is cleared and the plain Lloyd
  /// step is taken. Replaces `relaxation` when > 0. 0 = off (paper). Default 0.
  int anderson_depth = 0;
  /// Iterations of a cheap *graph* Lloyd on the initial sites (cells = multi-source Dijkstra on
  /// the edge graph, centroid = area-weighted mean position snapped to the closest vertex of the
  /// cell) before the heat iterations start. It runs concurrently with the Cholesky factorisation
  /// when threads ≥ 2 (results do not depend on it). 0 = off. Stops early when no site moves.
  int graph_lloyd_iterations = 0;
  /// Iterations of a cheap *surface* Lloyd on the start sites, after the graph Lloyd and, like
  /// it, concurrently with the Cholesky factorisation when threads ≥ 2 (results do not depend on
  /// it). Cells: restricted Voronoi cells grown over the edge graph by Euclidean distance to the
  /// continuous site (a local stand-in for the geodesic cells of §7.1, connected so thin parts are
  /// not bridged; after the first iteration updated by local sweeps next to label changes);
  /// centroid: the mean position of the restricted cell, faces on cell borders clipped exactly by
  /// the Euclidean bisector planes (as eq. 20 clips by heat), projected onto the surface (not
  /// snapped to a vertex, unlike the graph Lloyd); over-relaxed by surface_lloyd_relaxation
  /// (safeguarded by the lumped CVT energy). An iteration costs a few linear passes over the mesh,
  /// far below a heat iteration, so the heat Lloyd iterations of §7.1 are left to correct the
  /// metric (often none are needed, see quality_at_start). Stops early when no site moved more than
  /// surface_lloyd_tolerance · spacing. Skipped with face_metric_area (anisotropic metric).
  /// The result is still the heat Voronoi diagram (and its dual) of the final sites.
  /// 0 = off (paper). Default 0.
  int surface_lloyd_iterations = 0;
  /// Number the generated start sites in the Morton order of their positions (spatial_order.h)
  /// instead of the order they were drawn in, so the per-site loops and cell rings of every later
  /// step read memory that is close together. The cells, centroids and stopping rules are the
  /// same; only tie-breaks by site index differ. Worth it where the per-site arrays outgrow the
  /// caches (tens of thousands of sites; measurements in docs/benchmarks.md). Default false (the
  /// numbering of the draw).
  bool spatial_site_order = false;
  /// Early stop of the surface Lloyd: max site move < this · spacing. Default 0.01.
  double surface_lloyd_tolerance = 0.01;
  /// Early stop of the surface Lloyd on the mean site move: mean move < this · spacing. With many
  /// sites a few of them keep moving (cells at thin parts and folds swap corners back and forth),
  /// so the max rule alone runs every iteration, and its cost grows with the site count; the mean
  /// move falls like the energy. 0 = off. Default 0.
  double surface_lloyd_mean_tolerance = 0;
  /// Over-relaxation ω ∈ [1, 2) of the surface Lloyd (step capped at half a spacing). Default 1.
  double surface_lloyd_relaxation = 1.0;
  /// With quality_every > 0: evaluate the quality of the start sites (after graph/surface Lloyd)
  /// before the first heat iteration, so a start that already meets the targets costs one heat
  /// diagram and no Lloyd iteration. Default false.
  bool quality_at_start = false;
  /// With quality_at_start and the surface Lloyd: when the start evaluation split cells too big
  /// for thin parts (split_nonmanifold_cells), run surface_lloyd_split_iterations more
  /// surface-Lloyd iterations on all sites and evaluate the start again, at most this many times,
  /// before the heat iterations. 0 = off. Default 0.
  int surface_lloyd_split_rounds = 0;
  /// Surface-Lloyd iterations after each such split (few: the added sites must stay in the thin
  /// part while their neighbours make room). Default 3.
  int surface_lloyd_split_iterations = 3;
  /// In those start rounds, when only φmin misses its target (no non-manifold spot, φm met): a new
  /// site at the Voronoi vertex dual to every triangle whose smallest angle is below
  /// target_phi_min_deg (circumcentre insertion of Delaunay refinement, placed where the three
  /// heat cells meet, snapped to the nearest input vertex; worst first, at most
  /// tuning.refine_fraction_per_round of the sites per round, within max_inserted_fraction), then
  /// the same surface-Lloyd iterations and a new evaluation. The result stays the dual of the heat
  /// Voronoi diagram of all final sites. With a far-off target (many bad triangles) it can lower
  /// φmin, the inserted sites not settling in a few surface-Lloyd iterations. Default false.
  bool refine_small_angles = false;
  /// Split cells too big for thin parts: at each quality evaluation, every cell incident to a
  /// non-manifold spot of the dual (an edge with more than two triangles or a boundary edge on a
  /// closed input, a vertex whose triangles do not form one fan, a cell appearing twice around a
  /// Voronoi vertex) gets a new site at its vertex farthest from its site (at most
  /// max_inserted_fraction · initial sites in total). The quality target is then only accepted
  /// for a dual without such spots. The result's dual is always the dual of the heat Voronoi
  /// diagram of the final sites. Not done on inputs with non-manifold edges (no manifold dual
  /// exists), and stopped for good when the spots grow beyond tuning.spot_growth_factor × the
  /// fewest seen + tuning.spot_growth_slack. Default false (fixed site count, as in the paper).
  bool split_nonmanifold_cells = false;
  /// Sites added by split_nonmanifold_cells and refine_small_angles, at most this fraction of the
  /// initial sites in total. Default 0.25.
  double max_inserted_fraction = 0.25;
  /// Convergence test on the quality (needs quality_every > 0): stop when φm has not improved by
  /// more than tuning.patience_gain_deg over this many consecutive evaluations (result.stalled).
  /// Where the evaluation at which the patience runs out split cells (split_nonmanifold_cells),
  /// the splitting stops and the next evaluation ends the run. 0 = off. Default 0.
  int quality_patience = 0;
  /// With quality_every: the first evaluation happens only after this many iterations. Default 0.
  int quality_start = 0;
  /// Constants of the safeguards and heuristics above (CvtTuning).
  CvtTuning tuning;
};

/// The configuration for remeshing (meshcvt's defaults; docs/benchmarks.md has its measurements): farthest-point sampling,
/// surface-Lloyd pre-relaxation (60 iterations, ω = 1.5) during the factorisation, a quality check of
/// the start sites before the first heat iteration (with up to 12 rounds of splitting cells too big
/// for thin parts or inserting sites at small-angle Voronoi vertices + 3 surface-Lloyd iterations), over-relaxed Lloyd (ω = 1.5), quality
/// evaluated every 2nd iteration with the targets φm ≥ 51°, φmin ≥ 25° and a stop when φm stalls
/// for 10 evaluations, cells split where too big for thin parts. `CvtOptions{}` remains the paper's configuration.
CvtOptions fast_cvt_options(int sites);

/// Statistics of one Lloyd iteration.
struct CvtIterationStats {
  int iteration = 0;           ///< 1-based
  double seconds = 0;          ///< wall time of the iteration
  double voronoi_seconds = 0;  ///< of which localized Voronoi solves + tessellation
  double centroid_seconds = 0; ///< of which centroid solves + refinement
  double voronoi_solve_seconds = 0;  ///< localized point-source solves (part of voronoi_seconds)
  double tessellate_seconds = 0;     ///< heat field + tessellation (part of voronoi_seconds)
  double max_move = 0;         ///< largest site displacement (Euclidean, input units)
  double mean_move = 0;
  double area_variance = 0;    ///< variance of the cell areas of the diagram this iteration started from
  double mean_index_set = 0;   ///< mean |I| of the Voronoi solves
  double phi_min_deg = -1;     ///< quality of the dual of this iteration's sites (−1 = not evaluated)
  double phi_mean_deg = -1;
  double quality_seconds = 0;  ///< time of that evaluation (not included in `seconds`)
  int revived_sites = 0;       ///< sites whose cell was empty, moved into the largest cell this iteration
  int inserted_sites = 0;      ///< sites added after this iteration's quality evaluation (split_nonmanifold_cells)
  int nonmanifold_spots = -1;  ///< non-manifold spots of the evaluated dual (−1 = not evaluated)
  double relaxation = 1.0;     ///< ω used by this iteration's step
  int anderson_columns = 0;    ///< history columns of this iteration's Anderson step (0 = plain step)
  double residual = 0;         ///< sqrt(Σ area_s |centroid_s − site_s|²) of this iteration
};

/// Result of centroidal_voronoi().
struct CvtResult {
  std::vector<SurfacePoint> sites;   ///< final sites
  Eigen::MatrixX3d positions;        ///< #sites by 3 positions of the final sites
  VoronoiDiagram diagram;            ///< exact heat Voronoi diagram of the final sites
  DualMesh dual;                     ///< its dual triangulation (if options.build_dual)
  std::vector<CvtIterationStats> iterations;
  bool converged = false;            ///< stopped by the tolerance
  bool reached_quality = false;      ///< stopped by the quality targets
  bool stalled = false;              ///< stopped by quality_patience (φm no longer improving)
  double factor_seconds = 0;         ///< Cholesky factorisation of M − tL
  std::size_t factor_bytes = 0;      ///< memory of the factor
  double setup_seconds = 0;          ///< factorisation + adjacency + initial sites
  double total_seconds = 0;
  double final_area_variance = 0;    ///< variance of the final cell areas
  int graph_lloyd_iterations = 0;    ///< graph-Lloyd iterations done on the initial sites
  double graph_lloyd_seconds = 0;    ///< their time (overlapped with the factorisation when threads ≥ 2)
  int surface_lloyd_iterations = 0;  ///< surface-Lloyd iterations done on the start sites
  double surface_lloyd_seconds = 0;  ///< their time (overlapped with the factorisation when threads ≥ 2)
  double start_phi_min_deg = -1;     ///< quality of the start sites' dual (quality_at_start; −1 = not evaluated)
  double start_phi_mean_deg = -1;
  double start_quality_seconds = 0;  ///< time of the start evaluations (heat field + diagram + dual) and split rounds
  int start_rounds = 0;              ///< surface-Lloyd rounds after splits at the start (surface_lloyd_split_rounds)
  int refined_sites = 0;             ///< of inserted_sites, added by refine_small_angles
  int start_spots = -1;              ///< non-manifold spots of the last start evaluation (−1 = not evaluated)
  int inserted_sites = 0;            ///< sites added by split_nonmanifold_cells (and refine_small_angles)
};

/// Progress callback: called after every iteration with its statistics; return false to stop.
using CvtCallback = std::function<bool(const CvtIterationStats&)>;

/// Lloyd iteration for a CVT of the surface (V, F) with the given Laplacian (paper §7.1).
///   V #V by 3, F #F by 3; laplacian.num_vertices() == #V (cotan or point Laplacian).
///   initial_sites: optional starting sites (empty = options.initialization with options.seed);
///   then options.sites is ignored.
///   face_metric_area: optional #F areas in the Laplacian's metric (anisotropic lift); the area
///   sources of the centroids use them. Empty = the Euclidean areas of (V, F).
///   vertex_density: optional #V densities ρ > 0 of a CVT with density (adaptive sizing,
///   adaptive_sizing.h): the cells stay the heat Voronoi cells, the centroids' area sources and
///   the surface Lloyd's cell means weight each face's area by its density (the mean of its
///   corners'), so the sites minimise Σ ∫_cell ρ |x − p|² and the cells get a diameter
///   ∝ ρ^(-1/4); the generated start follows it (initial_sites()). Empty = uniform.
/// Each iteration: per site a localized point-source diffusion over its cell and
/// `voronoi_rings` rings of neighbouring cells → heat field → (exact) tessellation → per cell an
/// area-source diffusion (eq. 10–11) localized to the cell and `centroid_rings` rings → hottest
/// vertex → quadratic refinement → move. Deterministic: same inputs and seed give bit-identical
/// results for any thread count.
/// \throw InvalidInputError on bad sizes/options (sites < 1 or > #V, iterations < 0, ...);
///        SolverError if the heat matrix cannot be factored.
CvtResult centroidal_voronoi(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Laplacian& laplacian,
                             const CvtOptions& options = {}, const std::vector<SurfacePoint>& initial_sites = {},
                             const CvtCallback& callback = {},
                             const Eigen::VectorXd& face_metric_area = Eigen::VectorXd(),
                             const Eigen::VectorXd& vertex_density = Eigen::VectorXd());

/// Laplacian of the anisotropic CVT (paper §7.1, Fig. 9): scales the mesh into the unit
/// bounding box (largest side 1), lifts each vertex to (p, λ n) ∈ R⁶ (n = area-weighted unit
/// vertex normal; paper λ = 0.05) and builds the cotan Laplacian from the lifted edge lengths
/// (face_edge_lengths + cotan_laplacian_from_lengths); h̄ (hence t) is the lifted mean edge
/// length. `face_metric_area`, if given, receives the lifted face areas (#F, same scaled units),
/// to be passed to centroidal_voronoi() so the centroids' area sources use the lifted metric.
/// \throw InvalidInputError on an invalid mesh or λ < 0 / non-finite.
Laplacian anisotropic_laplacian(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double lambda,
                                Eigen::VectorXd* face_metric_area = nullptr);

/// Variance of the cell areas (population variance over the cells).
double cell_area_variance(const VoronoiDiagram& diagram);

}  // namespace heatcvt

#include "heatcvt/cvt/anisotropic_lift.h"  // lifted_laplacian(): the R⁶ lift shared with the point path
#include "heatcvt/cvt/start.h"             // initial_sites()
