// meshcvt: intrinsic (optionally anisotropic) CVT remeshing of a triangle mesh by Lloyd iteration
// with heat Voronoi cells and heat centroids (Herholz et al. 2017, §6–7.1). Writes the dual
// triangulation of the final CVT and reports its quality and the CGAL surface checks.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "cell_colors.h"
#include "cli_common.h"
#include "heatcvt/atomic_file.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/remesh.h"
#include "heatcvt/validate.h"
#include "heatcvt/weld.h"
#include "report_json.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

namespace {

// The CVT's φmin target (degrees) when the dual is the output (--no-post-cvt).
constexpr double kDualPhiMin = 25.0;

// The command line of meshcvt. Defaults shown by --help: the best measured configuration
// (fast_cvt_options); --paper switches every option not given explicitly to the paper's plain
// Lloyd (CvtOptions{}).
struct Settings {
  explicit Settings(const RemeshOptions& defaults = RemeshOptions{})
      : cvt(defaults.cvt),
        min_vertices_per_site(defaults.min_vertices_per_site),
        flat_angle_deg(defaults.refinement.flat_angle_deg),
        needle_share(defaults.needle_area_share),
        needle_angle_deg(defaults.needle_angle_deg),
        repair_rounds(defaults.repair_rounds),
        no_post(!defaults.post_cvt_stages),
        no_features(!defaults.creases.enabled),
        crease_angle(defaults.creases.min_dihedral_deg),
        init(cvt.initialization == CvtInitialization::farthest_point ? "farthest" : "random"),
        relaxation(cvt.relaxation),
        graph_lloyd(cvt.graph_lloyd_iterations),
        surface_lloyd(cvt.surface_lloyd_iterations),
        no_split(!cvt.split_nonmanifold_cells),
        sites(cvt.sites),
        iterations(cvt.iterations),
        threads(cvt.threads),
        seed(cvt.seed),
        tolerance(cvt.tolerance),
        t_coef(cvt.time_coefficient),
        quality_every(cvt.quality_every),
        target_mean(cvt.target_phi_mean_deg),
        target_min(cvt.target_phi_min_deg) {}

