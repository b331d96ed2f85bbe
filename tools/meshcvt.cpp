// meshcvt: intrinsic (optionally anisotropic) CVT remeshing of a triangle mesh by Lloyd iteration
// with heat Voronoi cells and heat centroids (Herholz et al. 2017, §6–7.1). Writes the dual
// triangulation of the final CVT and reports its quality and the CGAL surface checks.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
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
#include "report_json.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

// The CVT's φmin target (degrees) when the dual is the output (--no-post-cvt).
constexpr double kDualPhiMin = 25.0;

int main(int argc, char** argv) {
  CLI::App app{"meshcvt: remesh a triangle mesh by an intrinsic centroidal Voronoi tessellation with heat "
               "diffusion (Herholz, Haase, Alexa 2017, §7.1); writes the dual triangulation"};
  // Defaults shown by --help: the best measured configuration (fast_cvt_options); --paper switches
  // every option not given explicitly to the paper's plain Lloyd (CvtOptions{}).
  const RemeshOptions defaults;
  CvtOptions cvt = defaults.cvt;
  const CvtOptions paper_cvt;
  double min_vertices_per_site = defaults.min_vertices_per_site;
  int repair_rounds = defaults.repair_rounds;
  bool no_post = !defaults.post_cvt_stages;
  bool no_features = !defaults.creases.enabled;
  double crease_angle = defaults.creases.min_dihedral_deg;
  std::string mesh_path, out_path, cells_path, report_path,
      init = cvt.initialization == CvtInitialization::farthest_point ? "farthest" : "random";
  double relaxation = cvt.relaxation;
  int graph_lloyd = cvt.graph_lloyd_iterations;
  int surface_lloyd = cvt.surface_lloyd_iterations;
  bool no_split = !cvt.split_nonmanifold_cells, paper = false;
  int sites = cvt.sites, iterations = cvt.iterations, threads = cvt.threads;
  unsigned seed = cvt.seed;
  double anisotropy = 0.0, tolerance = cvt.tolerance, t_coef = cvt.time_coefficient;
  int quality_every = cvt.quality_every;
  double target_mean = cvt.target_phi_mean_deg, target_min = cvt.target_phi_min_deg;
  bool quiet = false;
  app.add_option("MESH", mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("-n,--sites", sites, "number of sites = vertices of the output")->capture_default_str();
  app.add_option("-o,--output", out_path, "output dual triangulation (.obj .ply .off)")->required();
  app.add_option("-i,--iterations", iterations, "maximum number of Lloyd iterations")->capture_default_str();
  app.add_option("--tolerance", tolerance,
                 "stop when no site moves more than TOL * sqrt(area / sites) (0 = run all iterations)")
      ->capture_default_str();
  app.add_option("--quality-every", quality_every,
                 "every K iterations build the dual of the current sites and measure phi_min / phi_m (0 = never)")
      ->capture_default_str();
  app.add_option("--target-phi-m", target_mean,
                 "with --quality-every: stop once phi_m >= this and phi_min >= --target-phi-min (0 = off)")
      ->capture_default_str();
  app.add_option("--target-phi-min", target_min,
                 "see --target-phi-m (degrees; 0 = off: the post-CVT stages raise phi_min; with --no-post-cvt the "
                 "default is " + std::to_string(static_cast<int>(kDualPhiMin)) + ")")
      ->capture_default_str();
  app.add_option("--anisotropy", anisotropy,
                 "lambda of the anisotropic CVT: lift to (p, lambda n) in R^6 after scaling to the unit bounding "
                 "box (paper: 0.05; 0 = isotropic)")
      ->capture_default_str();
  app.add_option("--init", init, "initial sites: random (area-uniform) or farthest (farthest-point sampling)")
      ->capture_default_str()
      ->check(CLI::IsMember({"random", "farthest"}));
  app.add_option("--seed", seed, "random seed of the initial sites")->capture_default_str();
  app.add_option("--t-coef", t_coef, "time step t = C * (mean edge length)^2")->capture_default_str();
  app.add_option("--threads", threads, "worker threads (0 = all cores); results do not depend on it")
      ->capture_default_str();
  app.add_option("--cells", cells_path, "also write the tessellated input with a cell id per face (.ply)");
  app.add_option("--report", report_path, "also write the final report as JSON");
  app.add_option("--relaxation", relaxation,
                 "Lloyd over-relaxation omega in [1, 2) (1 = plain Lloyd; safeguarded by the cell-area variance)")
      ->capture_default_str();
  app.add_option("--graph-lloyd", graph_lloyd,
                 "graph-Lloyd iterations on the initial sites, run during the factorisation (0 = off)")
      ->capture_default_str();
  app.add_option("--surface-lloyd", surface_lloyd,
                 "surface-Lloyd iterations on the initial sites (restricted Euclidean cells, exact centroids "
                 "projected onto the surface), run during the factorisation; the start sites' quality is checked "
                 "before the first heat iteration (0 = off)")
      ->capture_default_str();
  app.add_flag("--no-split", no_split,
               "keep the site count: do not add sites to cells that are too big for thin parts (non-manifold dual)");
  app.add_option("--min-vertices-per-site", min_vertices_per_site,
                 "refine the input by midpoint subdivision (surface unchanged) until it has this many vertices per "
                 "site, so more sites than input vertices work (0 = never refine)")
      ->capture_default_str();
  app.add_option("--repair-rounds", repair_rounds,
                 "rounds of adding a site to every cell at a non-manifold spot of the dual (and sites on boundary loops "
                 "of the input with fewer than three cells or sharing a cell with another loop; up to 3 more rounds "
                 "where only loops need them), and running the CVT again (0 = no repair)")
      ->capture_default_str();
  app.add_flag("--no-post-cvt", no_post,
               "write the dual triangulation itself, without the post-CVT stages (manifold extraction, hole filling, "
               "untangling, polish, sliver collapse, edge splits; the input mesh is their projector)");
  app.add_flag("--no-features", no_features,
               "do not keep sharp creases: by default edges of the input whose faces meet at more than --crease-angle "
               "are kept as edge paths of the output, their corners fixed");
  app.add_option("--crease-angle", crease_angle, "dihedral angle (degrees) above which an input edge is a sharp crease")
      ->capture_default_str();
  app.add_flag("--paper", paper,
               "the paper's configuration for every option not given: random start, plain Lloyd, 100 iterations, "
               "no quality evaluation or target, no splitting, no repair rounds, no post-CVT stages");
  app.add_flag("-q,--quiet", quiet, "no progress and no report on the terminal");
  if (const int status = cli::parse_command_line(app, argc, argv, "meshcvt"); status >= 0) return status;

  auto given = [&](const char* name) { return app.count(name) > 0; };
  // Without the post-CVT stages the dual is the output: the CVT itself must reach φmin.
  if (no_post && !paper && !given("--target-phi-min")) target_min = kDualPhiMin;
  if (paper) {
    if (!given("--iterations")) iterations = paper_cvt.iterations;
    if (!given("--quality-every")) quality_every = paper_cvt.quality_every;
    if (!given("--target-phi-m")) target_mean = paper_cvt.target_phi_mean_deg;
    if (!given("--target-phi-min")) target_min = paper_cvt.target_phi_min_deg;
    if (!given("--init")) init = "random";
    if (!given("--relaxation")) relaxation = paper_cvt.relaxation;
    if (!given("--graph-lloyd")) graph_lloyd = paper_cvt.graph_lloyd_iterations;
    if (!given("--surface-lloyd")) surface_lloyd = paper_cvt.surface_lloyd_iterations;
    if (!given("--no-split")) no_split = !paper_cvt.split_nonmanifold_cells;
    if (!given("--repair-rounds")) repair_rounds = 0;
    if (!given("--no-post-cvt")) no_post = true;
    if (!given("--no-features")) no_features = true;
    cvt = paper_cvt;
  }
  return cli::run_tool("meshcvt", [&]() -> int {
    if (!(relaxation >= 1 && relaxation < 2)) throw InvalidInputError("--relaxation must be in [1, 2)");
    if (graph_lloyd < 0) throw InvalidInputError("--graph-lloyd must be >= 0");
    if (surface_lloyd < 0) throw InvalidInputError("--surface-lloyd must be >= 0");
    if (sites < 1) throw InvalidInputError("--sites must be at least 1, got " + std::to_string(sites));
    if (iterations < 0) throw InvalidInputError("--iterations must be >= 0, got " + std::to_string(iterations));
    if (!(tolerance >= 0) || !std::isfinite(tolerance)) throw InvalidInputError("--tolerance must be >= 0");
    if (!(anisotropy >= 0) || !std::isfinite(anisotropy)) throw InvalidInputError("--anisotropy must be >= 0");
    if (!(t_coef > 0) || !std::isfinite(t_coef)) throw InvalidInputError("--t-coef must be a positive number");
    if (threads < 0) throw InvalidInputError("--threads must be >= 0");
    if (!(min_vertices_per_site >= 0) || !std::isfinite(min_vertices_per_site))
      throw InvalidInputError("--min-vertices-per-site must be a number >= 0");
    if (repair_rounds < 0) throw InvalidInputError("--repair-rounds must be >= 0");
    if (!(crease_angle > 0 && crease_angle < 180)) throw InvalidInputError("--crease-angle must be in (0, 180) degrees");
    if (quality_every < 0) throw InvalidInputError("--quality-every must be >= 0");
    if (!(target_mean >= 0 && target_mean <= 60) || !(target_min >= 0 && target_min <= 60))
      throw InvalidInputError("--target-phi-m / --target-phi-min must be angles in [0, 60] degrees");
    if ((target_mean > 0 || target_min > 0) && quality_every == 0)
      throw InvalidInputError("--target-phi-m / --target-phi-min need --quality-every K > 0");
    cli::check_output_path(out_path, {".obj", ".ply", ".off"});
    cli::check_output_path(cells_path, {".ply"});
    cli::check_output_path(report_path, {".json"});
    cli::check_distinct_outputs({{"-o", out_path}, {"--cells", cells_path}, {"--report", report_path}}, {mesh_path});
    auto log = [&](const std::string& s) {
      if (!quiet) std::cerr << s << std::endl;
    };
    const auto t_start = Clock::now();
    TriangleMesh mesh = read_mesh(mesh_path);
    validate_mesh(mesh.V, mesh.F, mesh_path);
    const int nv = static_cast<int>(mesh.V.rows());
    const SurfaceDescription input = describe_surface(mesh);
    const int input_genus = input.genus;
    log("read " + mesh_path + ": " + std::to_string(nv) + " vertices, " + std::to_string(mesh.F.rows()) + " faces, " +
        input.genus_text() + (input.closed() ? ", closed" : ", open"));

    RemeshOptions remesh;
    remesh.anisotropy = anisotropy;
    remesh.min_vertices_per_site = min_vertices_per_site;
    remesh.repair_rounds = repair_rounds;
    if (repair_rounds == 0) remesh.loop_repair_rounds = 0;  // no repair at all
    remesh.post_cvt_stages = !no_post;
    remesh.creases.enabled = !no_features;
    remesh.creases.min_dihedral_deg = crease_angle;
    remesh.cvt = cvt;
    remesh.cvt.sites = sites;
    remesh.cvt.iterations = iterations;
    remesh.cvt.tolerance = tolerance;
    remesh.cvt.seed = seed;
    remesh.cvt.threads = threads;
    remesh.cvt.time_coefficient = t_coef;
    remesh.cvt.quality_every = quality_every;
    remesh.cvt.target_phi_mean_deg = target_mean;
    remesh.cvt.target_phi_min_deg = target_min;
    remesh.cvt.initialization = init == "farthest" ? CvtInitialization::farthest_point : CvtInitialization::random;
    remesh.cvt.relaxation = relaxation;
    remesh.cvt.graph_lloyd_iterations = graph_lloyd;
    remesh.cvt.surface_lloyd_iterations = surface_lloyd;
    remesh.cvt.split_nonmanifold_cells = !no_split;
    cli::Progress progress("lloyd", iterations, quiet);
    // remesh_cvt works in the mesh's unit bounding-box frame (normalize.h) and returns input
    // coordinates: the result does not depend on the units.
    const RemeshResult res = cli::on_file(mesh_path, [&] {
      return remesh_cvt(mesh, remesh, [&](const CvtIterationStats& s) {
        progress.update(s.iteration);
        return true;
      });
    });
    progress.finish();
    const CvtResult& r = res.cvt;
    double laplacian_s = 0;
    for (const auto& [name, seconds] : res.stage_seconds)
      if (name == "laplacian") laplacian_s = seconds;
    if (res.refinement_levels)
      log("refined " + mesh_path + " by " + std::to_string(res.refinement_levels) + " midpoint subdivision(s) to " +
          std::to_string(res.cvt_vertices) + " vertices (--min-vertices-per-site " + std::to_string(min_vertices_per_site) + ")");
    if (res.degenerate_faces)
      log("warning: " + std::to_string(res.degenerate_faces) + " degenerate faces in " + mesh_path +
          " carry no heat conduction");
    for (int comp : r.diagram.unreached_components)
      log("warning: connected component " + std::to_string(comp) + " of " + mesh_path +
          " has no site and gets no cell");
    const ValidationReport& checks = res.checks;
    const TriangleQuality& q = res.quality;


    const int done = static_cast<int>(r.iterations.size());
    double iter_s = 0;
    for (const auto& s : r.iterations) iter_s += s.seconds;
    const double per_iter = done ? iter_s / done : 0.0;
    const double total_s = cli::seconds_since(t_start);
    int revived = 0;
    for (const auto& s : r.iterations) revived += s.revived_sites;
    const std::vector<cli::CheckRecord> check_list = cli::check_records(checks);
    cli::Json rep = cli::report_head("meshcvt", mesh_path, {out_path, cells_path, report_path});
    rep["vertices"] = nv;
    rep["faces"] = mesh.F.rows();
    rep["input_genus"] = input_genus;
    rep["sites"] = r.sites.size();
    rep["anisotropy"] = anisotropy;
    rep["seed"] = seed;
    rep["iterations"] = done;
    rep["converged"] = r.converged;
    rep["reached_quality_target"] = r.reached_quality;
    rep["blas"] = heatcvt::blas_description();
    rep["laplacian_s"] = laplacian_s;
    rep["factor_s"] = r.factor_seconds;
    rep["factor_memory_bytes"] = r.factor_bytes;
    rep["time_per_iteration_s"] = per_iter;
    rep["total_s"] = total_s;
    rep["cell_area_variance"] = r.final_area_variance;
    rep["revived_sites"] = revived;
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
                      {"corners", res.creases.corners},
                      {"snapped_vertices", res.creases.snapped}, {"line_edges", res.creases.line_edges},
                      {"missing_edges", res.creases.missing_edges}, {"undone", res.creases.undone},
                      {"undone_reason", res.creases.undone_reason}};
    rep["coverage"] = {{"uncovered_before", res.coverage.uncovered_before},
                       {"uncovered_after", res.coverage.uncovered_after}, {"moves", res.coverage.moves},
                       {"gap_before", res.coverage.gap_before}, {"gap_after", res.coverage.gap_after}};
    rep["refinement_levels"] = res.refinement_levels;
    rep["cvt_vertices"] = res.cvt_vertices;
    rep["repair_rounds"] = res.repair_rounds;
    rep["repair_sites"] = res.repair_sites;
    rep["repair_dropped_sites"] = res.repair_dropped_sites;
    std::vector<double> moves, times;
    for (const auto& s : r.iterations) moves.push_back(s.max_move), times.push_back(s.seconds);
    rep["max_move_per_iteration"] = moves;
    rep["seconds_per_iteration"] = times;
    rep["dual_topology"] = {{"vertices", checks.vertices}, {"edges", checks.edges}, {"faces", checks.faces},
                            {"components", checks.components}, {"boundary_loops", checks.boundary_loops},
                            {"euler_characteristic", checks.euler_characteristic}, {"genus", checks.genus},
                            {"orientable", checks.orientable}, {"crosscaps", checks.crosscaps}};
    const int status = cli::finish_report(rep, res.stage_seconds, check_list);
    {
      OutputTransaction outputs;  // all outputs or none (atomic_file.h)
      write_mesh(out_path, res.mesh.V, res.mesh.F);
      if (!cells_path.empty()) {
        MeshAttributes attr;
        attr.face_int = r.diagram.face_cell;
        attr.face_color = cli::cell_colors(r.diagram.face_cell);
        write_mesh(cells_path, r.diagram.V, r.diagram.F, attr);
      }
      if (!report_path.empty()) cli::write_json(report_path, rep);
      outputs.commit();
    }
    if (!quiet) {
      std::printf("meshcvt: %s (%d vertices) -> %s (%d vertices, %d triangles)\n", mesh_path.c_str(), nv,
                  out_path.c_str(), static_cast<int>(res.mesh.V.rows()), q.triangles);
      std::printf("  factor: %.3f s, %.1f MB (%s); %d iterations%s, %.4f s per iteration; total %.2f s\n", r.factor_seconds,
                  r.factor_bytes / 1e6, heatcvt::blas_description().c_str(), done, r.converged ? " (converged)" : (r.reached_quality ? " (quality target reached)" : ""), per_iter, total_s);
      std::printf("  stages:");
      for (const auto& [name, seconds] : res.stage_seconds) std::printf(" %s %.2f s;", name.c_str(), seconds);
      std::printf("\n");
      if (res.coverage.uncovered_before > 0)
        std::printf("  coverage repair: %d vertex moves; %d input vertices farther than %.2f site spacings, %d after\n",
                    res.coverage.moves, res.coverage.uncovered_before, remesh.coverage.max_gap,
                    res.coverage.uncovered_after);
      if (!no_post && !res.post_cvt_kept)
        std::printf("  post-CVT stages: %s; the dual is written\n", res.post_cvt_refusal.c_str());
      if (res.creases.lines + res.creases.skipped_lines > 0)
        std::printf("  creases: %d lines%s, %d corners, %d vertices moved onto them, %d of %d line edges made%s\n",
                    res.creases.lines,
                    res.creases.skipped_lines > 0
                        ? (" (" + std::to_string(res.creases.skipped_lines) + " more left out: their snap made faces cross)").c_str()
                        : "",
                    res.creases.corners, res.creases.snapped,
                    res.creases.line_edges, res.creases.line_edges + res.creases.missing_edges,
                    res.creases.undone ? ("; not kept: " + res.creases.undone_reason).c_str() : "");
      if (res.repair_rounds)
        std::printf("  %d sites added, %d dropped in %d closed-ball repair rounds\n", res.repair_sites,
                    res.repair_dropped_sites, res.repair_rounds);
      std::printf("  quality: phi_min %.2f deg, phi_m %.2f deg, %.2f%% of triangles below 30 deg\n", q.min_angle_deg,
                  q.mean_min_angle_deg, 100.0 * q.below_30_fraction);
      std::printf("  cell-area variance %.4g%s\n", r.final_area_variance,
                  revived ? (", " + std::to_string(revived) + " vanished cells re-seeded").c_str() : "");
      if (r.inserted_sites)
        std::printf("  %d sites added to cells too big for thin parts (%d requested)\n", r.inserted_sites, sites);
      std::printf("  checks (CGAL):\n");
      cli::print_checks(check_list);
    }
    if (status != cli::exit_ok && res.input_self_intersections > 0)
      log("warning: the result crosses itself where the input does (" + std::to_string(res.input_self_intersections) +
          " intersecting face pairs in " + mesh_path + "; exit status 3): repair the input first");
    else if (status != cli::exit_ok)
      log("warning: the dual triangulation failed some checks (exit status 3); try more sites or iterations");
    return status;
  });
}
