// cloud2mesh: surface reconstruction from a point cloud by a heat CVT on the points (paper §8):
// point Laplacian -> centroidal Voronoi tessellation -> dual triangulation on a fitted surface.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sys/resource.h>
#include <string>
#include <vector>

#include "cli_common.h"
#include "heatcvt/atomic_file.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/mesh.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/scan_merge.h"
#include "heatcvt/vertex_attributes.h"
#include "report_json.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

namespace {

// Below this many usable points per requested site the summary notes that the cloud is
// undersampled for -n.
constexpr double kFewPointsPerSite = 3.0;
// Far outliers: when a few points set the bounding box (the normalisation frame) and the bulk of
// the cloud spans less than `ratio` of it, the bulk collapses below the precision of the
// normalised coordinates. The bulk is the 1 %-99 % quantile box per axis.
void reject_far_outliers(const Eigen::MatrixX3d& P, const std::string& path) {
  constexpr double ratio = 1e-6;
  const Eigen::Index n = P.rows();
  if (n < 100) return;
  Eigen::RowVector3d bulk, full;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v(P.col(k).data(), P.col(k).data() + n);
    std::sort(v.begin(), v.end());
    bulk[k] = 0.5 * v[n - 1 - n / 100] - 0.5 * v[n / 100];
    full[k] = 0.5 * v[n - 1] - 0.5 * v[0];
  }
  if (bulk.norm() < ratio * full.norm())
    throw InvalidInputError(path + ": a few points lie far outside the others (98 % of the points span " +
                            format_double(2 * bulk.norm()) + ", the bounding box " + format_double(2 * full.norm()) +
                            "): remove these outliers");
}

// An angle as the summary prints it ("28.24 deg").
std::string format_angle(double degrees) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f deg", degrees);
  return buf;
}

// Option checks before any work (the library checks them again), naming the option at fault.
void check_options(const ReconstructionOptions& opt) {
  if (opt.sites < 4) throw InvalidInputError("-n must be at least 4 (got " + std::to_string(opt.sites) + ")");
  if (opt.iterations < 0) throw InvalidInputError("-i must be >= 0");
  if (opt.neighbors < ReconstructionOptions::min_neighbors || opt.neighbors > ReconstructionOptions::max_neighbors)
    throw InvalidInputError("-k must be between " + std::to_string(ReconstructionOptions::min_neighbors) + " and " +
                            std::to_string(ReconstructionOptions::max_neighbors));
  if (!(opt.anisotropy >= 0) || !std::isfinite(opt.anisotropy)) throw InvalidInputError("--anisotropy must be >= 0");
  if (!(opt.adaptive.adaptivity >= 0 && opt.adaptive.adaptivity <= 2))
    throw InvalidInputError("--adaptive must be in [0, 2]");
  if (!(opt.adaptive.max_size_ratio >= 1) || !std::isfinite(opt.adaptive.max_size_ratio))
    throw InvalidInputError("--size-ratio must be a number >= 1");
  if (!(opt.voxel_size >= 0) || !std::isfinite(opt.voxel_size)) throw InvalidInputError("--voxel must be >= 0");
  cli::check_time_coefficient(opt.time_coefficient);
  cli::check_threads(opt.threads);
  if (opt.surface_lloyd_iterations < 0) throw InvalidInputError("--surface-lloyd must be >= 0");
  if (!(opt.cvt_points_per_site == 0 || opt.cvt_points_per_site >= 3) || !std::isfinite(opt.cvt_points_per_site))
    throw InvalidInputError("--points-per-site must be 0 (every point) or at least 3");
  if (!(opt.lloyd_relaxation >= 1 && opt.lloyd_relaxation < 2)) throw InvalidInputError("--relaxation must be in [1, 2)");
  if (!(opt.lloyd_tolerance >= 0) || !std::isfinite(opt.lloyd_tolerance)) throw InvalidInputError("--tolerance must be >= 0");
  if (!(opt.lloyd_mean_tolerance >= 0) || !std::isfinite(opt.lloyd_mean_tolerance))
    throw InvalidInputError("--mean-tolerance must be >= 0");
  if (opt.count_retries < 0) throw InvalidInputError("--count-retries must be >= 0");
  if (!(opt.coverage.grow_gap >= 0) || !std::isfinite(opt.coverage.grow_gap))
    throw InvalidInputError("--tip-growth must be >= 0");
  if (!(opt.retry_count_error >= 0) || !std::isfinite(opt.retry_count_error))
    throw InvalidInputError("--retry-count-error must be >= 0");
  if (!(opt.finer_retry_factor >= 1) || !std::isfinite(opt.finer_retry_factor))
    throw InvalidInputError("--finer-retry must be >= 1");
  if (!(opt.dense_pieces.min_point_fraction >= 0 && opt.dense_pieces.min_point_fraction <= 1))
    throw InvalidInputError("--dense-pieces must be in [0, 1]");
  if (opt.max_hole_edges < 0) throw InvalidInputError("--max-hole-edges must be >= 0");
  if (opt.relaxation_iterations < 0) throw InvalidInputError("--polish-iterations must be >= 0");
  if (opt.denoise_neighbors < 2) throw InvalidInputError("--denoise-k must be >= 2");
  if (!(opt.denoise_stddev > 0) || !std::isfinite(opt.denoise_stddev))
    throw InvalidInputError("--denoise-stddev must be a positive number");
  try {  // the library's rule, in the option's words
    check_stray_point_options(opt.stray);
  } catch (const InvalidInputError&) {
    throw InvalidInputError("--stray-ratio must be 0 (off) or above 1");
  }
}

