// heatvoronoi: heat Voronoi diagram of generators on a triangle mesh (paper §4), with the
// exact tessellation, Voronoi edges and heat centroids (paper §5).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>

#include "cell_colors.h"
#include "cli_common.h"
#include "heatcvt/atomic_file.h"
#include "heatcvt/centroid.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/normalize.h"
#include "heatcvt/voronoi.h"
#include "report_json.h"
#include "sites.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

namespace {

std::vector<int> random_vertices(int num_vertices, int count, unsigned seed) {
  std::vector<int> all(num_vertices);
  std::iota(all.begin(), all.end(), 0);
  std::mt19937 rng(seed);
  // Partial Fisher–Yates: deterministic for a given seed on every platform (no std::shuffle).
  for (int i = 0; i < count; ++i) {
    std::uniform_int_distribution<int> pick(i, num_vertices - 1);
    std::swap(all[i], all[pick(rng)]);
  }
  all.resize(count);
  return all;
}

// What one run of the diagram produced, in the normalised frame.
struct DiagramRun {
  VoronoiDiagram diagram;
  std::vector<SurfacePoint> centroids;  // empty unless asked for
  double factor_s = 0, solve_s = 0, tess_s = 0, centroid_s = 0, time_step = 0;
  long degenerate_faces = 0;
};

// Cotan Laplacian, one factorisation, one point-source diffusion per generator (eq. 8), the exact
// tessellation, and with centroid_steps > 0 the heat centroids (§5).
DiagramRun compute_diagram(const TriangleMesh& mesh, const std::vector<SurfacePoint>& sites, double t_coef,
                           int threads, int centroid_steps, bool quiet) {
  DiagramRun r;
  const int nv = static_cast<int>(mesh.V.rows()), n = static_cast<int>(sites.size());
  auto t0 = Clock::now();
  Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
  r.degenerate_faces = static_cast<long>(lap.degenerate_faces.size());
  HeatSolverOptions sopt;
  sopt.time_coefficient = t_coef;
  sopt.threads = threads;
  HeatSolver solver(lap, sopt);
  r.factor_s = cli::seconds_since(t0);
  r.time_step = solver.time_step();

  // One point-source diffusion per generator (eq. 8), in chunks so progress can be shown.
  t0 = Clock::now();
  Eigen::MatrixXd U(nv, n);
  {
    cli::Progress progress("diffusing", n, quiet);
    const int chunk = 64;
    for (int c0 = 0; c0 < n; c0 += chunk) {
      const int width = std::min(chunk, n - c0);
      Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nv, width);
      for (int j = 0; j < width; ++j)
        for (int k = 0; k < 3; ++k) rhs(mesh.F(sites[c0 + j].face, k), j) += sites[c0 + j].bary[k];
      U.middleCols(c0, width) = solver.solve(rhs);
      progress.update(c0 + width);
    }
    progress.finish();
  }
  r.solve_s = cli::seconds_since(t0);

  t0 = Clock::now();
  VoronoiOptions vopt;
  vopt.threads = threads;
  r.diagram = tessellate(mesh.V, mesh.F, heat_field_from_dense(U, vopt.keep_sites_per_vertex), vopt);
  U.resize(0, 0);
  r.tess_s = cli::seconds_since(t0);

  if (centroid_steps > 0) {
    t0 = Clock::now();
    CentroidOptions copt;
    copt.steps = centroid_steps;
    copt.threads = threads;
    r.centroids = heat_centroids(mesh.V, mesh.F, solver, r.diagram, copt);
    r.centroid_s = cli::seconds_since(t0);
  }
  return r;
}

// Checks of a diagram (exit status 3 when one fails, cli_common.h): every connected component
// reached by a generator, no cell of zero area (a generator on a vertex of degenerate faces only).
std::vector<cli::CheckRecord> diagram_checks(const VoronoiDiagram& diagram) {
  int empty_cells = 0;
  for (Eigen::Index i = 0; i < diagram.cell_area.size(); ++i) empty_cells += diagram.cell_area[i] > 0 ? 0 : 1;
  const size_t unreached = diagram.unreached_components.size();
  return {{"every_component_has_a_site", unreached == 0, true,
           unreached == 0 ? "ok" : std::to_string(unreached) + " connected components without a generator"},
          {"no_empty_cells", empty_cells == 0, true,
           empty_cells == 0 ? "ok" : std::to_string(empty_cells) + " cells with zero area"}};
}

