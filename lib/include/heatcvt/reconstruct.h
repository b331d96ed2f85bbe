#pragma once
/// \file reconstruct.h
/// Surface reconstruction from a point cloud (the design card's headline pipeline; paper §8,
/// METHOD.md §7): point Laplacian → heat CVT on the points → dual triangulation → sites placed
/// on a locally fitted surface → orientation, clean-up, validation. The same CVT engine as the
/// mesh path (cvt.h); only the Laplacian builder differs.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/adaptive_sizing.h"
#include "heatcvt/cloud_coverage.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dense_pieces.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/coverage_repair.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/surface_mesher.h"
#include "heatcvt/neighbour_spread.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/stray_points.h"
#include "heatcvt/validate.h"

namespace heatcvt {

/// Tuning of the cloud side of reconstruct_surface() (before the surface mesher), each with its
/// documented default.
struct CloudPreparationOptions {
  /// k of the MST normal orientation (orient_normals_mst(); at most `neighbors`). Default 10.
  int orientation_neighbors = 10;
  /// Offset penalty of the MST orientation (orient_normals_mst()): edges leaving the tangent
  /// plane are taken last, so the two sides of a part thinner than the neighbourhood get opposite
  /// normals. Default 1.
  double orientation_offset_penalty = 1.0;
  /// Fit neighbourhoods hold about this many cells' worth of points (about one output edge
  /// length across, so that noise averages out instead of passing into the vertex positions),
  /// at least `neighbors` points. Default 4.
  double fit_cells = 4.0;
  int max_fit_neighbors = 100;  ///< upper bound of the fit neighbourhood size. Default 100.
  /// A CVT point is smoothed onto the fitted surface only when that moves it by at most its mean
  /// distance to this many nearest CVT points (tips of thin parts, where the fit is not to be
  /// trusted, keep their points). Default 6.
  int smoothing_spacing_neighbors = 6;
  /// The point Laplacian leaves out neighbours of opposite oriented normal (the other side of a
  /// thin part) only when at most this fraction of the CVT points has one: where they are common
  /// the orientation itself is unreliable (cluttered scenes). Default 0.08.
  double max_crossing_fraction = 0.08;
  /// ... and where more do, the pairs of opposite normal are still cut where at least
  /// min_thin_pair_share of them lie across a thin part: normals more than 120° apart
  /// (PointLaplacianOptions::across_max_dot) and the second point off the first's tangent plane
  /// by at least across_min_offset of their distance (the two faces of a plate or a wall about as
  /// thick as the neighbourhood, where nearly every point has a neighbour on the other face);
  /// then those pairs are cut. In cluttered and noisy scans most opposite pairs are orientation
  /// errors within one sheet (0.1–0.4 of them across), on such plates 0.9 and more (measured in
  /// docs/benchmarks.md). across_min_offset = 0 turns this off. Defaults 0.5 and 0.75.
  double across_min_offset = 0.5;
  double min_thin_pair_share = 0.75;
  /// The voxel subset of the CVT points is used only when it has fewer than this fraction of the
  /// points. Default 0.8.
  double max_subset_fraction = 0.8;
  /// Graph-Lloyd iterations of the farthest-point start (`farthest_point_start`). Default 20.
  int graph_lloyd_iterations = 20;
  /// Over-relaxation ω of the surface Lloyd start (CvtOptions::surface_lloyd_relaxation). Default 1.5.
  double surface_lloyd_relaxation = 1.5;
  /// Neighbourhoods that span the surface (neighbour_spread.h): where `neighbors` nearest points
  /// lie along a line (the rings of a rotating lidar, the stripes of a line scanner), the CVT
  /// points' neighbourhoods (normals, orientation, point Laplacian) and the cloud's (fit, walk,
  /// border test) grow to neighbours_for_spread() of their own points; an isotropic sampling
  /// keeps `neighbors`. spread.factor = 0 turns it off.
  NeighbourSpreadOptions spread;
};

/// The coverage repair of the cloud path (ReconstructionOptions::coverage): the defaults of
/// CoverageRepairOptions with the growth on (grow_gap = 1 spacing): a tip longer than its ring
/// can reach gets vertices inserted (docs/benchmarks.md, "Tips grown by inserted vertices").
inline CoverageRepairOptions tip_growth_defaults() {
  CoverageRepairOptions o;
  o.grow_gap = 1.0;
  return o;
}

/// Options of reconstruct_surface(). Every default is the one `cloud2mesh --help` shows.
struct ReconstructionOptions {
  int sites = 3000;               ///< vertices of the output mesh (CVT sites). Default 3000.
  /// Maximum heat Lloyd iterations. Default 6: they start from sites already relaxed by the
  /// surface Lloyd (`surface_lloyd_iterations`). With `surface_lloyd_iterations` = 0 use the
  /// paper's 30 from its random start.
  int iterations = 6;
  int neighbors = 30;             ///< k of the kNN neighbourhoods of the point Laplacian, in [min_neighbors, max_neighbors]. Default 30.
  static constexpr int min_neighbors = 6;    ///< smallest valid `neighbors`
  static constexpr int max_neighbors = 200;  ///< largest valid `neighbors`
  double anisotropy = 0.0;        ///< λ of the anisotropic lift (paper §7.1); 0 = isotropic. Default 0.
  /// Curvature-adaptive sizing (adaptive_sizing.h): where adaptive.adaptivity > 0, relative sizes
  /// g are estimated on the CVT points (their normals, at the uniform site spacing), the CVT runs
  /// with the density g⁻⁴ (smaller cells where the surface bends: tips, rims, creases) and the
  /// mesher's sizing follows g; the vertex count stays `sites`. Default uniform (adaptivity 0).
  AdaptiveSizingOptions adaptive;
  bool denoise = false;           ///< statistical outlier removal before everything. Default false.
  double voxel_size = 0.0;        ///< voxel-grid downsampling (input units); 0 = off. Default 0.
  double time_coefficient = 1.0;  ///< t = C·h̄². Default 1.
  std::uint32_t seed = 1;         ///< seed of the initial sites. Default 1.
  int threads = 0;                ///< 0 = all cores. Default 0.
  /// Boundary loops of the extracted mesh with at most this many edges are treated as holes of
  /// the extraction (not scan boundaries) and filled. Loops of up to 4× this many edges are
  /// filled only if their centre is > h/4 away from every triangle yet < h/2 from a cloud point
  /// (h = mean loop edge length): a hole in sampled surface, not the border of a scan. Loops of
  /// up to 8× this many edges are filled when, for >= 30 % of their edges, a cloud point lies
  /// within half an edge length of the point one edge length outward (in the plane of the edge's
  /// triangle): the cloud continues beyond the loop (around the tip of a thin part, where the
  /// dual lost the tip, only the edges facing the tip find cloud; across the border of an open
  /// scan none does). Default 8.
  int max_hole_edges = 8;
  /// Final polish: iterations of tangential relaxation (each vertex towards the area-weighted
  /// centroid of its one-ring, re-projected to the fitted surface) alternating with edge flips
  /// (valence-equalising on nearly flat pairs, max-min-angle in the last two iterations; if the
  /// result self-intersects the polish is redone with max-min-angle flips only).
  /// 0 = the plain dual of the heat CVT (max-min-angle flips only). Default 10.
  int relaxation_iterations = 10;
  /// Statistical outlier removal: neighbours and standard-deviation multiplier (PCL
  /// StatisticalOutlierRemoval). Defaults 20 and 2.0. Only used with `denoise`.
  int denoise_neighbors = 20;
  double denoise_stddev = 2.0;
  /// Stray points (single points and small groups far from the rest, stray_points.h) are
  /// removed before everything. On by default (ratio 8, 16 neighbours); ratio 0 keeps them.
  StrayPointOptions stray;
  /// Start of the Lloyd iterations when `surface_lloyd_iterations` = 0 (cvt.h): true =
  /// farthest-point sites relaxed by a graph Lloyd on the point triangles while the Cholesky
  /// factor is computed; false = seeded random sites (the paper's start). Default false.
  bool farthest_point_start = false;
  /// Lloyd over-relaxation ω ∈ [1, 2) (cvt.h, safeguarded by the cell-area variance); 1 = the
  /// paper's plain Lloyd. Default 1.
  double lloyd_relaxation = 1.0;
  /// Stop the Lloyd iterations early when no site moved more than this fraction of the site
  /// spacing sqrt(area / sites); 0 = always run `iterations`. Default 0.
  double lloyd_tolerance = 0.0;
  /// Stop the heat Lloyd iterations once the mean site move of one is below this fraction of
  /// the site spacing (CvtOptions::mean_move_tolerance): after the surface-Lloyd start the
  /// sites of a clean sampling are already heat centroids up to a few percent of the spacing,
  /// and further steps only move them by the noise of the sampling; 0 = run `iterations`.
  /// Default 0.05.
  double lloyd_mean_tolerance = 0.05;
  /// Iterations of the cheap surface Lloyd (CvtOptions::surface_lloyd_iterations, ω = 1.5) on
  /// farthest-point start sites, run while the Cholesky factor is computed; 0 = off (the start
  /// is then `farthest_point_start`'s). Default 40.
  int surface_lloyd_iterations = 40;
  /// The surface Lloyd also stops when the mean site move falls below this · site spacing
  /// (CvtOptions::surface_lloyd_mean_tolerance). 0 = off: every iteration runs unless the max
  /// move rule stops it. Default 0.
  double surface_lloyd_mean_tolerance = 0;
  /// The CVT (Laplacian, heat Voronoi, Lloyd, dual candidates) runs on a spatially uniform subset
  /// of about this many points per site (one point per voxel of a grid sized to that count, the
  /// one nearest its voxel's centroid); the site positions are still fitted to every point, so
  /// noise keeps averaging out over the whole cloud. 0 = every point. Default 10 (the
  /// measurements behind it are in docs/benchmarks.md).
  double cvt_points_per_site = 10.0;
  /// Number the CVT's start sites in Morton order (CvtOptions::spatial_site_order). The streamed
  /// path (reconstruct_stream.h), whose site counts reach the hundreds of thousands, turns it on.
  /// Default false.
  bool spatial_site_order = false;
  /// Project the CVT points onto the surface fitted to the whole cloud (the fit of the site
  /// positions) before the Laplacian is built: noise of the scan does not reach the Laplacian,
  /// whose factor and localized solves are then as cheap as on a clean scan. Default true.
  bool smooth_cvt_points = true;
  /// Tuning of normals, fit neighbourhoods, CVT points and the CVT start.
  CloudPreparationOptions cloud;
  /// Tuning of the cloud's local surface fit (the projector of the mesher). Its fit_neighbors,
  /// walk_neighbors and threads are set by reconstruct_surface() from `neighbors`, `sites`,
  /// cloud.fit_cells / max_fit_neighbors and `threads`.
  CloudFitOptions fit;
  /// Tuning of the post-CVT stages (mesher/surface_mesher.h). mesher.holes.max_hole_edges,
  /// mesher.polish.relaxation_iterations and mesher.threads are set by reconstruct_surface() from
  /// `max_hole_edges`, `relaxation_iterations` and `threads` above.
  SurfaceMesherOptions mesher;
  /// Tips of thin parts (ears, fingers, claws) of closed pieces: the relaxation and the polish
  /// pull the vertices there towards the middle of their rings and the mesh caps the tip. After
  /// the mesher, the CVT points (on the fitted surface) farther than coverage.max_gap mean edge
  /// lengths from the mesh pull the nearest corner of their nearest face onto them, where its
  /// triangles keep a smallest angle of min(coverage.min_angle_deg, before) (mesher/coverage_repair.h);
  /// a repair that makes faces cross, lowers φm by more than tips_max_mean_angle_loss_deg, or
  /// lowers it below mesher.sizing.mean_angle_deg (at all, where it was below) is undone: noise
  /// wider than half a spacing leaves points off the mesh everywhere, not at tips, and chasing
  /// them costs the shape. Vertices of open pieces stay: there the samples the mesh leaves out
  /// lie beyond the scan's edge or where flying faces and slivers were cut.
  /// Where samples stay farther than coverage.grow_gap spacings after the moves (a claw or a
  /// finger a few spacings long, cut off whole), vertices are inserted there and moved out along
  /// it (at most coverage.max_grown_fraction of the count: the count stays within 2 %).
  /// coverage.rounds = 0 turns it off. Defaults as CoverageRepairOptions, except grow_gap = 1
  /// (coverage.grow_gap = 0: moves only).
  CoverageRepairOptions coverage = tip_growth_defaults();
  /// See `coverage`. Default 1°.
  double tips_max_mean_angle_loss_deg = 1.0;
  /// Where the mesh comes out more than retry_count_error off the vertex count asked for
  /// (mesher.sizing.target_vertices where set, else `sites`; a coarse dual that crosses itself
  /// can lose most of its faces to the untangling, and what is left may be too little for the
  /// sizing to regrow), or where it covers the cloud only in part (CloudCoverage::partial(): more
  /// than a fifth of the points farther than a spacing, on a cloud that is not volumetric and
  /// whose largest group left out is at least a spacing across, which other start sites can
  /// reach: an unevenly dense RGB-D fragment whose sparse floor the dual of one start leaves
  /// out), the CVT and the mesher run again from the
  /// start sites of the next seeds (seed + 1, seed + 2, ...), at most count_retries times, on the
  /// same points, fit and Laplacian; the result kept passes every check where another does not,
  /// then covers the cloud whole where another does not, then is nearest the count (beyond
  /// mesher.sizing.count_tolerance), then has the larger φmin. 0 = no retry. Default 2.
  int count_retries = 2;
  /// See `count_retries` (a fraction of the count asked for). Default 0.25.
  double retry_count_error = 0.25;
  /// Where every run of `count_retries` still covers the cloud only in part where other sites may
  /// reach the rest (the same rule), the whole reconstruction runs once more with this many times
  /// the sites (and CVT points for them) and its mesh sized to the count asked for (the sizing of
  /// mesher.sizing): a part too thin for the count's cells (a tube about 3 site spacings round,
  /// whose cells wrap around it and whose dual breaks) is resolved by the finer cells, and the
  /// sizing then coarsens the whole surface. The result is kept by the rule of `count_retries`.
  /// It runs only where the cloud holds cvt_points_per_site (at least 10) points per finer site,
  /// and not where count_retries is 0. 1 = no such run. Default 2.
  double finer_retry_factor = 2.0;
  /// How the result's coverage of the points used is measured (ReconstructionResult::
  /// cloud_coverage, cloud_coverage.h). Defaults as CloudCoverageOptions; `threads` is taken
  /// from this struct's.
  CloudCoverageOptions cloud_coverage;
  /// Separate parts holding a large share of the points on too small a share of the area for a
  /// piece of their own (dense_pieces.h) are meshed on their own sites, and the rest of the cloud
  /// on the sites left; the meshes are joined and checked as one. min_point_fraction 0 turns it
  /// off. Defaults as DensePieceOptions.
  DensePieceOptions dense_pieces;
};

/// The CVT options reconstruct_surface() runs centroidal_voronoi() with (sites, iterations,
/// seed, threads, time coefficient, start: the surface Lloyd on farthest-point sites, or the
/// graph-Lloyd farthest-point start, or the paper's random start; over-relaxation, tolerance;
/// no dual). Benchmarks of the CVT on clouds call it to run the same CVT.
CvtOptions reconstruction_cvt_options(const ReconstructionOptions& options);

/// Progress of a reconstruction: a stage name and a fraction in [0, 1].
using ReconstructionCallback = std::function<void(const std::string& stage, double fraction)>;

/// Result of reconstruct_surface(), in the input's coordinates.
struct ReconstructionResult {
  TriangleMesh mesh;               ///< the reconstructed, consistently oriented surface
  ValidationReport validation;     ///< CGAL checks of `mesh`
  int points_used = 0;             ///< after clean-up / denoising / downsampling
  /// Neighbourhood sizes used (CloudPreparationOptions::spread): on the CVT points (normals, point
  /// Laplacian) and on the cloud (surface fit, border test). `neighbors` and the fit's own size
  /// where the sampling spans the surface at them.
  int neighbors_cvt = 0, neighbors_fit = 0;
  double laplacian_seconds = 0, factor_seconds = 0, cvt_seconds = 0, total_seconds = 0;
  int iterations = 0;              ///< Lloyd iterations run
  double size_ratio = 1;           ///< largest over smallest relative size of the adaptive sizing (1 = uniform)
  double min_angle_deg = 0;        ///< φmin: smallest interior angle over all triangles
  double mean_min_angle_deg = 0;   ///< φm: mean over triangles of their smallest angle
  double boundary_min_angle_deg = 180;  ///< φmin of the triangles with an edge on the boundary (180: none)
  int points_input = 0;            ///< rows of P
  int points_merged = 0;           ///< exact duplicates merged
  int points_denoised = 0;         ///< removed by the outlier filter
  int points_stray = 0;            ///< removed as stray points (ReconstructionOptions::stray)
  int points_voxel_removed = 0;    ///< removed by voxel-grid downsampling (input − output count)
  std::vector<double> iteration_seconds;  ///< wall time of each Lloyd iteration
  /// Mean site move of each Lloyd iteration, in site spacings sqrt(area / sites).
  std::vector<double> iteration_moves;
  int candidate_triangles = 0;     ///< distinct dual triangles witnessed by the point triangles
  int rejected_triangles = 0;      ///< candidates not kept (non-manifold or orientation conflict)
  int removed_triangles = 0;       ///< kept, then removed to make vertices manifold / drop tiny pieces
  int holes_filled = 0;            ///< boundary loops filled (mesher.holes.policy decides which)
  int star_triangles = 0;          ///< triangles of the sites' own stars added where the dual had none
  int trimmed_faces = 0;           ///< slivers flat along the border removed
  int pieces_removed = 0;          ///< small and stray pieces dropped (mesher.min_piece_faces, min_piece_vertex_fraction)
  std::vector<int> filled_hole_edges;  ///< edge count of each filled loop
  int flipped_edges = 0;           ///< edge flips on the extracted mesh (max-min-angle and valence)
  bool polish_fallback = false;    ///< the valence-flip polish self-intersected; redone with Delaunay flips only
  long crossing_after_sizing = 0;  ///< intersecting face pairs the sizing left, untangled after it (MesherStats)
  /// Vertices of the working mesh left in no triangle and dropped: sites the dual or the stages
  /// left out, and vertices the stages added and collapsed again (so it can exceed `sites` where
  /// the sizing remeshed).
  int unused_sites = 0;
  bool angle_polish_undone = false;  ///< the smallest-angle polish self-intersected and was undone
  int collapsed_edges = 0;         ///< short edges of slivers (< 25 degrees) collapsed at the end
  /// Wall time of each stage in pipeline order (name, seconds): where the time went.
  std::vector<std::pair<std::string, double>> stage_seconds;
  int split_edges = 0;             ///< long edges of remaining slivers split at their midpoint (on the fitted surface)
  bool sized = false;              ///< remeshed to the vertex count asked for (mesher.sizing: the dual fell short or missed the shape targets)
  int flying_faces = 0;            ///< faces across depth jumps removed before the sizing (remove_flying_faces())
  int faces_turned_outward = 0;    ///< faces of closed pieces whose orientation was reversed (negative enclosed volume)
  int points_cvt = 0;              ///< points the CVT ran on (points_used unless cvt_points_per_site thins them)
  /// How the mesh's border follows the scan's edge (the border points of the cloud the surface
  /// was fitted to), in site spacings (the mesh's mean edge length); zero counts for a closed
  /// mesh.
  BorderFit border;
  /// The tips' coverage repair (ReconstructionOptions::coverage): samples farther than its
  /// max_gap from the mesh before and after, vertex moves kept, largest gaps (in the cloud's
  /// bounding-box frame, not the input's units). All zero where it was off or undone.
  CoverageRepairStats coverage;
  /// Runs of the CVT and the mesher after the first, for a mesh far off the count
  /// (ReconstructionOptions::count_retries), and the seed of the start sites of the result kept.
  int count_retries = 0;
  std::uint32_t seed_used = 1;
  /// The sites of the CVT of the result kept where it came from the run of
  /// ReconstructionOptions::finer_retry_factor (0 where it did not).
  int finer_retry_sites = 0;
  /// How much of the points used (after the clean-up) the mesh covers, how thick they lie at its
  /// spacing and the largest group it leaves out, in input units (cloud_coverage.h): every check
  /// can pass on a mesh of one part of the cloud.
  CloudCoverage cloud_coverage;
  /// Pieces meshed on their own sites (ReconstructionOptions::dense_pieces); 0 where none was.
  /// The other fields then describe the joined result: counts summed over the runs, the quality,
  /// validation and coverage of the joined mesh.
  int dense_pieces = 0;
};

/// Reconstructs a surface from the points P (#P by 3; NaN-free, duplicates allowed).
///
/// Pipeline (all in the cloud's bounding_box_frame, restored at the end):
///  1. exact duplicates merged; optional statistical outlier removal and voxel grid (PCL); the
///     CVT points: a voxel subset of about `cvt_points_per_site` × `sites` points (steps 2-3 and
///     the candidates run on them; the fitted surface and the polish use every point);
///  2. point_laplacian() with k = `neighbors` (tufted intrinsic Delaunay, kNN via FLANN), PCA
///     normals oriented by orient_normals_mst() (edges leaving the tangent plane penalised) before
///     it; where few points (cloud.max_crossing_fraction) have a neighbour of opposite oriented
///     normal (the two sides of a part thinner than the neighbourhood) those neighbours are left
///     out of the local triangulations (PointLaplacianOptions::oriented_normals); with anisotropy
///     λ > 0 the Laplacian is rebuilt from the edge lengths of the local triangles lifted to
///     (p, λ n) ∈ R⁶ (paper §7.1);
///  3. centroidal_voronoi() on (points, local triangles, Laplacian) with
///     reconstruction_cvt_options(): `sites` sites, `iterations` heat Lloyd steps from seeded
///     farthest-point sites relaxed by `surface_lloyd_iterations` of the cheap surface Lloyd (or
///     the paper's seeded random start);
///  4. site positions projected to the cloud's fitted surface (CloudSurfaceProjector: a weighted
///     least-squares quadratic height field over the PCA plane of the nearest points); dual
///     candidates (dual_candidates()): every local triangle whose three corner points lie in
///     three different cells, and every Voronoi vertex of the exact tessellation (each triple of
///     its cells), witnesses the triangle of those three sites;
///  5. the surface mesher's stages with the fitted surface as projector (mesh_from_candidates(),
///     finish_mesh(); each stage documented in its header under mesher/): greedy manifold
///     extraction ordered by witness count then smallest angle, non-manifold vertices resolved,
///     a second pass, hole filling (see max_hole_edges), untangling, valence-3 removal,
///     max-min-angle flips, the polish of `relaxation_iterations` (tangential relaxation +
///     flips, angle polish), sliver collapse, long-edge split, small pieces removed, then the
///     sizing where the dual fell short of `sites` or missed φmin ≥ 25° or φm ≥ 52°
///     (mesher/isotropic_remesh.h: flying faces across depth jumps removed, isotropic remeshing
///     on the fitted surface to `sites` vertices shared among the pieces by area, kept only when
///     no worse on any target), closed pieces outward, unused sites removed;
///  6. validate_triangle_mesh() (require_closed = false: open scans legitimately keep boundaries);
///  7. the cloud's coverage by the mesh (cloud_coverage.h); where the mesh is more than
///     `retry_count_error` off the count or covers the cloud only in part, steps 3-7 again from
///     the start sites of the next seeds (at most `count_retries` times), the best result kept.
/// Deterministic for a given input, options and seed, independent of `threads`.
/// \throw InvalidInputError for empty / too small clouds, sites < 4 or > usable points, bad options.
ReconstructionResult reconstruct_surface(const Eigen::MatrixX3d& P, const ReconstructionOptions& options = {},
                                         const ReconstructionCallback& progress = {});

/// A cloud reconstructed in parts (the dense pieces' path, dense_pieces.h): `rest` on
/// options.sites − Σ piece_sites sites (the sizing's target, where set, lowered by as much) and
/// each of `pieces` on its own piece_sites[k] sites, each as reconstruct_surface() (its clean-up,
/// retries and run on finer sites) but with no dense pieces of its own. The meshes are
/// joined into one result: counts summed over the runs; the quality, CGAL validation and coverage
/// of the joined mesh (coverage of every part's points, at the spacing of the joined mesh's area
/// over the count); `dense_pieces` = the pieces meshed. A piece whose run fails is left out and
/// counted in pieces_removed; a failure of the rest's run is thrown.
/// \throw InvalidInputError as reconstruct_surface(), or where the pieces take all the sites or
///        their sites do not match them.
ReconstructionResult reconstruct_parts(const Eigen::MatrixX3d& rest, const std::vector<Eigen::MatrixX3d>& pieces,
                                       const std::vector<int>& piece_sites, const ReconstructionOptions& options,
                                       const ReconstructionCallback& progress = {});

/// Area-uniform random points on the triangle mesh (V, F) (std::mt19937 seeded with `seed`), plus
/// isotropic Gaussian noise of standard deviation `noise_sigma` (input units) per coordinate.
/// Used to build test and benchmark clouds from meshes. Returns count by 3.
/// \throw InvalidInputError on an empty / zero-area mesh, count < 1 or noise_sigma < 0.
Eigen::MatrixX3d sample_surface(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, int count,
                                std::uint32_t seed = 1, double noise_sigma = 0.0);

/// Distances between two triangle meshes A and B, measured from `samples` area-uniform points on
/// each to the other surface (exact point–triangle distances, CGAL AABB tree).
struct SurfaceDistance {
  double mean_a_to_b = 0, mean_b_to_a = 0;
  double mean = 0;       ///< (mean_a_to_b + mean_b_to_a) / 2: the two-sided mean distance
  double hausdorff = 0;  ///< max over both sample sets (a sampled, one-sided-max-of-both estimate)
};
/// \throw InvalidInputError on empty meshes or samples < 1.
SurfaceDistance surface_distance(const Eigen::MatrixX3d& VA, const Eigen::MatrixX3i& FA, const Eigen::MatrixX3d& VB,
                                 const Eigen::MatrixX3i& FB, int samples = 20000, std::uint32_t seed = 7);

}  // namespace heatcvt