// PCL's voxel grid indexes at most 2^31 voxels; a smaller voxel would silently do nothing.
void reject_tiny_voxel(const Eigen::MatrixX3d& P, double voxel_size, const std::string& path) {
  if (voxel_size <= 0) return;
  const Eigen::RowVector3d extent = P.colwise().maxCoeff() - P.colwise().minCoeff();
  double voxels = 1;
  for (int k = 0; k < 3; ++k) voxels *= std::floor(extent[k] / voxel_size) + 1;
  if (!(voxels <= static_cast<double>(INT_MAX)))
    throw InvalidInputError("--voxel " + format_double(voxel_size) + ": too small for " + path +
                            " (more than 2^31 voxels over its bounding box)");
}

// The --report of a run (schema: report_json.h), without the common tail.
cli::Json make_report(const std::string& cloud_path, const std::vector<std::string>& outputs, const CloudReadReport& rr,
                      const ReconstructionOptions& opt, const ReconstructionResult& res, double per_iter, double total_s) {
  cli::Json j = cli::report_head("cloud2mesh", cloud_path, outputs);
  j["format"] = rr.format;
  j["points_in_file"] = rr.points_in_file;
  j["non_finite_dropped"] = rr.non_finite_dropped;
  j["duplicates_merged"] = rr.duplicates_merged;
  j["flying_pixels_removed"] = rr.flying_pixels_removed;
  j["depth_quantised"] = rr.depth_steps.quantised;
  j["depth_step_median"] = rr.depth_steps.median_step;
  j["depth_points_moved"] = static_cast<long>(rr.depth_steps.points_moved);
  j["depth_mean_move_steps"] = rr.depth_steps.mean_move_steps;
  j["depth_steps_s"] = rr.depth_steps.seconds;
  j["points_denoised"] = res.points_denoised;
  j["points_stray"] = res.points_stray;
  j["points_voxel_removed"] = res.points_voxel_removed;
  j["points_used"] = res.points_used;
  j["points_cvt"] = res.points_cvt;
  j["sites"] = opt.sites;
  j["iterations"] = res.iterations;
  j["neighbors"] = opt.neighbors;
  j["neighbors_cvt"] = res.neighbors_cvt;
  j["neighbors_fit"] = res.neighbors_fit;
  j["anisotropy"] = opt.anisotropy;
  j["adaptivity"] = opt.adaptive.adaptivity;
  j["size_ratio"] = res.size_ratio;
  j["seed"] = opt.seed;
  j["vertices"] = res.mesh.V.rows();
  j["faces"] = res.mesh.F.rows();
  j["unused_sites"] = res.unused_sites;
  j["candidate_triangles"] = res.candidate_triangles;
  j["rejected_triangles"] = res.rejected_triangles;
  j["removed_triangles"] = res.removed_triangles;
  j["holes_filled"] = res.holes_filled;
  j["star_triangles"] = res.star_triangles;
  j["trimmed_faces"] = res.trimmed_faces;
  j["pieces_removed"] = res.pieces_removed;
  j["sized"] = res.sized;
  j["count_retries"] = res.count_retries;
  j["finer_retry_sites"] = res.finer_retry_sites;
  j["dense_pieces"] = res.dense_pieces;
  j["seed_used"] = res.seed_used;
  j["crossing_after_sizing"] = res.crossing_after_sizing;
  j["flying_faces_removed"] = res.flying_faces;
  j["boundary_loops"] = res.validation.boundary_loops;
  j["components"] = res.validation.components;
  j["genus"] = res.validation.genus;
  j["self_intersecting_pairs"] = res.validation.self_intersecting_pairs;
  j["phi_min_deg"] = res.min_angle_deg;
  j["phi_mean_deg"] = res.mean_min_angle_deg;
  j["phi_min_boundary_deg"] = res.boundary_min_angle_deg;
  j["scan_edge_points"] = res.border.edge_points;
  j["scan_edge_covered"] = res.border.edge_covered;
  j["border_vertices"] = res.border.mesh_border_vertices;
  j["border_on_scan_edge"] = res.border.mesh_border_on_edge;
  j["border_p90_spacings"] = res.border.mesh_border_distance;
  j["cloud_uncovered_share"] = res.cloud_coverage.uncovered_share;
  j["cloud_thickness_spacings"] = res.cloud_coverage.thickness_spacings;
  j["cloud_thickness_radius_spacings"] = res.cloud_coverage.thickness_radius_spacings;
  j["cloud_largest_uncovered_share"] = res.cloud_coverage.largest_group_share;
  j["cloud_largest_uncovered_spacings"] = res.cloud_coverage.largest_group_spacings;
  j["cloud_covered_in_part"] = res.cloud_coverage.partial();
  j["cloud_volumetric"] = res.cloud_coverage.volumetric();
  j["tip_moves"] = res.coverage.moves;
  j["tip_vertices_inserted"] = res.coverage.inserted;
  j["tip_repair_skipped"] = res.coverage.skipped;
  j["tip_uncovered_before"] = res.coverage.uncovered_before;
  j["tip_uncovered_after"] = res.coverage.uncovered_after;
  j["blas"] = heatcvt::blas_description();
  j["laplacian_s"] = res.laplacian_seconds;
  j["factor_s"] = res.factor_seconds;
  j["cvt_s"] = res.cvt_seconds;
  j["per_iteration_s"] = per_iter;
  j["iteration_mean_move_spacings"] = res.iteration_moves;
  j["reconstruct_s"] = res.total_seconds;
  j["total_s"] = total_s;
  return j;
}

}  // namespace

