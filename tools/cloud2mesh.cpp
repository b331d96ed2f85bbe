// cloud2mesh: surface reconstruction from a point cloud by a heat CVT on the points (paper §8):
// point Laplacian -> centroidal Voronoi tessellation -> dual triangulation on a fitted surface.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "cli_common.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "report_json.h"

using namespace heatcvt;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  CLI::App app{"cloud2mesh: reconstruct a triangle mesh from a point cloud with a heat-diffusion centroidal "
               "Voronoi tessellation of the points (Herholz et al. 2017, §7-8)"};
  ReconstructionOptions opt;
  std::string cloud_path, out_path, report_path;
  bool quiet = false;
  app.add_option("CLOUD", cloud_path, "input point cloud (.pcd .ply .xyz .pwn .txt)")->required();
  app.add_option("-o,--output", out_path, "output mesh (.ply .obj .off .stl)")->required();
  app.add_option("-n,--sites", opt.sites, "number of output vertices (CVT sites)")->capture_default_str();
  app.add_option("-i,--iterations", opt.iterations, "maximum heat Lloyd iterations (after the surface Lloyd; use 30 with --surface-lloyd 0)")->capture_default_str();
  app.add_option("-k,--neighbours,--neighbors", opt.neighbors, "k nearest neighbours of the point Laplacian")
      ->capture_default_str();
  app.add_option("--anisotropy", opt.anisotropy, "lambda of the anisotropic lift (p, lambda n); 0 = isotropic")
      ->capture_default_str();
  app.add_flag("--denoise", opt.denoise, "statistical outlier removal before reconstruction");
  app.add_option("--voxel", opt.voxel_size, "voxel-grid downsampling size in input units; 0 = off")
      ->capture_default_str();
  app.add_option("--t-coef", opt.time_coefficient, "time step t = C * (mean edge length)^2")->capture_default_str();
  app.add_option("--seed", opt.seed, "seed of the initial sites")->capture_default_str();
  app.add_option("--relaxation", opt.lloyd_relaxation, "Lloyd over-relaxation factor in [1, 2); 1 = plain Lloyd")
      ->capture_default_str();
  app.add_flag("--fast-start", opt.farthest_point_start,
               "with --surface-lloyd 0: farthest-point initial sites relaxed on the point graph instead of seeded "
               "random ones (the paper's)");
  app.add_option("--surface-lloyd", opt.surface_lloyd_iterations,
                 "iterations of the cheap surface Lloyd on farthest-point start sites (during the factorisation); "
                 "0 = the paper's seeded random start")
      ->capture_default_str();
  app.add_option("--points-per-site", opt.cvt_points_per_site,
                 "the CVT runs on a uniform subset of about this many points per site (site positions are still "
                 "fitted to every point); 0 = every point")
      ->capture_default_str();
  app.add_flag("--no-smooth-cvt-points", [&](std::int64_t) { opt.smooth_cvt_points = false; },
               "build the Laplacian on the raw CVT points instead of their projections onto the fitted surface");
  app.add_option("--threads", opt.threads, "worker threads (0 = all cores)")->capture_default_str();
  app.add_option("--report", report_path, "write a JSON report");
  app.add_flag("-q,--quiet", quiet, "no progress and no summary");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One clear line (CLI11 would add a "Run with --help" line).
    std::cerr << "cloud2mesh: error: " << e.what() << " (see cloud2mesh --help)" << std::endl;
    return 2;
  }

  return cli::run_tool("cloud2mesh", [&]() -> int {
    // Option checks before any work (reconstruct_surface checks them again).
    if (opt.sites < 4) throw InvalidInputError("-n must be at least 4 (got " + std::to_string(opt.sites) + ")");
    if (opt.iterations < 0) throw InvalidInputError("-i must be >= 0");
    if (opt.neighbors < 6 || opt.neighbors > 200) throw InvalidInputError("-k must be between 6 and 200");
    if (!(opt.anisotropy >= 0) || !std::isfinite(opt.anisotropy)) throw InvalidInputError("--anisotropy must be >= 0");
    if (!(opt.voxel_size >= 0) || !std::isfinite(opt.voxel_size)) throw InvalidInputError("--voxel must be >= 0");
    if (!(opt.time_coefficient > 0) || !std::isfinite(opt.time_coefficient))
      throw InvalidInputError("--t-coef must be a positive number");
    if (opt.threads < 0) throw InvalidInputError("--threads must be >= 0");
    if (opt.surface_lloyd_iterations < 0) throw InvalidInputError("--surface-lloyd must be >= 0");
    if (!(opt.cvt_points_per_site == 0 || opt.cvt_points_per_site >= 3) || !std::isfinite(opt.cvt_points_per_site))
      throw InvalidInputError("--points-per-site must be 0 (every point) or at least 3");
    if (!(opt.lloyd_relaxation >= 1 && opt.lloyd_relaxation < 2)) throw InvalidInputError("--relaxation must be in [1, 2)");
    cli::check_output_path(out_path, {".ply", ".obj", ".off", ".stl"});
    cli::check_output_path(report_path, {".json"});

    const auto t_start = Clock::now();
    CloudReadReport rr;
    PointCloud cloud = read_cloud(cloud_path, &rr);
    if (!quiet)
      std::cerr << "read " << cloud_path << ": " << rr.points_in_file << " points, " << rr.non_finite_dropped
                << " non-finite dropped, " << rr.duplicates_merged << " duplicates merged" << std::endl;
    if (opt.sites > cloud.P.rows())
      throw InvalidInputError(cloud_path + ": -n " + std::to_string(opt.sites) + " exceeds the " +
                              std::to_string(cloud.P.rows()) + " usable points");

    ReconstructionResult res;
    {
      cli::Progress bar("reconstructing", 1000, quiet);
      // Stages weighted by their typical share of the time.
      res = reconstruct_surface(cloud.P, opt, [&](const std::string& stage, double f) {
        double done = 0;
        if (stage == "preprocess") done = 0;
        else if (stage == "laplacian") done = 0.02 + 0.08 * f;
        else if (stage == "cvt") done = 0.10 + 0.80 * f;
        else if (stage == "mesh") done = 0.90 + 0.05 * f;
        else done = 0.95 + 0.05 * f;
        bar.update(static_cast<long>(1000 * done));
      });
      bar.finish();
    }
    write_mesh(out_path, res.mesh.V, res.mesh.F);
    const double total_s = cli::seconds_since(t_start);
    const auto& val = res.validation;
    double iteration_sum = 0;
    for (double t : res.iteration_seconds) iteration_sum += t;
    const double per_iter = res.iterations > 0 ? iteration_sum / res.iterations : 0.0;

    if (!report_path.empty()) {
      cli::JsonObject checks;
      for (const auto& c : val.checks)
        checks.add(c.name, c.ran ? (c.passed ? std::string("pass") : "fail: " + c.detail) : std::string("not run"));
      cli::JsonObject timings;
      timings.add("laplacian_s", res.laplacian_seconds).add("factor_s", res.factor_seconds)
          .add("cvt_s", res.cvt_seconds).add("per_iteration_s", per_iter).add("reconstruct_s", res.total_seconds)
          .add("total_s", total_s);
      timings.add("blas", heatcvt::blas_description());
      cli::JsonObject stages;
      for (const auto& [name, seconds] : res.stage_seconds) stages.add(name, seconds);
      timings.add_object("stages", stages);
      cli::JsonObject j;
      j.add("input", cloud_path).add("output", out_path).add("format", rr.format)
          .add("points_in_file", rr.points_in_file).add("non_finite_dropped", rr.non_finite_dropped)
          .add("duplicates_merged", rr.duplicates_merged).add("points_denoised", res.points_denoised)
          .add("points_voxel_removed", res.points_voxel_removed).add("points_used", res.points_used)
          .add("sites", opt.sites).add("iterations", res.iterations).add("neighbors", opt.neighbors)
          .add("anisotropy", opt.anisotropy).add("seed", static_cast<long>(opt.seed))
          .add("vertices", static_cast<long>(res.mesh.V.rows())).add("faces", static_cast<long>(res.mesh.F.rows()))
          .add("unused_sites", res.unused_sites).add("candidate_triangles", res.candidate_triangles)
          .add("rejected_triangles", res.rejected_triangles).add("removed_triangles", res.removed_triangles)
          .add("holes_filled", res.holes_filled).add("boundary_loops", val.boundary_loops)
          .add("components", val.components).add("genus", val.genus)
          .add("self_intersecting_pairs", val.self_intersecting_pairs)
          .add("min_angle_deg", res.min_angle_deg).add("mean_min_angle_deg", res.mean_min_angle_deg)
          .add("valid", val.ok()).add_object("checks", checks).add_object("timings", timings);
      cli::write_json(report_path, j);
    }
    if (!quiet) {
      std::printf("cloud2mesh: %s -> %s\n", cloud_path.c_str(), out_path.c_str());
      std::printf("  points: %ld read, %ld non-finite dropped, %ld duplicates merged, %d outliers removed, "
                  "%d voxel-merged, %d used\n",
                  rr.points_in_file, rr.non_finite_dropped, rr.duplicates_merged + res.points_merged,
                  res.points_denoised, res.points_voxel_removed, res.points_used);
      std::printf("  time: Laplacian %.3f s, factor %.3f s, CVT %.3f s (%d heat iterations, %.3f s each), total %.3f s\n",
                  res.laplacian_seconds, res.factor_seconds, res.cvt_seconds, res.iterations, per_iter, total_s);
      std::printf("  stages:");
      for (const auto& [name, seconds] : res.stage_seconds) std::printf(" %s %.2f s;", name.c_str(), seconds);
      std::printf("\n");
      std::printf("  mesh: %ld vertices, %ld faces, %d components, %d boundary loops, genus %d; %d holes filled, "
                  "%d unused sites\n",
                  static_cast<long>(res.mesh.V.rows()), static_cast<long>(res.mesh.F.rows()), val.components,
                  val.boundary_loops, val.genus, res.holes_filled, res.unused_sites);
      std::printf("  quality: phi_min %.2f deg, phi_m %.2f deg\n", res.min_angle_deg, res.mean_min_angle_deg);
      for (const auto& c : val.checks)
        std::printf("  %s %s: %s\n", !c.ran ? "SKIP" : (c.passed ? "PASS" : "FAIL"), c.name.c_str(), c.detail.c_str());
      std::printf("  wrote %s%s\n", out_path.c_str(), report_path.empty() ? "" : (", " + report_path).c_str());
    }
    return 0;
  });
}