// Cell areas (in input units) and sizes of the refined mesh, for the report.
void add_diagram_figures(cli::Json& report, const VoronoiDiagram& diagram, const Eigen::VectorXd& areas) {
  report["cell_area_min"] = areas.minCoeff();
  report["cell_area_mean"] = areas.mean();
  report["cell_area_max"] = areas.maxCoeff();
  report["refined_vertices"] = diagram.V.rows();
  report["refined_faces"] = diagram.F.rows();
  report["voronoi_vertices"] = diagram.voronoi_vertices.size();
  report["voronoi_edges"] = diagram.edges.size();
  report["unreached_components"] = diagram.unreached_components.size();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"heatvoronoi: heat Voronoi diagram, exact tessellation and heat centroids of generators on a "
               "triangle mesh (Herholz et al. 2017, §4–5)"};
  std::string mesh_path, cells_path, sites_file, edges_path, centroids_path, report_path;
  int num_sites = 20, threads = 0, centroid_steps = 1;
  unsigned seed = 1;
  double t_coef = 1.0, snap = cli::kDefaultSnapTolerance;
  bool quiet = false;
  app.add_option("MESH", mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("-o,--output", cells_path, "output: tessellated mesh with a cell id and colour per face (.ply recommended)")
      ->required();
  auto* sites_opt = app.add_option("--sites", num_sites, "number of random generators (distinct vertices)")
                        ->capture_default_str();
  auto* file_opt = app.add_option("--sites-file", sites_file, "generators, one 'x y z' per line, snapped to the surface");
  cli::add_snap_tolerance_option(app, snap);
  sites_opt->excludes(file_opt);
  file_opt->excludes(sites_opt);
  app.add_option("--seed", seed, "random seed for --sites")->capture_default_str();
  cli::add_time_coefficient_option(app, t_coef);
  app.add_option("--centroid-steps", centroid_steps, "implicit heat steps for the centroids (h <- u)")->capture_default_str();
  app.add_option("--edges", edges_path, "write the Voronoi edges as OBJ polylines");
  app.add_option("--centroids", centroids_path, "write one heat centroid per cell as 'x y z'");
  app.add_option("--report", report_path, "write a JSON report");
  cli::add_threads_option(app, threads);
  app.add_flag("-q,--quiet", quiet, "no progress output on stderr");
  return cli::parse_and_run(app, argc, argv, "heatvoronoi", [&]() -> int {
    cli::check_time_coefficient(t_coef);
    cli::check_threads(threads);
    cli::check_snap_tolerance(snap);
    if (centroid_steps < 1) throw InvalidInputError("--centroid-steps must be >= 1");
    cli::check_output_path(cells_path, {".ply", ".obj", ".off", ".stl"});
    cli::check_output_path(edges_path, {".obj"});
    cli::check_output_path(centroids_path, {".xyz", ".txt"});
    cli::check_output_path(report_path, {".json"});
    cli::check_distinct_outputs({{"-o", cells_path}, {"--edges", edges_path}, {"--centroids", centroids_path},
                                 {"--report", report_path}}, {mesh_path, sites_file});
    auto log = [&](const std::string& s) { cli::log_line(quiet, s); };
    const auto t_start = Clock::now();
    MeshReadReport read_report;
    TriangleMesh mesh = read_mesh(mesh_path, &read_report);
    validate_mesh(mesh.V, mesh.F, mesh_path);
    // Everything below runs on the mesh in its unit bounding-box frame (normalize.h): the
    // result does not depend on the units; positions are restored on output.
    const NormalizationFrame frame = cli::on_file(mesh_path, [&] { return normalize_positions(mesh.V); });
    const int nv = static_cast<int>(mesh.V.rows());
    log("read " + mesh_path + ": " + std::to_string(nv) + " vertices, " + std::to_string(mesh.F.rows()) + " faces");

    std::vector<SurfacePoint> sites;
    if (!sites_file.empty()) {
      sites = cli::read_snapped_sites(sites_file, mesh.V, mesh.F, frame, snap);
    } else {
      if (num_sites < 1) throw InvalidInputError("--sites must be at least 1");
      if (num_sites > nv)
        throw InvalidInputError("--sites " + std::to_string(num_sites) + " exceeds the " + std::to_string(nv) +
                                " vertices of " + mesh_path);
      sites = surface_points_at_vertices(mesh.F, nv, random_vertices(nv, num_sites, seed));
    }
    const int n = static_cast<int>(sites.size());

    const DiagramRun run = cli::on_file(mesh_path, [&] {
      return compute_diagram(mesh, sites, t_coef, threads, centroids_path.empty() ? 0 : centroid_steps, quiet);
    });
    const VoronoiDiagram& diagram = run.diagram;
    if (run.degenerate_faces > 0)
      log("warning: " + std::to_string(run.degenerate_faces) + " degenerate faces in " + mesh_path +
          " carry no heat conduction");
    log("factored M - tL (t = " + std::to_string(run.time_step * frame.scale * frame.scale) + ") in " +
        std::to_string(run.factor_s) + " s");
    for (int comp : diagram.unreached_components)
      log("warning: connected component " + std::to_string(comp) + " of " + mesh_path +
          " has no generator and gets no cell");

    const Eigen::VectorXd areas = diagram.cell_area * (frame.scale * frame.scale);
    const std::vector<cli::CheckRecord> checks = diagram_checks(diagram);
    const std::vector<SurfacePoint>& centroids = run.centroids;
    Eigen::MatrixX3d refined_V = diagram.V;
    restore_frame(refined_V, frame);

    // Outputs: written together, all or none (atomic_file.h).
    const double total_s = cli::seconds_since(t_start);
    cli::Json report = cli::report_head("heatvoronoi", mesh_path, {cells_path, edges_path, centroids_path, report_path});
    report["vertices"] = nv;
    report["faces"] = mesh.F.rows();
    report["time_step"] = run.time_step * frame.scale * frame.scale;
    report["cells"] = n;
    add_diagram_figures(report, diagram, areas);
    report["degenerate_faces"] = run.degenerate_faces;
    report["total_s"] = total_s;
    const int status = cli::finish_report(
        report, {{"factor", run.factor_s}, {"solves", run.solve_s}, {"tessellation", run.tess_s}, {"centroids", run.centroid_s}},
        checks);
    {
      OutputTransaction outputs;
      MeshAttributes attr;
      attr.face_int = diagram.face_cell;
      attr.face_color = cli::cell_colors(diagram.face_cell);
      write_mesh(cells_path, refined_V, diagram.F, attr);
      if (!edges_path.empty()) {
        std::vector<std::vector<int>> lines;
        for (const auto& e : diagram.edges) lines.push_back(e.polyline);
        write_polylines_obj(edges_path, refined_V, lines);
      }
      if (!centroids_path.empty()) {
        Eigen::MatrixX3d C(centroids.size(), 3);
        for (size_t i = 0; i < centroids.size(); ++i) C.row(i) = position(mesh.V, mesh.F, centroids[i]).transpose();
        restore_frame(C, frame);
        write_points_xyz(centroids_path, C);
      }
      if (!report_path.empty()) cli::write_json(report_path, report);
      outputs.commit();
    }
    if (!quiet) {
      std::printf("heatvoronoi: %d cells on %d vertices / %ld faces -> %ld refined faces, %zu Voronoi vertices\n", n, nv,
                  static_cast<long>(mesh.F.rows()), static_cast<long>(diagram.F.rows()), diagram.voronoi_vertices.size());
      std::printf("  cell area min / mean / max: %.6g / %.6g / %.6g\n", areas.minCoeff(), areas.mean(), areas.maxCoeff());
      std::printf("  time: factor %.3f s, %d diffusions %.3f s, tessellation %.3f s, centroids %.3f s, total %.3f s\n",
                  run.factor_s, n, run.solve_s, run.tess_s, run.centroid_s, total_s);
      std::printf("  wrote %s%s%s%s\n", cells_path.c_str(), edges_path.empty() ? "" : (", " + edges_path).c_str(),
                  centroids_path.empty() ? "" : (", " + centroids_path).c_str(),
                  report_path.empty() ? "" : (", " + report_path).c_str());
      cli::print_checks(checks);
    }
    if (status != cli::exit_ok) log("warning: the diagram failed some checks (exit status 3)");
    return status;
  });
}