// Progress weights of the reconstruction's stages (their typical share of the time).
ReconstructionCallback stage_progress(cli::Progress& bar) {
  return [&bar](const std::string& stage, double f) {
    double done = 0;
    if (stage == "preprocess") done = 0;
    else if (stage == "laplacian") done = 0.02 + 0.08 * f;
    else if (stage == "cvt") done = 0.10 + 0.80 * f;
    else if (stage == "mesh") done = 0.90 + 0.05 * f;
    else done = 0.95 + 0.05 * f;
    // The CVT's start (factorisation and surface Lloyd) reports 0, its heat Lloyd iterations more.
    const std::string what = stage != "cvt" ? stage : f > 0 ? "cvt: heat Lloyd iterations" : "cvt: factor and start";
    bar.update(static_cast<long>(1000 * done), what);
  };
}

// Bytes per point assumed for a text cloud (no point count in its header) when deciding whether
// to stream it: "x y z" with about 7 significant digits per coordinate.
constexpr double kTextBytesPerPoint = 30.0;

// Whether one input file has more points than raw_point_limit() allows (--stream-above, and
// --stream-per-site per site): then it is streamed into a voxel summary (reconstruct_stream.h)
// instead of being held whole (about 2.1 KB per point).
bool should_stream(const std::vector<ScanInput>& scans, const ReconstructionOptions& opt, const StreamOptions& limits) {
  if (scans.size() != 1 || !scans[0].pose.isApprox(Eigen::Isometry3d::Identity()) || opt.denoise || opt.voxel_size > 0)
    return false;
  const CloudChunkReader probe(scans[0].path);
  const double points = probe.points_in_file() >= 0 ? static_cast<double>(probe.points_in_file())
                                                    : static_cast<double>(probe.bytes_total()) / kTextBytesPerPoint;
  return points > static_cast<double>(raw_point_limit(limits, opt.sites));
}

// The streamed reconstruction of one large file, with reading progress (bytes) per pass.
StreamedReconstruction reconstruct_streamed(const std::string& path, const ReconstructionOptions& opt,
                                            const CloudReadOptions& read, const StreamOptions& limits, bool quiet) {
  StreamOptions stream = limits;
  stream.flying_pixels = read.flying_pixels;
  stream.depth_steps = read.depth_steps;  // run on opt.threads (reconstruct_surface_streamed)
  // --points-per-site sizes the summary: the voxel points the CVT runs on, per site.
  if (opt.cvt_points_per_site > 0) stream.voxel.points_per_site = opt.cvt_points_per_site;
  std::unique_ptr<cli::Progress> reading;
  int reading_pass = 0;
  stream.progress = [&](int pass, const StreamProgress& p) {
    if (pass != reading_pass) {
      if (reading) reading->finish();
      reading = std::make_unique<cli::Progress>("reading (pass " + std::to_string(pass) + ")", p.bytes_total, quiet);
      reading_pass = pass;
    }
    reading->update(p.bytes_read, "", std::to_string(p.points_read) + " points");
  };
  // The reconstruction's bar starts when reading ends (its first stage report).
  std::unique_ptr<cli::Progress> bar;
  ReconstructionCallback stages;
  const ReconstructionCallback on_stage = [&](const std::string& stage, double f) {
    if (!bar) {
      if (reading) reading->finish();
      bar = std::make_unique<cli::Progress>("reconstructing", 1000, quiet);
      stages = stage_progress(*bar);
    }
    stages(stage, f);
  };
  StreamedReconstruction s = cli::on_file(path, [&] { return reconstruct_surface_streamed(path, opt, stream, on_stage); });
  if (reading) reading->finish();
  if (bar) bar->finish();
  return s;
}

// Peak resident memory of this process in MB (getrusage).
double peak_memory_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

namespace {

// The command line of cloud2mesh.
struct Settings {
  ReconstructionOptions opt;
  std::vector<std::string> cloud_paths, pose_paths;
  std::string conf_path, out_path, report_path;
  bool quiet = false, write_normals = false;
  StreamOptions stream_limits;  ///< max_raw_points and max_raw_points_per_site (--stream-above, --stream-per-site)
  CloudReadOptions read_options;
};

// What a run produced: the cloud as read (or its voxel summary when streamed) and the mesh.
struct Reconstruction {
  CloudReadReport rr;
  PointCloud cloud;
  ReconstructionResult res;
  StreamedReconstruction streamed;
  bool stream = false;
};

// Declares the input options: clouds, poses, holes, streaming, flying pixels, normals, small pieces.
void add_input_options(CLI::App& app, Settings& s) {
  app.add_option("CLOUD", s.cloud_paths,
                 "input point clouds (.pcd .ply .xyz .pwn .txt); several scans are merged into one surface");
  app.add_option("--pose", s.pose_paths,
                 "rigid pose of an input (a 4x4 or 3x4 matrix file), applied before merging; give one per CLOUD, "
                 "in the same order");
  app.add_option("--conf", s.conf_path,
                 "Stanford-style .conf listing scans with a translation and quaternion each (bmesh FILE tx ty tz qx qy "
                 "qz qw), instead of CLOUD");
  app.add_option("--holes", s.opt.mesher.holes.policy,
                 "which holes to close: auto (holes inside sampled surface and scan holes the surface continues "
                 "around; the border of an open scan stays open), fill (every hole: watertight wherever the cloud "
                 "encloses a volume), keep (only where the surface is sampled: no invented surface)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, HolePolicy>{{"auto", HolePolicy::automatic},
                                                                            {"fill", HolePolicy::fill},
                                                                            {"keep", HolePolicy::keep}},
                                          CLI::ignore_case))
      ->default_str("auto");
  app.add_option("--stream-above", s.stream_limits.max_raw_points,
                 "a single cloud file with more points than this is streamed into a voxel summary sized for -n "
                 "(memory bounded by the output size) instead of being held whole (about 2.1 KB per point)")
      ->capture_default_str();
  app.add_option("--stream-per-site", s.stream_limits.max_raw_points_per_site,
                 "... and so is one with more than this many points per site (-n): the output's resolution needs "
                 "only the voxel summary, which averages the noise down; 0 = no limit per site")
      ->capture_default_str();
  app.add_option("--flying-pixels", s.read_options.flying_pixels.neighbour_distance_ratio,
                 "organised PCD clouds (depth-camera frames): a pixel with fewer than 2 of its 8 grid neighbours "
                 "within this fraction of its range from the sensor (the file's VIEWPOINT) is a flying pixel mixed "
                 "from two depths at an edge, and is dropped; 0 keeps every pixel")
      ->capture_default_str();
  app.add_option("--depth-steps", s.read_options.depth_steps.max_distinct_fraction,
                 "a depth frame in its sensor's frame whose depth takes at most this fraction of the point count "
                 "as distinct values (the disparity steps of RGB-D and stereo cameras: terraces 1 cm apart at 2 m, "
                 "10-20 cm at 6 m) has each point's depth refitted on a plane through its image neighbours, moving "
                 "it along its ray by at most a step; clouds in a world frame are left as they are; 0 = never")
      ->capture_default_str();
  app.add_flag("--normals", s.write_normals, "write per-vertex normals (outward on closed pieces) with the mesh");
  app.add_flag("--keep-small",
               [&](std::int64_t) {
                 s.opt.mesher.min_piece_faces = 0, s.opt.mesher.min_piece_vertex_fraction = 0;
                 s.opt.stray.sparse_group_fraction = 0;
               },
               "keep every piece of the mesh; by default pieces of fewer than 20 triangles or fewer than 1 % of the "
               "vertices (stray bits of clutter) are dropped and counted in the report, and so are groups of the "
               "cloud with under 1 % of its points spread 4 times more sparsely than the rest (stray points; groups "
               "of fewer points than -k are always dropped: their neighbourhoods would bridge the gap)");
}

