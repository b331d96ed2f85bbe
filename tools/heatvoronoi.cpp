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
#include "heatcvt/centroid.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/voronoi.h"
#include "report_json.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

namespace {

Eigen::MatrixX3d read_sites_file(const std::string& path) {
  const auto rows = cli::read_number_rows(path, 3, "sites");
  Eigen::MatrixX3d P(rows.size(), 3);
  for (size_t i = 0; i < rows.size(); ++i) P.row(i) << rows[i][0], rows[i][1], rows[i][2];
  return P;
}

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"heatvoronoi: heat Voronoi diagram, exact tessellation and heat centroids of generators on a "
               "triangle mesh (Herholz et al. 2017, §4–5)"};
  std::string mesh_path, cells_path, sites_file, edges_path, centroids_path, report_path;
  int num_sites = 20, threads = 0, centroid_steps = 1;
  unsigned seed = 1;
  double t_coef = 1.0;
  bool quiet = false;
  app.add_option("MESH", mesh_path, "input triangle mesh (.obj .off .ply .stl)")->required();
  app.add_option("-o,--output", cells_path, "output: tessellated mesh with a cell id and colour per face (.ply recommended)")
      ->required();
  auto* sites_opt = app.add_option("--sites", num_sites, "number of random generators (distinct vertices)")
                        ->capture_default_str();
  auto* file_opt = app.add_option("--sites-file", sites_file, "generators, one 'x y z' per line, snapped to the surface");
  sites_opt->excludes(file_opt);
  file_opt->excludes(sites_opt);
  app.add_option("--seed", seed, "random seed for --sites")->capture_default_str();
  app.add_option("--t-coef", t_coef, "time step t = C * (mean edge length)^2")->capture_default_str();
  app.add_option("--centroid-steps", centroid_steps, "implicit heat steps for the centroids (h <- u)")->capture_default_str();
  app.add_option("--edges", edges_path, "write the Voronoi edges as OBJ polylines");
  app.add_option("--centroids", centroids_path, "write one heat centroid per cell as 'x y z'");
  app.add_option("--report", report_path, "write a JSON report");
  app.add_option("--threads", threads, "worker threads (0 = all cores)")->capture_default_str();
  app.add_flag("-q,--quiet", quiet, "no progress output on stderr");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  return cli::run_tool("heatvoronoi", [&]() -> int {
    if (!(t_coef > 0) || !std::isfinite(t_coef)) throw InvalidInputError("--t-coef must be a positive number");
    if (threads < 0) throw InvalidInputError("--threads must be >= 0");
    if (centroid_steps < 1) throw InvalidInputError("--centroid-steps must be >= 1");
    cli::check_output_path(cells_path, {".ply", ".obj", ".off", ".stl"});
    cli::check_output_path(edges_path, {".obj"});
    cli::check_output_path(centroids_path, {".xyz", ".txt"});
    cli::check_output_path(report_path, {".json"});
    auto log = [&](const std::string& s) {
      if (!quiet) std::cerr << s << std::endl;
    };
    const auto t_start = Clock::now();
    MeshReadReport read_report;
    TriangleMesh mesh = read_mesh(mesh_path, &read_report);
    validate_mesh(mesh.V, mesh.F, mesh_path);
    const int nv = static_cast<int>(mesh.V.rows());
    log("read " + mesh_path + ": " + std::to_string(nv) + " vertices, " + std::to_string(mesh.F.rows()) + " faces");

    std::vector<SurfacePoint> sites;
    if (!sites_file.empty()) {
      sites = closest_surface_points(mesh.V, mesh.F, read_sites_file(sites_file));
    } else {
      if (num_sites < 1) throw InvalidInputError("--sites must be at least 1");
      if (num_sites > nv)
        throw InvalidInputError("--sites " + std::to_string(num_sites) + " exceeds the " + std::to_string(nv) +
                                " vertices of " + mesh_path);
      sites = surface_points_at_vertices(mesh.F, nv, random_vertices(nv, num_sites, seed));
    }
    const int n = static_cast<int>(sites.size());

    auto t0 = Clock::now();
    Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
    if (!lap.degenerate_faces.empty())
      log("warning: " + std::to_string(lap.degenerate_faces.size()) + " degenerate faces in " + mesh_path +
          " carry no heat conduction");
    HeatSolverOptions sopt;
    sopt.time_coefficient = t_coef;
    sopt.threads = threads;
    HeatSolver solver(lap, sopt);
    const double factor_s = cli::seconds_since(t0);
    log("factored M - tL (t = " + std::to_string(solver.time_step()) + ") in " + std::to_string(factor_s) + " s");

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
    const double solve_s = cli::seconds_since(t0);

    t0 = Clock::now();
    VoronoiOptions vopt;
    vopt.threads = threads;
    VoronoiDiagram diagram = tessellate(mesh.V, mesh.F, heat_field_from_dense(U, vopt.keep_sites_per_vertex), vopt);
    U.resize(0, 0);
    const double tess_s = cli::seconds_since(t0);
    for (int comp : diagram.unreached_components)
      log("warning: connected component " + std::to_string(comp) + " of " + mesh_path +
          " has no generator and gets no cell");

    double centroid_s = 0;
    std::vector<SurfacePoint> centroids;
    if (!centroids_path.empty()) {
      t0 = Clock::now();
      CentroidOptions copt;
      copt.steps = centroid_steps;
      copt.threads = threads;
      centroids = heat_centroids(mesh.V, mesh.F, solver, diagram, copt);
      centroid_s = cli::seconds_since(t0);
    }

    // Outputs (each atomic: temporary file + rename).
    MeshAttributes attr;
    attr.face_int = diagram.face_cell;
    attr.face_color = cli::cell_colors(diagram.face_cell);
    write_mesh(cells_path, diagram.V, diagram.F, attr);
    if (!edges_path.empty()) {
      std::vector<std::vector<int>> lines;
      for (const auto& e : diagram.edges) lines.push_back(e.polyline);
      write_polylines_obj(edges_path, diagram.V, lines);
    }
    if (!centroids_path.empty()) {
      Eigen::MatrixX3d C(centroids.size(), 3);
      for (size_t i = 0; i < centroids.size(); ++i) C.row(i) = position(mesh.V, mesh.F, centroids[i]).transpose();
      write_points_xyz(centroids_path, C);
    }

    const Eigen::VectorXd& areas = diagram.cell_area;
    const double total_s = cli::seconds_since(t_start);
    if (!report_path.empty()) {
      cli::JsonObject timings;
      timings.add("factor_s", factor_s).add("solves_s", solve_s).add("tessellation_s", tess_s)
          .add("centroids_s", centroid_s).add("total_s", total_s);
      cli::JsonObject report;
      report.add("input", mesh_path).add("vertices", nv).add("faces", static_cast<long>(mesh.F.rows()))
          .add("time_step", solver.time_step()).add("cells", n)
          .add("cell_area_min", areas.minCoeff()).add("cell_area_mean", areas.mean())
          .add("cell_area_max", areas.maxCoeff()).add("refined_vertices", static_cast<long>(diagram.V.rows()))
          .add("refined_faces", static_cast<long>(diagram.F.rows()))
          .add("voronoi_vertices", static_cast<long>(diagram.voronoi_vertices.size()))
          .add("voronoi_edges", static_cast<long>(diagram.edges.size()))
          .add("unreached_components", static_cast<long>(diagram.unreached_components.size()))
          .add("degenerate_faces", static_cast<long>(lap.degenerate_faces.size()))
          .add_object("timings", timings);
      cli::write_json(report_path, report);
    }
    if (!quiet) {
      std::printf("heatvoronoi: %d cells on %d vertices / %ld faces -> %ld refined faces, %zu Voronoi vertices\n", n, nv,
                  static_cast<long>(mesh.F.rows()), static_cast<long>(diagram.F.rows()), diagram.voronoi_vertices.size());
      std::printf("  cell area min / mean / max: %.6g / %.6g / %.6g\n", areas.minCoeff(), areas.mean(), areas.maxCoeff());
      std::printf("  time: factor %.3f s, %d diffusions %.3f s, tessellation %.3f s, centroids %.3f s, total %.3f s\n",
                  factor_s, n, solve_s, tess_s, centroid_s, total_s);
      std::printf("  wrote %s%s%s%s\n", cells_path.c_str(), edges_path.empty() ? "" : (", " + edges_path).c_str(),
                  centroids_path.empty() ? "" : (", " + centroids_path).c_str(),
                  report_path.empty() ? "" : (", " + report_path).c_str());
    }
    return 0;
  });
}