  CvtOptions cvt;  // the CVT options no flag sets (the paper's with --paper)
  double min_vertices_per_site;
  double flat_angle_deg, needle_share, needle_angle_deg;
  bool midpoint_refinement = false;
  int repair_rounds;
  bool no_post, no_features;
  double crease_angle;
  std::string mesh_path, out_path, cells_path, report_path, init;
  double relaxation;
  int graph_lloyd, surface_lloyd;
  bool no_split, paper = false;
  int sites, iterations, threads;
  unsigned seed;
  double anisotropy = 0.0, tolerance, t_coef;
  AdaptiveSizingOptions adaptive;
  int quality_every;
  double target_mean, target_min;
  bool quiet = false;
};

// Declares the input, output and Lloyd-iteration options (the first half of --help).
void add_lloyd_options(CLI::App& app, Settings& s) {
  app.add_option("MESH", s.mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("-n,--sites", s.sites, "number of sites = vertices of the output")->capture_default_str();
  app.add_option("-o,--output", s.out_path, "output dual triangulation (.obj .ply .off)")->required();
  app.add_option("-i,--iterations", s.iterations, "maximum number of Lloyd iterations")->capture_default_str();
  app.add_option("--tolerance", s.tolerance,
                 "stop when no site moves more than TOL * sqrt(area / sites) (0 = run all iterations)")
      ->capture_default_str();
  app.add_option("--quality-every", s.quality_every,
                 "every K iterations build the dual of the current sites and measure phi_min / phi_m (0 = never)")
      ->capture_default_str();
  app.add_option("--target-phi-m", s.target_mean,
                 "with --quality-every: stop once phi_m >= this and phi_min >= --target-phi-min (0 = off)")
      ->capture_default_str();
  app.add_option("--target-phi-min", s.target_min,
                 "see --target-phi-m (degrees; 0 = off: the post-CVT stages raise phi_min; with --no-post-cvt the "
                 "default is " + std::to_string(static_cast<int>(kDualPhiMin)) + ")")
      ->capture_default_str();
  app.add_option("--anisotropy", s.anisotropy,
                 "lambda of the anisotropic CVT: lift to (p, lambda n) in R^6 after scaling to the unit bounding "
                 "box (paper: 0.05; 0 = isotropic)")
      ->capture_default_str();
  app.add_option("--adaptive", s.adaptive.adaptivity,
                 "curvature-adaptive sizing: edge length ~ curvature^(-A/2), finer where the surface bends, the vertex "
                 "count kept (0 = uniform; 1 = the same chord error everywhere)")
      ->capture_default_str();
  app.add_option("--size-ratio", s.adaptive.max_size_ratio,
                 "with --adaptive: largest over smallest edge length")
      ->capture_default_str();
  app.add_option("--init", s.init, "initial sites: random (area-uniform) or farthest (farthest-point sampling)")
      ->capture_default_str()
      ->check(CLI::IsMember({"random", "farthest"}));
  app.add_option("--seed", s.seed, "random seed of the initial sites")->capture_default_str();
  cli::add_time_coefficient_option(app, s.t_coef);
  cli::add_threads_option(app, s.threads);
  app.add_option("--cells", s.cells_path, "also write the tessellated input with a cell id per face (.ply)");
  app.add_option("--report", s.report_path, "also write the final report as JSON");
  app.add_option("--relaxation", s.relaxation,
                 "Lloyd over-relaxation omega in [1, 2) (1 = plain Lloyd; safeguarded by the cell-area variance)")
      ->capture_default_str();
}

// Declares the start, repair and post-CVT options (the second half of --help).
void add_stage_options(CLI::App& app, Settings& s) {
  app.add_option("--graph-lloyd", s.graph_lloyd,
                 "graph-Lloyd iterations on the initial sites, run during the factorisation (0 = off)")
      ->capture_default_str();
  app.add_option("--surface-lloyd", s.surface_lloyd,
                 "surface-Lloyd iterations on the initial sites (restricted Euclidean cells, exact centroids "
                 "projected onto the surface), run during the factorisation; the start sites' quality is checked "
                 "before the first heat iteration (0 = off)")
      ->capture_default_str();
  app.add_flag("--no-split", s.no_split,
               "keep the site count: do not add sites to cells that are too big for thin parts (non-manifold dual)");
  app.add_option("--min-vertices-per-site", s.min_vertices_per_site,
                 "refine the input (surface unchanged) until it has this many vertices per site, so more sites than "
                 "input vertices work (0 = never refine): by midpoint subdivision, or, where more than 5 % of the area "
                 "of an oriented manifold lies in needles (an angle below 5 degrees: CAD fans and strips), at any vertex "
                 "count by long edges split at their midpoints and edges between faces in one plane flipped to Delaunay")
      ->capture_default_str();
  app.add_option("--needle-share", s.needle_share,
                 "the splits and flips refine an oriented manifold (at any vertex count) where more than this share of its "
                 "area lies in needles (faces with an angle below --needle-angle); otherwise midpoint subdivision")
      ->capture_default_str();
  app.add_option("--needle-angle", s.needle_angle_deg, "a needle has an angle below this (degrees)")->capture_default_str();
  app.add_flag("--midpoint-refinement", s.midpoint_refinement,
               "refine the input by midpoint subdivision only (its triangles keep their shapes, needles included)");
  app.add_option("--flat-angle", s.flat_angle_deg,
                 "the refinement flips an edge only where its two faces' normals differ by less than this (degrees; "
                 "0 = exactly coplanar faces only)")
      ->capture_default_str();
  app.add_option("--repair-rounds", s.repair_rounds,
                 "rounds of adding a site to every cell at a non-manifold spot of the dual (and sites on boundary loops "
                 "of the input with fewer than three cells or sharing a cell with another loop; up to 3 more rounds "
                 "where only loops need them), and running the CVT again (0 = no repair)")
      ->capture_default_str();
  app.add_flag("--no-post-cvt", s.no_post,
               "write the dual triangulation itself, without the post-CVT stages (manifold extraction, hole filling, "
               "untangling, polish, sliver collapse, edge splits; the input mesh is their projector)");
  app.add_flag("--no-features", s.no_features,
               "do not keep sharp creases nor border corners: by default edges of the input whose faces meet at more "
               "than --crease-angle are kept as edge paths of the output, their corners fixed, and so are the corners "
               "of an open input's border (turns above 60 degrees at the output's spacing) with the border between them");
  app.add_option("--crease-angle", s.crease_angle, "dihedral angle (degrees) above which an input edge is a sharp crease")
      ->capture_default_str();
  app.add_flag("--paper", s.paper,
               "the paper's configuration for every option not given: random start, plain Lloyd, 100 iterations, "
               "no quality evaluation or target, no splitting, no repair rounds, no post-CVT stages");
  app.add_flag("-q,--quiet", s.quiet, "no progress and no report on the terminal");
}

// Sets what the options not given default to: φmin target of the dual output; the paper's
// configuration with --paper.
void apply_implied_defaults(const CLI::App& app, Settings& s) {
  auto given = [&](const char* name) { return app.count(name) > 0; };
  // Without the post-CVT stages the dual is the output: the CVT itself must reach φmin.
  if (s.no_post && !s.paper && !given("--target-phi-min")) s.target_min = kDualPhiMin;
  if (!s.paper) return;
  const CvtOptions paper_cvt;
  if (!given("--iterations")) s.iterations = paper_cvt.iterations;
  if (!given("--quality-every")) s.quality_every = paper_cvt.quality_every;
  if (!given("--target-phi-m")) s.target_mean = paper_cvt.target_phi_mean_deg;
  if (!given("--target-phi-min")) s.target_min = paper_cvt.target_phi_min_deg;
  if (!given("--init")) s.init = "random";
  if (!given("--relaxation")) s.relaxation = paper_cvt.relaxation;
  if (!given("--graph-lloyd")) s.graph_lloyd = paper_cvt.graph_lloyd_iterations;
  if (!given("--surface-lloyd")) s.surface_lloyd = paper_cvt.surface_lloyd_iterations;
  if (!given("--no-split")) s.no_split = !paper_cvt.split_nonmanifold_cells;
  if (!given("--repair-rounds")) s.repair_rounds = 0;
  if (!given("--no-post-cvt")) s.no_post = true;
  if (!given("--no-features")) s.no_features = true;
  s.cvt = paper_cvt;
}

// Option checks before any work, naming the option at fault; then the output paths.
void check_settings(const Settings& s) {
  if (!(s.relaxation >= 1 && s.relaxation < 2)) throw InvalidInputError("--relaxation must be in [1, 2)");
  if (s.graph_lloyd < 0) throw InvalidInputError("--graph-lloyd must be >= 0");
  if (s.surface_lloyd < 0) throw InvalidInputError("--surface-lloyd must be >= 0");
  // Fewer than 4 sites make at most one triangle (a tetrahedron is the smallest closed dual).
  if (s.sites < 4) throw InvalidInputError("--sites must be at least 4, got " + std::to_string(s.sites));
  if (s.iterations < 0) throw InvalidInputError("--iterations must be >= 0, got " + std::to_string(s.iterations));
  if (!(s.tolerance >= 0) || !std::isfinite(s.tolerance)) throw InvalidInputError("--tolerance must be >= 0");
  if (!(s.anisotropy >= 0) || !std::isfinite(s.anisotropy)) throw InvalidInputError("--anisotropy must be >= 0");
  if (!(s.adaptive.adaptivity >= 0 && s.adaptive.adaptivity <= 2)) throw InvalidInputError("--adaptive must be in [0, 2]");
  if (!(s.adaptive.max_size_ratio >= 1) || !std::isfinite(s.adaptive.max_size_ratio))
    throw InvalidInputError("--size-ratio must be a number >= 1");
  cli::check_time_coefficient(s.t_coef);
  cli::check_threads(s.threads);
  if (!(s.min_vertices_per_site >= 0) || !std::isfinite(s.min_vertices_per_site))
    throw InvalidInputError("--min-vertices-per-site must be a number >= 0");
  if (!(s.flat_angle_deg >= 0 && s.flat_angle_deg < 90))
    throw InvalidInputError("--flat-angle must be a number of degrees in [0, 90)");
  if (!(s.needle_share >= 0 && s.needle_share <= 1)) throw InvalidInputError("--needle-share must be a number in [0, 1]");
  if (!(s.needle_angle_deg >= 0 && s.needle_angle_deg <= 60))
    throw InvalidInputError("--needle-angle must be a number of degrees in [0, 60]");
  if (s.repair_rounds < 0) throw InvalidInputError("--repair-rounds must be >= 0");
  if (!(s.crease_angle > 0 && s.crease_angle < 180)) throw InvalidInputError("--crease-angle must be in (0, 180) degrees");
  if (s.quality_every < 0) throw InvalidInputError("--quality-every must be >= 0");
  if (!(s.target_mean >= 0 && s.target_mean <= 60) || !(s.target_min >= 0 && s.target_min <= 60))
    throw InvalidInputError("--target-phi-m / --target-phi-min must be angles in [0, 60] degrees");
  if ((s.target_mean > 0 || s.target_min > 0) && s.quality_every == 0)
    throw InvalidInputError("--target-phi-m / --target-phi-min need --quality-every K > 0");
  cli::check_output_path(s.out_path, {".obj", ".ply", ".off"});
  cli::check_output_path(s.cells_path, {".ply"});
  cli::check_output_path(s.report_path, {".json"});
  cli::check_distinct_outputs({{"-o", s.out_path}, {"--cells", s.cells_path}, {"--report", s.report_path}},
                              {s.mesh_path});
}

// The options of remesh_cvt() that the settings ask for.
RemeshOptions remesh_options(const Settings& s) {
  RemeshOptions remesh;
  remesh.anisotropy = s.anisotropy;
  remesh.adaptive = s.adaptive;
  remesh.min_vertices_per_site = s.min_vertices_per_site;
  remesh.refinement.flat_angle_deg = s.flat_angle_deg;
  remesh.needle_area_share = s.needle_share;
  remesh.needle_angle_deg = s.needle_angle_deg;
  if (s.midpoint_refinement) remesh.refinement_method = RemeshOptions::Refinement::midpoint;
  remesh.repair_rounds = s.repair_rounds;
  if (s.repair_rounds == 0) remesh.loop_repair_rounds = 0;  // no repair at all
  remesh.post_cvt_stages = !s.no_post;
  remesh.creases.enabled = !s.no_features;
  remesh.creases.min_dihedral_deg = s.crease_angle;
  remesh.cvt = s.cvt;
  remesh.cvt.sites = s.sites;
  remesh.cvt.iterations = s.iterations;
  remesh.cvt.tolerance = s.tolerance;
  remesh.cvt.seed = s.seed;
  remesh.cvt.threads = s.threads;
  remesh.cvt.time_coefficient = s.t_coef;
  remesh.cvt.quality_every = s.quality_every;
  remesh.cvt.target_phi_mean_deg = s.target_mean;
  remesh.cvt.target_phi_min_deg = s.target_min;
  remesh.cvt.initialization = s.init == "farthest" ? CvtInitialization::farthest_point : CvtInitialization::random;
  remesh.cvt.relaxation = s.relaxation;
  remesh.cvt.graph_lloyd_iterations = s.graph_lloyd;
  remesh.cvt.surface_lloyd_iterations = s.surface_lloyd;
  remesh.cvt.split_nonmanifold_cells = !s.no_split;
  return remesh;
}

// Reads and checks the input mesh and notes its size and topology on stderr.
TriangleMesh read_input(const Settings& s, SurfaceDescription& input) {
  TriangleMesh mesh = read_mesh(s.mesh_path);
  validate_mesh(mesh.V, mesh.F, s.mesh_path);
  const WeldStats weld = weld_coincident_borders(mesh);
  if (weld.welded)
    cli::log_line(s.quiet, "welded " + std::to_string(weld.welded) + " boundary vertices of " + s.mesh_path +
                               " onto others at the same position (unwelded seams or a triangle soup)");
  if (weld.refused)
    cli::log_line(s.quiet, "warning: " + std::to_string(weld.refused) + " boundary vertices of " + s.mesh_path +
                               " share a position but stay apart: welding them would give " +
                               std::to_string(weld.bad_edges) + " edges more than two faces and collapse " +
                               std::to_string(weld.bad_faces) + " faces");
  input = describe_surface(mesh);
  cli::log_line(s.quiet, "read " + s.mesh_path + ": " + std::to_string(mesh.V.rows()) + " vertices, " +
                             std::to_string(mesh.F.rows()) + " faces, " + input.genus_text() +
                             (input.closed() ? ", closed" : ", open"));
  return mesh;
}

// Runs the remeshing with a progress bar over the Lloyd iterations. The closed-ball repair and
// the fallback run the CVT again: each further run is labelled "CVT run k" and timed from its
// own start, so that its ETA is its own.
RemeshResult run_remesh(const TriangleMesh& mesh, const RemeshOptions& remesh, const Settings& s) {
  cli::Progress progress("lloyd", s.iterations, s.quiet);
  int last_iteration = 0, run = 1;
  // remesh_cvt works in the mesh's unit bounding-box frame (normalize.h) and returns input
  // coordinates: the result does not depend on the units.
  RemeshResult res = cli::on_file(s.mesh_path, [&] {
    return remesh_cvt(mesh, remesh, [&](const CvtIterationStats& st) {
      if (st.iteration <= last_iteration) {
        ++run;
        progress.restart();
      }
      last_iteration = st.iteration;
      progress.update(st.iteration, run > 1 ? "CVT run " + std::to_string(run) : "");
      return true;
    });
  });
  progress.finish();
  return res;
}

// Components without a site named one by one on stderr; the rest are counted in one line.
constexpr std::size_t kMaxListedComponents = 10;

// Notes on stderr what the run did to the input: refinement, degenerate faces, unreached components.
void log_input_notes(const RemeshResult& res, const Settings& s) {
  if (res.reoriented_faces)
    cli::log_line(s.quiet, "oriented " + s.mesh_path + " consistently: " + std::to_string(res.reoriented_faces) +
                               " faces reversed (each piece keeps the orientation of most of its faces)");
  if (res.refinement_splits + res.refinement_flips)
    cli::log_line(s.quiet, "refined " + s.mesh_path + " for the CVT to " + std::to_string(res.cvt_vertices) + " vertices: " +
                               std::to_string(res.refinement_splits) + " edges split, " +
                               std::to_string(res.refinement_flips) + " flat edges flipped (--min-vertices-per-site " +
                               std::to_string(s.min_vertices_per_site) + ")");
  if (res.refinement_levels)
    cli::log_line(s.quiet, "refined " + s.mesh_path + " by " + std::to_string(res.refinement_levels) +
                               " midpoint subdivision(s) to " + std::to_string(res.cvt_vertices) +
                               " vertices (--min-vertices-per-site " + std::to_string(s.min_vertices_per_site) + ")");
  if (s.adaptive.enabled()) {
    char ratio[32];
    std::snprintf(ratio, sizeof ratio, "%.2f", res.size_ratio);
    cli::log_line(s.quiet, std::string("adaptive sizing: largest over smallest edge length ") + ratio +
                               " (--size-ratio bounds it; 1 = one size all over)");
  }
  if (res.degenerate_faces)
    cli::log_line(s.quiet, "warning: " + std::to_string(res.degenerate_faces) + " degenerate faces in " +
                               s.mesh_path + " carry no heat conduction");
  const std::vector<int>& unreached = res.cvt.diagram.unreached_components;
  for (std::size_t i = 0; i < unreached.size() && i < kMaxListedComponents; ++i)
    cli::log_line(s.quiet, "warning: connected component " + std::to_string(unreached[i]) + " of " + s.mesh_path +
                               " has no site and gets no cell");
  if (unreached.size() > kMaxListedComponents)
    cli::log_line(s.quiet, "warning: " + std::to_string(unreached.size() - kMaxListedComponents) +
                               " more components of " + s.mesh_path + " have no site");
}

// Timings and counts of a run that the report and the summary both give.
struct RunFigures {
  int input_vertices = 0;
  int iterations = 0;
  double laplacian_s = 0, per_iteration_s = 0, total_s = 0;
  int revived = 0;
};

// Collects the run's figures; total_s is the time since `start`.
RunFigures run_figures(const TriangleMesh& mesh, const RemeshResult& res, Clock::time_point start) {
  RunFigures f;
  f.input_vertices = static_cast<int>(mesh.V.rows());
  for (const auto& [name, seconds] : res.stage_seconds)
    if (name == "laplacian") f.laplacian_s = seconds;
  const CvtResult& r = res.cvt;
  f.iterations = static_cast<int>(r.iterations.size());
  double iter_s = 0;
  for (const auto& st : r.iterations) iter_s += st.seconds;
  f.per_iteration_s = f.iterations ? iter_s / f.iterations : 0.0;
  f.total_s = cli::seconds_since(start);
  for (const auto& st : r.iterations) f.revived += st.revived_sites;
  return f;
}

// The --report of a run (schema: report_json.h), without the common tail.
cli::Json make_report(const Settings& s, const TriangleMesh& mesh, int input_genus, const RemeshResult& res,
                      const RunFigures& f) {
  const CvtResult& r = res.cvt;
  const ValidationReport& checks = res.checks;
  const TriangleQuality& q = res.quality;
  cli::Json rep = cli::report_head("meshcvt", s.mesh_path, {s.out_path, s.cells_path, s.report_path});
  rep["vertices"] = f.input_vertices;
  rep["faces"] = mesh.F.rows();
  rep["input_genus"] = input_genus;
  rep["sites"] = r.sites.size();
  rep["anisotropy"] = s.anisotropy;
  rep["adaptivity"] = s.adaptive.adaptivity;
  rep["size_ratio"] = res.size_ratio;
  rep["seed"] = s.seed;
  rep["iterations"] = f.iterations;
  rep["converged"] = r.converged;
  rep["reached_quality_target"] = r.reached_quality;
  rep["blas"] = heatcvt::blas_description();
  rep["factorization"] = heatcvt::factorization_description(res.cvt_vertices);
  rep["laplacian_s"] = f.laplacian_s;
  rep["factor_s"] = r.factor_seconds;
  rep["factor_memory_bytes"] = r.factor_bytes;
  rep["time_per_iteration_s"] = f.per_iteration_s;
  rep["total_s"] = f.total_s;
  rep["cell_area_variance"] = r.final_area_variance;
  rep["revived_sites"] = f.revived;
  rep["inserted_sites"] = r.inserted_sites;
  rep["graph_lloyd_iterations"] = r.graph_lloyd_iterations;
  rep["surface_lloyd_iterations"] = r.surface_lloyd_iterations;
  rep["triangles"] = q.triangles;
  rep["phi_min_deg"] = q.min_angle_deg;
  rep["phi_mean_deg"] = q.mean_min_angle_deg;
  rep["share_below_30"] = q.below_30_fraction;
  rep["split_voronoi_vertices"] = r.dual.split_vertices;
  rep["duplicate_triangles"] = r.dual.duplicate_triangles;
  rep["flipped_triangles"] = r.dual.flipped_against_input;
  rep["unused_sites"] = r.dual.unused_sites.size();
  rep["output_vertices"] = res.mesh.V.rows();
  rep["post_cvt_kept"] = res.post_cvt_kept;
  if (!res.post_cvt_refusal.empty()) rep["post_cvt_refusal"] = res.post_cvt_refusal;
  if (res.input_self_intersections >= 0) rep["input_self_intersections"] = res.input_self_intersections;
  rep["creases"] = {{"lines", res.creases.lines}, {"skipped_lines", res.creases.skipped_lines},
                    {"dropped_lines", res.creases.dropped_crease_lines},
                    {"corners", res.creases.corners},
                    {"snapped_vertices", res.creases.snapped}, {"line_edges", res.creases.line_edges},
                    {"missing_edges", res.creases.missing_edges}, {"undone", res.creases.undone},
                    {"undone_reason", res.creases.undone_reason}, {"border_lines", res.creases.border_lines},
                    {"border_corners", res.creases.border_corners}, {"border_lines_dropped", res.creases.dropped_lines},
                    {"border_undone_reason", res.creases.border_undone_reason}};
  rep["coverage"] = {{"uncovered_before", res.coverage.uncovered_before},
                     {"uncovered_after", res.coverage.uncovered_after}, {"moves", res.coverage.moves},
                     {"gap_before", res.coverage.gap_before}, {"gap_after", res.coverage.gap_after},
                     {"ring_dragged", res.coverage_ring_dragged}};
  rep["tips_held_deg"] = res.tips_held_deg;
  rep["refinement_levels"] = res.refinement_levels;
  rep["uncovered_area_share"] = res.uncovered_area_share;
  rep["refinement_splits"] = res.refinement_splits;
  rep["refinement_flips"] = res.refinement_flips;
  rep["reoriented_faces"] = res.reoriented_faces;
  rep["cvt_vertices"] = res.cvt_vertices;
  rep["repair_rounds"] = res.repair_rounds;
  rep["repair_sites"] = res.repair_sites;
  rep["repair_dropped_sites"] = res.repair_dropped_sites;
  std::vector<double> moves, times;
  for (const auto& st : r.iterations) moves.push_back(st.max_move), times.push_back(st.seconds);
  rep["max_move_per_iteration"] = moves;
  rep["seconds_per_iteration"] = times;
  rep["dual_topology"] = {{"vertices", checks.vertices}, {"edges", checks.edges}, {"faces", checks.faces},
                          {"components", checks.components}, {"boundary_loops", checks.boundary_loops},
                          {"euler_characteristic", checks.euler_characteristic}, {"genus", checks.genus},
                          {"orientable", checks.orientable}, {"crosscaps", checks.crosscaps}};
  return rep;
}

// Writes the remeshed surface, the tessellated input (--cells) and the report: all or none.
void write_outputs(const Settings& s, const RemeshResult& res, const cli::Json& rep) {
  OutputTransaction outputs;  // all outputs or none (atomic_file.h)
  write_mesh(s.out_path, res.mesh.V, res.mesh.F);
  if (!s.cells_path.empty()) {
    const VoronoiDiagram& diagram = res.cvt.diagram;
    MeshAttributes attr;
    attr.face_int = diagram.face_cell;
    attr.face_color = cli::cell_colors(diagram.face_cell);
    write_mesh(s.cells_path, diagram.V, diagram.F, attr);
  }
  if (!s.report_path.empty()) cli::write_json(s.report_path, rep);
  outputs.commit();
}

// Prints the summary of a run on stdout: sizes, times, what the stages did, quality and checks.
void print_summary(const Settings& s, const RemeshOptions& remesh, const RemeshResult& res, const RunFigures& f,
                   const std::vector<cli::CheckRecord>& check_list) {
  const CvtResult& r = res.cvt;
  const TriangleQuality& q = res.quality;
  std::printf("meshcvt: %s (%d vertices) -> %s (%d vertices, %d triangles)\n", s.mesh_path.c_str(), f.input_vertices,
              s.out_path.c_str(), static_cast<int>(res.mesh.V.rows()), q.triangles);
  std::printf("  factor: %.3f s, %.1f MB (%s); %d iterations%s, %.4f s per iteration; total %.2f s\n", r.factor_seconds,
              r.factor_bytes / 1e6, heatcvt::factorization_description(res.cvt_vertices).c_str(), f.iterations,
              r.converged ? " (converged)" : (r.reached_quality ? " (quality target reached)" : ""), f.per_iteration_s,
              f.total_s);
  cli::print_stages(res.stage_seconds);
  if (res.coverage.uncovered_before > 0)
    std::printf("  coverage repair: %d vertex moves%s; %d input vertices farther than %.2f site spacings, %d after\n",
                res.coverage.moves, res.coverage_ring_dragged ? " (rings dragged along)" : "",
                res.coverage.uncovered_before, remesh.coverage.max_gap, res.coverage.uncovered_after);
  if (res.tips_held_deg > 0)
    std::printf("  tips held: the stages' result with the vertices of angle defect above %.0f deg held is the output\n",
                res.tips_held_deg);
  if (!s.no_post && !res.post_cvt_kept)
    std::printf("  post-CVT stages: %s; the dual is written\n", res.post_cvt_refusal.c_str());
  if (res.creases.lines + res.creases.skipped_lines + res.creases.dropped_crease_lines > 0)
    std::printf("  creases: %d lines%s%s, %d corners, %d vertices moved onto them, %d of %d line edges made%s\n",
                res.creases.lines,
                res.creases.skipped_lines > 0
                    ? (" (" + std::to_string(res.creases.skipped_lines) + " more left out: their snap made faces cross)").c_str()
                    : "",
                res.creases.dropped_crease_lines > 0
                    ? (" (" + std::to_string(res.creases.dropped_crease_lines) +
                       " more left out: faces next to them fell below the smallest angle)")
                          .c_str()
                    : "",
                res.creases.corners, res.creases.snapped,
                res.creases.line_edges, res.creases.line_edges + res.creases.missing_edges,
                res.creases.undone ? ("; not kept: " + res.creases.undone_reason).c_str() : "");
  if (res.creases.border_lines + res.creases.dropped_lines > 0 || !res.creases.border_undone_reason.empty())
    std::printf("  border corners: %d border lines between %d corners kept%s%s\n", res.creases.border_lines,
                res.creases.border_corners,
                res.creases.dropped_lines > 0
                    ? (" (" + std::to_string(res.creases.dropped_lines) + " left out: faces next to them fell below the smallest angle)").c_str()
                    : "",
                res.creases.border_undone_reason.empty() ? "" : ("; not kept: " + res.creases.border_undone_reason).c_str());
  if (res.repair_rounds)
    std::printf("  %d sites added, %d dropped in %d closed-ball repair rounds\n", res.repair_sites,
                res.repair_dropped_sites, res.repair_rounds);
  std::printf("  quality: phi_min %.2f deg, phi_m %.2f deg, %.2f%% of triangles below 30 deg\n", q.min_angle_deg,
              q.mean_min_angle_deg, 100.0 * q.below_30_fraction);
  std::printf("  cell-area variance %.4g%s\n", r.final_area_variance,
              f.revived ? (", " + std::to_string(f.revived) + " vanished cells re-seeded").c_str() : "");
  if (r.inserted_sites)
    std::printf("  %d sites added to cells too big for thin parts (%d requested)\n", r.inserted_sites, s.sites);
  std::printf("  checks (CGAL):\n");
  cli::print_checks(check_list);
}

// Explains on stderr a failed check of the result: the input's own crossings, or too few sites.
void log_failed_checks(int status, const RemeshResult& res, const Settings& s) {
  if (status != cli::exit_ok && res.input_self_intersections > 0)
    cli::log_line(s.quiet, "warning: the result crosses itself where the input does (" +
                               std::to_string(res.input_self_intersections) + " intersecting face pairs in " +
                               s.mesh_path + "; exit status 3): repair the input first");
  else if (status != cli::exit_ok)
    cli::log_line(s.quiet, "warning: the dual triangulation failed some checks (exit status 3); try more sites or "
                           "iterations");
}

// Explains on stderr an output whose vertex count is off the count asked for by more than the
// sizing's tolerance (IsotropicRemeshOptions::count_tolerance): where the sites came from (the CVT's splits
// of cells too big for thin parts or handles, the closed-ball repair) and that no result at the
// count passed the checks. (A result that fails a check gets log_failed_checks()'s line instead.)
void log_count_miss(int status, const RemeshOptions& remesh, const RemeshResult& res, const Settings& s) {
  const int vertices = static_cast<int>(res.mesh.V.rows());
  const double tolerance = remesh.mesher.sizing.count_tolerance * s.sites;
  if (status != cli::exit_ok || s.sites <= 0 || std::abs(vertices - s.sites) <= tolerance) return;
  const int sites = static_cast<int>(res.cvt.sites.size());
  const int split = sites - s.sites - res.repair_sites + res.repair_dropped_sites;
  const char* outcome = s.no_post ? "the dual is written as it is (--no-post-cvt)" : "no remesh at the count passed the checks";
  char line[640];
  if (vertices > s.sites)  // the sites the CVT added account for the excess
    std::snprintf(line, sizeof line,
                  "warning: %d vertices for the %d asked for (%+.0f %%): the CVT ended with %d sites (%d added by its "
                  "splits of cells too big for thin parts or handles, %d by the closed-ball repair, %d dropped), and "
                  "%s; thin parts narrower than the site spacing need more sites",
                  vertices, s.sites, 100.0 * (vertices - s.sites) / s.sites, sites, split, res.repair_sites,
                  res.repair_dropped_sites, outcome);
  else
    std::snprintf(line, sizeof line, "warning: %d vertices for the %d asked for (%+.0f %%): %s", vertices, s.sites,
                  100.0 * (vertices - s.sites) / s.sites, outcome);
  cli::log_line(s.quiet, line);
}

// The whole run after parsing: checks, input, remeshing, report, outputs, summary; the exit status.
int run(const Settings& s) {
  check_settings(s);
  const auto t_start = Clock::now();
  SurfaceDescription input;
  const TriangleMesh mesh = read_input(s, input);
  const RemeshOptions remesh = remesh_options(s);
  const RemeshResult res = run_remesh(mesh, remesh, s);
  // A mesh of vertices alone is no remesh: the computation failed, and nothing is written.
  if (res.mesh.F.rows() == 0)
    throw heatcvt::Error(s.mesh_path + ": no triangle could be made from the " + std::to_string(res.cvt.sites.size()) +
                         " sites (their Voronoi cells meet at no vertex: too few sites for this surface; ask for more)");
  log_input_notes(res, s);
  const RunFigures figures = run_figures(mesh, res, t_start);
  const std::vector<cli::CheckRecord> check_list = cli::check_records(res.checks);
  cli::Json rep = make_report(s, mesh, input.genus, res, figures);
  const int status = cli::finish_report(rep, res.stage_seconds, check_list);
  write_outputs(s, res, rep);
  if (!s.quiet) print_summary(s, remesh, res, figures, check_list);
  log_count_miss(status, remesh, res, s);
  log_failed_checks(status, res, s);
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"meshcvt: remesh a triangle mesh by an intrinsic centroidal Voronoi tessellation with heat "
               "diffusion (Herholz, Haase, Alexa 2017, §7.1); writes the dual triangulation"};
  Settings settings;
  add_lloyd_options(app, settings);
  add_stage_options(app, settings);
  return cli::parse_and_run(app, argc, argv, "meshcvt", [&] {
    apply_implied_defaults(app, settings);
    return run(settings);
  });
}