// Declares the output and reconstruction options: -o, -n, the cleaning, the CVT, the mesher, -q.
void add_reconstruction_options(CLI::App& app, Settings& s) {
  app.add_option("-o,--output", s.out_path, "output mesh (.ply .obj .off .stl)")->required();
  app.add_option("-n,--sites", s.opt.sites, "number of output vertices (CVT sites)")->capture_default_str();
  app.add_option("-i,--iterations", s.opt.iterations, "maximum heat Lloyd iterations (after the surface Lloyd; use 30 with --surface-lloyd 0)")->capture_default_str();
  app.add_option("-k,--neighbours,--neighbors", s.opt.neighbors,
                 "k nearest neighbours of the point Laplacian, in [" + std::to_string(ReconstructionOptions::min_neighbors) +
                     ", " + std::to_string(ReconstructionOptions::max_neighbors) + "]; more where they lie along a line (--spread-factor)")
      ->capture_default_str();
  app.add_option("--spread-factor", s.opt.cloud.spread.factor,
                 "where the -k nearest points lie along a line (the rings of a rotating lidar, the stripes of a line scanner), "
                 "neighbourhoods hold this many times the size at which 90 % of them span the surface (their second PCA "
                 "axis at least 0.05 of the first), up to 200; an isotropic sampling keeps -k; 0 = always -k")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--across-offset", s.opt.cloud.across_min_offset,
                 "where more than 8 % of the points have a neighbour of opposite normal, the point Laplacian still cuts "
                 "the pairs across a thin part (normals more than 120 deg apart, the second point off the first's "
                 "tangent plane by at least this fraction of their distance: the faces of a plate or a wall about a "
                 "neighbourhood thick) when they are at least 3/4 of those pairs; 0 = no cut there")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--anisotropy", s.opt.anisotropy, "lambda of the anisotropic lift (p, lambda n); 0 = isotropic")
      ->capture_default_str();
  app.add_option("--adaptive", s.opt.adaptive.adaptivity,
                 "curvature-adaptive sizing: edge length ~ curvature^(-A/2), finer at tips, rims and creases, the "
                 "vertex count kept (0 = uniform; 1 = the same chord error everywhere)")
      ->capture_default_str();
  app.add_option("--size-ratio", s.opt.adaptive.max_size_ratio, "with --adaptive: largest over smallest edge length")
      ->capture_default_str();
  app.add_flag("--denoise", s.opt.denoise, "statistical outlier removal before reconstruction");
  app.add_option("--denoise-k", s.opt.denoise_neighbors, "with --denoise: neighbours of the outlier statistics")
      ->capture_default_str();
  app.add_option("--denoise-stddev", s.opt.denoise_stddev,
                 "with --denoise: points farther than mean + this many standard deviations are outliers")
      ->capture_default_str();
  app.add_option("--stray-ratio", s.opt.stray.ratio,
                 "a point whose 16th nearest neighbour is more than this times farther than the median of the same "
                 "distance over those neighbours is a stray point (isolated returns, groups of fewer than about 8 "
                 "points off the surface) and is removed; 0 turns this rule off (groups of the cloud with fewer "
                 "points than -k, or with under 1 % of the points spread 4 times more sparsely than the rest, still "
                 "go: see --keep-small)")
      ->capture_default_str();
  app.add_option("--voxel", s.opt.voxel_size, "voxel-grid downsampling size in input units; 0 = off")
      ->capture_default_str();
  cli::add_time_coefficient_option(app, s.opt.time_coefficient);
  app.add_option("--seed", s.opt.seed, "seed of the initial sites")->capture_default_str();
  app.add_option("--count-retries", s.opt.count_retries,
                 "where the mesh is more than --retry-count-error * -n off the count, or leaves more than a fifth of "
                 "the points farther than a site spacing (not where they fill a volume or the part left out is "
                 "smaller than a spacing), run the CVT and the mesher again from the start sites of the next seeds, at "
                 "most this many times, and keep the best result (0 = never)")
      ->capture_default_str();
  app.add_option("--retry-count-error", s.opt.retry_count_error, "see --count-retries (a fraction of -n)")
      ->capture_default_str();
  app.add_option("--finer-retry", s.opt.finer_retry_factor,
                 "where the mesh still leaves more than a fifth of the points out after --count-retries (by the same "
                 "rule), reconstruct once more on this many times the sites, sized to -n, and keep it where it is "
                 "better (parts too thin for the cells of -n); only where the cloud has 10 points per finer site "
                 "(1 = never)")
      ->capture_default_str();
  app.add_option("--dense-pieces", s.opt.dense_pieces.min_point_fraction,
                 "a separate part holding at least this fraction of the points but too little of the area for a "
                 "piece of its own at -n (a small object scanned closely beside a large one) is meshed on its own "
                 "sites, at least 24 and 2 % of -n, and the rest on the sites left; 0 = never")
      ->capture_default_str();
  app.add_option("--tip-growth", s.opt.coverage.grow_gap,
                 "where CVT points stay more than this many site spacings from the mesh after the tips' vertices "
                 "were moved (a claw or finger several spacings long, cut off whole), vertices are inserted there "
                 "and moved out along it, at most 0.5 % of -n in all; 0 = vertices are only moved")
      ->capture_default_str();
  app.add_option("--relaxation", s.opt.lloyd_relaxation, "Lloyd over-relaxation factor in [1, 2); 1 = plain Lloyd")
      ->capture_default_str();
  app.add_option("--tolerance", s.opt.lloyd_tolerance,
                 "stop the heat Lloyd iterations when no site moves more than TOL * sqrt(area / sites); 0 = run all")
      ->capture_default_str();
  app.add_option("--mean-tolerance", s.opt.lloyd_mean_tolerance,
                 "stop the heat Lloyd iterations when the mean site move is below TOL * sqrt(area / sites); 0 = run all")
      ->capture_default_str();
  app.add_option("--max-hole-edges", s.opt.max_hole_edges,
                 "fill boundary loops of up to this many edges (longer ones under the conditions of reconstruct.h)")
      ->capture_default_str();
  app.add_option("--polish-iterations", s.opt.relaxation_iterations,
                 "final polish: tangential relaxation + edge flip iterations; 0 = the plain dual")
      ->capture_default_str();
  app.add_flag("--fast-start", s.opt.farthest_point_start,
               "with --surface-lloyd 0: farthest-point initial sites relaxed on the point graph instead of seeded "
               "random ones (the paper's)");
  app.add_option("--surface-lloyd", s.opt.surface_lloyd_iterations,
                 "iterations of the cheap surface Lloyd on farthest-point start sites (during the factorisation); "
                 "0 = the paper's seeded random start")
      ->capture_default_str();
  app.add_option("--points-per-site", s.opt.cvt_points_per_site,
                 "the CVT runs on a uniform subset of about this many points per site (site positions are still "
                 "fitted to every point; a streamed file is summarised into this many voxel points per site); 0 = "
                 "every point")
      ->capture_default_str();
  app.add_flag("--no-smooth-cvt-points", [&](std::int64_t) { s.opt.smooth_cvt_points = false; },
               "build the Laplacian on the raw CVT points instead of their projections onto the fitted surface");
  cli::add_threads_option(app, s.opt.threads);
  app.add_option("--report", s.report_path, "write a JSON report");
  app.add_flag("-q,--quiet", s.quiet, "no progress and no summary");
}

// Option checks before any work, naming the option at fault; then the output paths.
void check_settings(const Settings& s) {
  check_options(s.opt);
  if (const double r = s.read_options.flying_pixels.neighbour_distance_ratio; !(r >= 0) || !std::isfinite(r))
    throw InvalidInputError("--flying-pixels must be a finite number >= 0 (0 keeps every pixel)");
  if (const double q = s.read_options.depth_steps.max_distinct_fraction; !(q >= 0 && q <= 1))
    throw InvalidInputError("--depth-steps must be a fraction in [0, 1] (0 = never)");
  if (s.cloud_paths.empty() && s.conf_path.empty())
    throw InvalidInputError("no input: give the clouds as CLOUD arguments or with --conf");
  if (!s.cloud_paths.empty() && !s.conf_path.empty())
    throw InvalidInputError("give the input clouds either as CLOUD arguments or with --conf, not both");
  if (!s.pose_paths.empty() && s.pose_paths.size() != s.cloud_paths.size())
    throw InvalidInputError("--pose: " + std::to_string(s.pose_paths.size()) + " poses for " +
                            std::to_string(s.cloud_paths.size()) + " clouds (give one per CLOUD, in order)");
  cli::check_output_path(s.out_path, {".ply", ".obj", ".off", ".stl"});
  std::string out_ext = std::filesystem::path(s.out_path).extension().string();
  std::transform(out_ext.begin(), out_ext.end(), out_ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (s.write_normals && out_ext != ".ply" && out_ext != ".obj")
    throw InvalidInputError(s.out_path + ": --normals needs a .ply or .obj output (.off and .stl carry no vertex normals)");
  cli::check_output_path(s.report_path, {".json"});
  cli::check_distinct_outputs({{"-o", s.out_path}, {"--report", s.report_path}});
}

// The scans to merge (--conf, or the CLOUD arguments with their poses); no output may overwrite one.
std::vector<ScanInput> list_scans(const Settings& s) {
  std::vector<ScanInput> scans;
  if (!s.conf_path.empty()) scans = read_stanford_conf(s.conf_path);
  for (size_t i = 0; i < s.cloud_paths.size(); ++i)
    scans.push_back({s.cloud_paths[i], s.pose_paths.empty() ? Eigen::Isometry3d::Identity() : read_pose_file(s.pose_paths[i])});
  std::vector<std::string> inputs{s.conf_path};
  for (const ScanInput& scan : scans) inputs.push_back(scan.path);
  inputs.insert(inputs.end(), s.pose_paths.begin(), s.pose_paths.end());
  cli::check_distinct_outputs({{"-o", s.out_path}, {"--report", s.report_path}}, inputs);
  return scans;
}

// How messages and the report name the input: the one file, the .conf, or the first file and a count.
std::string input_label(const std::vector<ScanInput>& scans, const std::string& conf_path) {
  return scans.size() == 1 ? scans[0].path : !conf_path.empty() ? conf_path
         : scans[0].path + " (+" + std::to_string(scans.size() - 1) + " more)";
}

// Reads the scans whole, checks the merged cloud against the options and reconstructs its surface.
void reconstruct_whole(const Settings& s, const std::vector<ScanInput>& scans, const std::string& cloud_path,
                       Reconstruction& rec) {
  CloudReadOptions read = s.read_options;
  read.depth_steps.threads = s.opt.threads;
  rec.cloud = read_scans(scans, &rec.rr, read);
  cli::log_line(s.quiet, "read " + cloud_path + ": " + std::to_string(rec.rr.points_in_file) + " points, " +
                             std::to_string(rec.rr.non_finite_dropped) + " non-finite dropped, " +
                             std::to_string(rec.rr.flying_pixels_removed) + " flying pixels dropped, " +
                             std::to_string(rec.rr.duplicates_merged) + " duplicates merged");
  reject_far_outliers(rec.cloud.P, cloud_path);
  if (s.opt.sites > rec.cloud.P.rows())
    throw InvalidInputError(cloud_path + ": -n " + std::to_string(s.opt.sites) + " exceeds the " +
                            std::to_string(rec.cloud.P.rows()) + " usable points");
  reject_tiny_voxel(rec.cloud.P, s.opt.voxel_size, cloud_path);
  cli::Progress bar("reconstructing", 1000, s.quiet);
  rec.res = cli::on_file(cloud_path, [&] { return reconstruct_surface(rec.cloud.P, s.opt, stage_progress(bar)); });
  bar.finish();
}

// The reconstruction of the scans: streamed when one large file allows it, else from the whole cloud.
Reconstruction reconstruct(const Settings& s, const std::vector<ScanInput>& scans, const std::string& cloud_path) {
  Reconstruction rec;
  if (s.stream_limits.max_raw_points < 0) throw InvalidInputError("--stream-above must be >= 0");
  if (!(s.stream_limits.max_raw_points_per_site >= 0 && std::isfinite(s.stream_limits.max_raw_points_per_site)))
    throw InvalidInputError("--stream-per-site must be a finite number >= 0");
  rec.stream = should_stream(scans, s.opt, s.stream_limits);
  if (rec.stream) {
    rec.streamed = reconstruct_streamed(scans[0].path, s.opt, s.read_options, s.stream_limits, s.quiet);
    rec.res = std::move(rec.streamed.result);
    rec.cloud = std::move(rec.streamed.cloud);
    rec.rr.format = CloudChunkReader(scans[0].path).format();
    rec.rr.points_in_file = rec.streamed.points_read;
    rec.rr.flying_pixels_removed = static_cast<long>(rec.streamed.flying_pixels_removed);
    rec.rr.depth_steps = rec.streamed.depth_steps;
  } else {
    reconstruct_whole(s, scans, cloud_path, rec);
  }
  return rec;
}

// Colour (when every input point has one) and, on request, normals of the output vertices.
MeshAttributes output_attributes(const Settings& s, const Reconstruction& rec) {
  MeshAttributes attributes;
  if (rec.cloud.has_colours()) {
    ColourTransferOptions copt;
    copt.threads = s.opt.threads;
    attributes.vertex_color = transfer_colours(rec.cloud.P, rec.cloud.C, rec.res.mesh.V, copt);
  }
  if (s.write_normals) attributes.vertex_normal = vertex_normals(rec.res.mesh.V, rec.res.mesh.F);
  return attributes;
}

// Writes the mesh and the report: all or none.
void write_outputs(const Settings& s, const TriangleMesh& mesh, const MeshAttributes& attributes, const cli::Json& j) {
  OutputTransaction outputs;  // all outputs or none (atomic_file.h)
  write_mesh(s.out_path, mesh.V, mesh.F, attributes);
  if (!s.report_path.empty()) cli::write_json(s.report_path, j);
  outputs.commit();
}

// Adds the figures of the run beyond make_report()'s: inputs, streaming, peak memory, colours, holes.
void add_run_figures(cli::Json& j, size_t inputs, int sites, const Reconstruction& rec) {
  j["inputs"] = static_cast<long>(inputs);
  j["streamed"] = rec.stream;
  j["voxel_size"] = rec.streamed.voxel_size;
  j["noise_spacings"] = rec.streamed.noise_spacings;
  j["cvt_sites"] = rec.stream ? rec.streamed.cvt_sites : sites;
  j["peak_memory_mb"] = peak_memory_mb();
  j["colours"] = rec.cloud.has_colours();
  j["filled_hole_edges"] = rec.res.filled_hole_edges;
}

// Prints how much of the cloud the mesh covers and a warning where the points fill a band or a
// volume, or where the mesh covers the cloud only in part, with the largest group it left out
// (cloud_coverage.h).
void print_cloud_coverage(const CloudCoverage& c) {
  if (c.queries == 0) return;
  std::printf("  coverage: %.1f %% of the points within one site spacing of the mesh; the points lie %.2f spacings "
              "thick\n",
              100.0 * (1 - c.uncovered_share), c.thickness_spacings);
  if (c.volumetric())
    std::printf("  warning: the points fill a band or a volume %.2f site spacings thick (from %.2f they do not sample "
                "a surface at this spacing): the mesh follows no surface of them; a smaller -n, --denoise or "
                "--voxel may help where it is noise\n",
                c.thickness_spacings, c.volume_thickness);
  if (!c.partial()) return;
  std::printf("  warning: the mesh covers the cloud only in part: %.1f %% of the points are farther than one site "
              "spacing from it; the largest group of them holds %.1f %% of the points and is %.1f spacings across",
              100.0 * c.uncovered_share, 100.0 * c.largest_group_share, c.largest_group_spacings);
  if (c.largest_group_spacings < 1)
    std::printf(" (smaller than one site spacing: a larger -n meshes it)");
  std::printf("\n");
}

// A warning where the mesh is off -n by more than the sizing's tolerance (IsotropicRemeshOptions::
// count_tolerance), with what explains it: the run on finer sites kept at its finer count, sites
// left in no triangle and small pieces dropped, or no remesh at the count that passed the checks.
void print_count_warning(const ReconstructionResult& res, const ReconstructionOptions& opt) {
  const long vertices = static_cast<long>(res.mesh.V.rows());
  if (std::abs(static_cast<double>(vertices - opt.sites)) <= opt.mesher.sizing.count_tolerance * opt.sites) return;
  std::printf("  warning: %ld vertices for the %d asked for (%+.0f %%): ", vertices, opt.sites,
              100.0 * static_cast<double>(vertices - opt.sites) / opt.sites);
  if (res.finer_retry_sites > 0 && !res.sized)
    std::printf("the mesh on %d sites was kept (parts too thin for the cells of -n) and could not be coarsened to -n "
                "without breaking them\n",
                res.finer_retry_sites);
  else
    std::printf("%d sites left in no triangle, %d small pieces dropped, and no remesh at -n passed the checks%s\n",
                res.unused_sites, res.pieces_removed,
                vertices < opt.sites ? " (a smaller -n, or --keep-small, may meet it)" : "");
}

// The check that the mesh covers the cloud: at most CloudCoverageOptions::partial_share of the
// points farther than a site spacing from it (cloud_coverage.h). Every mesh check can pass on a
// mesh of one part of the cloud (a cluster below the spacing, a sheet the dual lost); the run then
// ends with exit status 3, as for any failed check. Empty where the coverage was not measured.
std::vector<cli::CheckRecord> coverage_check(const CloudCoverage& c) {
  if (c.queries == 0) return {};
  char detail[256];
  std::snprintf(detail, sizeof detail,
                "%.1f %% of the %d points measured farther than one site spacing from the mesh (at most %.0f %%)",
                100.0 * c.uncovered_share, c.queries, 100.0 * c.partial_share);
  return {{"covers_cloud", !c.partial(), true, detail}};
}

// Prints what the refit of quantised depth found and did (depth_steps.h), where the depth is quantised.
void print_depth_steps(const DepthStepReport& d) {
  if (!d.quantised) return;
  static const char* const axes[] = {"x", "y", "z"};
  std::printf("  depth steps: the %s depth of this frame takes %ld values (median step %g); %ld points refitted, "
              "by %.2f steps on average, in %.2f s (--depth-steps 0 keeps them)\n",
              axes[d.axis], static_cast<long>(d.levels), d.median_step, static_cast<long>(d.points_moved),
              d.mean_move_steps, d.seconds);
}

// Prints the summary of a run on stdout: points, times, the mesh, its quality and border, the checks.
void print_summary(const Settings& s, const std::string& cloud_path, const Reconstruction& rec, double per_iter,
                   double total_s, const std::vector<cli::CheckRecord>& checks) {
  const CloudReadReport& rr = rec.rr;
  const ReconstructionResult& res = rec.res;
  const ReconstructionOptions& opt = s.opt;
  const ValidationReport& val = res.validation;
  const StreamedReconstruction& streamed = rec.streamed;
  std::printf("cloud2mesh: %s -> %s\n", cloud_path.c_str(), s.out_path.c_str());
  std::printf("  points: %ld read, %ld non-finite dropped, %ld flying pixels dropped, %ld duplicates merged, "
              "%d outliers removed, %d stray points removed, %d voxel-merged, %d used\n",
              rr.points_in_file, rr.non_finite_dropped, rr.flying_pixels_removed, rr.duplicates_merged + res.points_merged,
              res.points_denoised, res.points_stray, res.points_voxel_removed, res.points_used);
  print_depth_steps(rr.depth_steps);
  std::printf("  time: Laplacian %.3f s, factor %.3f s, CVT %.3f s (%d heat iterations, %.3f s each), total %.3f s\n",
              res.laplacian_seconds, res.factor_seconds, res.cvt_seconds, res.iterations, per_iter, total_s);
  cli::print_stages(res.stage_seconds);
  std::printf("  mesh: %ld vertices, %ld faces, %d components, %d boundary loops, genus %d; %d holes filled, "
              "%d vertices left in no triangle, %d small pieces dropped, %d flying faces removed%s\n",
              static_cast<long>(res.mesh.V.rows()), static_cast<long>(res.mesh.F.rows()), val.components,
              val.boundary_loops, val.genus, res.holes_filled, res.unused_sites, res.pieces_removed,
              res.flying_faces, res.sized ? ", sized to -n" : "");
  if (res.count_retries > 0 && res.finer_retry_sites > 0)
    std::printf("  retries: %d more CVT and mesher runs for a mesh far off -n or covering the cloud in part; kept "
                "the one on %d CVT sites (parts too thin for the cells of -n), %s\n",
                res.count_retries, res.finer_retry_sites,
                res.sized ? "sized to -n" : "which the sizing could not coarsen to -n without breaking them");
  else if (res.count_retries > 0)
    std::printf("  retries: %d more CVT and mesher runs for a mesh far off -n or covering the cloud in part; kept "
                "the one from seed %u\n",
                res.count_retries, res.seed_used);
  if (res.dense_pieces > 0)
    std::printf("  dense pieces: %d parts holding many points on little area meshed on their own sites, the rest "
                "on the sites left\n",
                res.dense_pieces);
  const std::string boundary = val.boundary_loops > 0 ? format_angle(res.boundary_min_angle_deg) : "none";
  std::printf("  quality: phi_min %.2f deg (boundary triangles %s), phi_m %.2f deg\n", res.min_angle_deg,
              boundary.c_str(), res.mean_min_angle_deg);
  if (res.border.mesh_border_vertices > 0 && res.border.edge_points > 0)
    std::printf("  border: %.1f %% of the %d border vertices within one site spacing of the scan's edge (90 %% "
                "within %.2f), %.1f %% of the scan's %d edge points within one spacing of the mesh\n",
                100.0 * res.border.mesh_border_on_edge, res.border.mesh_border_vertices,
                res.border.mesh_border_distance, 100.0 * res.border.edge_covered, res.border.edge_points);
  print_cloud_coverage(res.cloud_coverage);
  print_count_warning(res, opt);
  if (res.coverage.moves > 0)
    std::printf("  tips: %d vertices moved onto the fitted surface the mesh had cut off, %d of them inserted on "
                "parts longer than a moved vertex reaches (%d CVT points farther than half a spacing from it "
                "before, %d after)\n",
                res.coverage.moves, res.coverage.inserted, res.coverage.uncovered_before, res.coverage.uncovered_after);
  if (res.coverage.skipped)
    std::printf("  tips: not repaired: %d CVT points farther than half a spacing from the mesh, more than a tip "
                "leaves (the mesh misses whole parts; see the coverage line)\n",
                res.coverage.uncovered_before);
  // The point Laplacian resolves a heat cell from about 10 points (ReconstructionOptions::
  // cvt_points_per_site); far fewer leave holes and slivers the mesher can only patch.
  const double points_per_site = static_cast<double>(res.points_used) / opt.sites;
  if (!rec.stream && points_per_site < kFewPointsPerSite)
    std::printf("  note: only %.1f points per site; the surface is undersampled for -n %d (about 10 per site "
                "give a clean mesh): a smaller -n gives a better one\n",
                points_per_site, opt.sites);
  if (res.neighbors_cvt > opt.neighbors)
    std::printf("  neighbours: %d on the CVT points, %d in the surface fit (-k %d): the sampling is in rows, whose %d "
                "nearest points lie along a line\n",
                res.neighbors_cvt, res.neighbors_fit, opt.neighbors, opt.neighbors);
  if (rec.stream)
    std::printf("  streamed: %ld points in %d passes into voxels of %g, reconstructed from %ld voxel points\n",
                static_cast<long>(streamed.points_read), streamed.passes, streamed.voxel_size,
                static_cast<long>(rec.cloud.P.rows()));
  if (rec.stream && streamed.cvt_sites < opt.sites)
    std::printf("  noise: %.2f site spacings wide (the limit is %.2f): the CVT ran on %d sites, the mesh was sized to "
                "-n on the fitted surface\n",
                streamed.noise_spacings, StreamOptions{}.max_noise_spacings, streamed.cvt_sites);
  std::printf("  peak memory: %.0f MB\n", peak_memory_mb());
  cli::print_checks(checks);
  std::printf("  wrote %s%s\n", s.out_path.c_str(), s.report_path.empty() ? "" : (", " + s.report_path).c_str());
}

// Mean seconds per heat Lloyd iteration of a reconstruction (0 without iterations).
double seconds_per_iteration(const ReconstructionResult& res) {
  double iteration_sum = 0;
  for (double t : res.iteration_seconds) iteration_sum += t;
  return res.iterations > 0 ? iteration_sum / res.iterations : 0.0;
}

// The whole run after parsing: checks, input, reconstruction, report, outputs, summary; the exit status.
int run(const Settings& s) {
  check_settings(s);
  const auto t_start = Clock::now();
  const std::vector<ScanInput> scans = list_scans(s);
  const std::string cloud_path = input_label(scans, s.conf_path);
  const Reconstruction rec = reconstruct(s, scans, cloud_path);
  const double total_s = cli::seconds_since(t_start);
  const double per_iter = seconds_per_iteration(rec.res);
  const MeshAttributes attributes = output_attributes(s, rec);
  std::vector<cli::CheckRecord> checks = cli::check_records(rec.res.validation);
  for (cli::CheckRecord& c : coverage_check(rec.res.cloud_coverage)) checks.push_back(std::move(c));
  cli::Json j = make_report(cloud_path, {s.out_path, s.report_path}, rec.rr, s.opt, rec.res, per_iter, total_s);
  add_run_figures(j, scans.size(), s.opt.sites, rec);
  const int status = cli::finish_report(j, rec.res.stage_seconds, checks);
  write_outputs(s, rec.res.mesh, attributes, j);
  if (!s.quiet) print_summary(s, cloud_path, rec, per_iter, total_s, checks);
  if (status != cli::exit_ok) cli::log_line(s.quiet, "warning: the reconstruction failed some checks (exit status 3)");
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cloud2mesh: reconstruct a triangle mesh from a point cloud with a heat-diffusion centroidal "
               "Voronoi tessellation of the points (Herholz et al. 2017, §7-8)"};
  Settings settings;
  add_input_options(app, settings);
  add_reconstruction_options(app, settings);
  return cli::parse_and_run(app, argc, argv, "cloud2mesh", [&] { return run(settings); });
}
