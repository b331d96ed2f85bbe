// Table 1 of the paper (§7.1) on meshes from ../shared/data, Loop-subdivided to Table-1 sizes, with
// CGAL's isotropic remeshing (5 iterations, same vertex count) side by side and the time to quality
// (φm ≥ 51°, φmin ≥ 25°).
//
//   bench_cvt [--iterations N] [--threads T] [--quality-every K] [--only NAME] [--quick] [--no-cgal] [--repeat R]
//             [--config default|paper|both]
//
// Two CVT configurations per model: `default` = fast_cvt_options() (meshcvt's CVT with the dual
// as output, --no-post-cvt, targets φm ≥ 51° and φmin ≥ 25°: farthest-point + surface-Lloyd
// start during the factorisation, quality of the start checked before any heat iteration with
// split / small-angle rounds, then over-relaxed heat Lloyd, quality checked every 2nd iteration,
// cells split where too big for thin parts; stops at quality, at most N iterations; "– (0 it)"
// in the time/iteration column: the start met the targets) and `paper` = CvtOptions{} (random
// start, plain Lloyd, N iterations, quality every K).
// Development overrides of the default configuration (environment): CVT_RELAXATION, CVT_ANDERSON,
// CVT_GRAPH_LLOYD, CVT_SPLIT, CVT_INIT_RANDOM, CVT_SURFACE_LLOYD, CVT_SURFACE_OMEGA, CVT_SURFACE_TOL,
// CVT_QUALITY_AT_START, CVT_QUALITY_EVERY, CVT_RINGS_SETTLED, CVT_SPLIT_ROUNDS, CVT_SPLIT_IT, CVT_ORDERING,
// CVT_REFINE (e.g. the previous defaults: CVT_SURFACE_LLOYD=0 CVT_QUALITY_AT_START=0 CVT_GRAPH_LLOYD=20).
// For `default` the time to quality is Laplacian + the whole centroidal_voronoi() call (set-up,
// factorisation, iterations, evaluations, final diagram and dual) when it stopped at quality.
//
// Time to quality of the CVT = Laplacian + factorisation + set-up + the Lloyd iterations up to the
// first evaluation that meets both targets + one final diagram/dual (the evaluation's own time):
// what `meshcvt --target-phi-m 51 --target-phi-min 25 --quality-every K` spends. For CGAL it is the
// remeshing time when its result meets the targets.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench_util.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/parallel.h"
#include "heatcvt/subdivision.h"
#include "heatcvt/validate.h"

using namespace heatcvt;

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

constexpr double kTargetMean = 51.0, kTargetMin = 25.0;

struct PaperRow {
  const char* model;
  const char* vertices;
  int generators;
  double factor_s, memory_mb, phi_min, phi_m, per_iteration_s;
};

struct Case {
  const char* name;
  const char* file;
  int subdivisions;
  int sites;
  PaperRow paper;  // model "" = no comparable row
};

struct CgalResult {
  int vertices = 0;
  double seconds = 0;
  TriangleQuality quality;
  bool valid = false;
};

// "4.2 s" for one time, "4.2 s (3.9–4.6)" median (min–max) for several.
std::string median_range(std::vector<double> t) {
  std::sort(t.begin(), t.end());
  char buf[96];
  if (t.size() == 1) std::snprintf(buf, sizeof buf, "%.1f s", t[0]);
  else std::snprintf(buf, sizeof buf, "%.1f s (%.1f–%.1f)", t[t.size() / 2], t.front(), t.back());
  return buf;
}

CgalResult cgal_remesh(const TriangleMesh& m, int target_vertices) {
  std::vector<Kernel::Point_3> points;
  for (int v = 0; v < m.V.rows(); ++v) points.emplace_back(m.V(v, 0), m.V(v, 1), m.V(v, 2));
  std::vector<std::vector<std::size_t>> polygons;
  for (int f = 0; f < m.F.rows(); ++f)
    polygons.push_back({static_cast<std::size_t>(m.F(f, 0)), static_cast<std::size_t>(m.F(f, 1)),
                        static_cast<std::size_t>(m.F(f, 2))});
  CgalMesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  // Equilateral triangles: a closed mesh with N vertices has ~2N triangles of area (√3/4)L².
  const double L = std::sqrt(2.0 * surface_area(m.V, m.F) / (std::sqrt(3.0) * target_vertices));
  const double t0 = bench::now_seconds();
  PMP::isotropic_remeshing(faces(mesh), L, mesh, CGAL::parameters::number_of_iterations(5));
  mesh.collect_garbage();
  CgalResult r;
  r.seconds = bench::now_seconds() - t0;
  r.vertices = static_cast<int>(num_vertices(mesh));
  Eigen::MatrixX3d V(num_vertices(mesh), 3);
  Eigen::MatrixX3i F(num_faces(mesh), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    V.row(v.idx()) << p.x(), p.y(), p.z();
  }
  int f = 0;
  for (auto face : mesh.faces()) {
    int k = 0;
    for (auto v : vertices_around_face(mesh.halfedge(face), mesh)) F(f, k++) = static_cast<int>(v.idx());
    ++f;
  }
  r.quality = triangle_quality(V, F);
  ValidationOptions vo;
  vo.check_self_intersections = false;
  vo.expected_genus = mesh_genus(m.F, static_cast<int>(m.V.rows()));
  r.valid = validate_triangle_mesh(V, F, vo).ok();
  return r;
}

std::string fmt(double x, const char* f) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 100, threads = 0, quality_every = 5;
  std::string only;
  bool quick = false, no_cgal = false;
  int repeat = 1;  // default config and CGAL run R times, interleaved: median (min–max) times
  std::string config = "both";
  for (int i = 1; i < argc; ++i) {
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_cvt: %s needs a value\n", argv[i]);
        std::exit(1);
      }
      return argv[++i];
    };
    if (!std::strcmp(argv[i], "--iterations")) iterations = std::atoi(next());
    else if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(next());
    else if (!std::strcmp(argv[i], "--quality-every")) quality_every = std::atoi(next());
    else if (!std::strcmp(argv[i], "--only")) only = next();
    else if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--no-cgal")) no_cgal = true;
    else if (!std::strcmp(argv[i], "--config")) config = next();
    else if (!std::strcmp(argv[i], "--repeat")) repeat = std::max(1, std::atoi(next()));
    else {
      std::fprintf(stderr,
                   "usage: bench_cvt [--iterations N] [--threads T] [--quality-every K] [--only NAME] [--quick] [--no-cgal] [--repeat R] "
                   "[--config default|paper|both]\n");
      return 1;
    }
  }
  const std::string data = HEATCVT_DATA_DIR;
  const std::vector<Case> cases = {
      {"armadillo", "meshes/armadillo.obj", 0, 1000, {"", "", 0, 0, 0, 0, 0, 0}},
      {"armadillo-L1", "meshes/armadillo.obj", 1, 1644, {"", "", 0, 0, 0, 0, 0, 0}},
      {"casting-L2", "meshes/casting.obj", 2, 1000, {"Casting", "109k", 1000, 0.437, 54, 23.2, 50.6, 0.564}},
      {"dragon-L1", "meshes/dragon_23k.obj", 1, 1500, {"Dragon", "153k", 1500, 0.479, 71, 27.6, 51.6, 0.786}},
      {"kitten-L2", "meshes/kitten.obj", 2, 2000, {"Kitten", "442k", 2000, 3.069, 244, 38.4, 53.6, 3.536}},
      {"fertility-L3", "meshes/fertility.off", 3, 2000, {"Fertility", "499k", 2000, 3.290, 277, 35.6, 53.2, 3.646}},
  };
  std::printf("bench_cvt: %d Lloyd iterations, %d threads (paper: 4 threads, i7 3.9 GHz), quality every %d "
              "iterations, targets phi_m >= %.0f, phi_min >= %.0f\n\n",
              quick ? std::min(iterations, 20) : iterations, resolve_threads(threads), quality_every, kTargetMean,
              kTargetMin);
  struct Row {
    std::string text;
  };
  std::vector<std::string> rows;
  if (config != "default" && config != "paper" && config != "both") {
    std::fprintf(stderr, "bench_cvt: --config must be default, paper or both\n");
    return 1;
  }
  for (const Case& c : cases) {
    if (!only.empty() && only != c.name) continue;
    if (quick && c.subdivisions > 1) continue;
    TriangleMesh m = read_mesh(data + "/" + c.file);
    for (int s = 0; s < c.subdivisions; ++s) m = loop_subdivide(m);
    const int nv = static_cast<int>(m.V.rows());
    std::fprintf(stderr, "%s: %d vertices, %d sites ...\n", c.name, nv, c.sites);

    double t0 = bench::now_seconds();
    Laplacian lap = cotan_laplacian(m.V, m.F);
    const double laplacian_s = bench::now_seconds() - t0;
    ValidationOptions vo;
    vo.expected_genus = mesh_genus(m.F, nv);
    vo.check_self_intersections = false;
    // (CGAL 5.5's remeshing spent > 8 minutes in Euler::does_satisfy_link_condition on dragon-L1
    // here; --no-cgal skips it.)
    CgalResult cg = no_cgal ? CgalResult{} : cgal_remesh(m, c.sites);
    std::vector<double> cgal_times = {cg.seconds};
    const bool cg_ok = cg.quality.mean_min_angle_deg >= kTargetMean && cg.quality.min_angle_deg >= kTargetMin;
    auto cgal_columns = [&]() {
      return std::to_string(cg.vertices) + " | " + fmt(cg.quality.min_angle_deg, "%.1f°") + " | " +
             fmt(cg.quality.mean_min_angle_deg, "%.1f°") + " | " + median_range(cgal_times) +
             (cg_ok ? "" : " (targets not met)") + (cg.valid ? "" : " (invalid)") + " |";
    };
    std::string cgal_cols = cgal_columns();
    std::string row;
    if (config != "paper") {
      CvtOptions o = fast_cvt_options(c.sites);
      o.iterations = quick ? std::min(iterations, 20) : iterations;
      o.threads = threads;
      // development overrides of the default configuration (not used for the README table)
      if (const char* e = std::getenv("CVT_RELAXATION")) o.relaxation = std::atof(e);
      if (const char* e = std::getenv("CVT_ANDERSON")) o.anderson_depth = std::atoi(e);
      if (const char* e = std::getenv("CVT_GRAPH_LLOYD")) o.graph_lloyd_iterations = std::atoi(e);
      if (const char* e = std::getenv("CVT_SPLIT")) o.split_nonmanifold_cells = std::atoi(e) != 0;
      if (const char* e = std::getenv("CVT_INIT_RANDOM")) o.initialization = CvtInitialization::random;
      if (const char* e = std::getenv("CVT_SURFACE_LLOYD")) o.surface_lloyd_iterations = std::atoi(e);
      if (const char* e = std::getenv("CVT_SURFACE_OMEGA")) o.surface_lloyd_relaxation = std::atof(e);
      if (const char* e = std::getenv("CVT_SURFACE_TOL")) o.surface_lloyd_tolerance = std::atof(e);
      if (const char* e = std::getenv("CVT_QUALITY_AT_START")) o.quality_at_start = std::atoi(e) != 0;
      if (const char* e = std::getenv("CVT_QUALITY_EVERY")) o.quality_every = std::atoi(e);
      if (const char* e = std::getenv("CVT_RINGS_SETTLED")) o.voronoi_rings_settled = std::atoi(e);
      if (const char* e = std::getenv("CVT_SPLIT_ROUNDS")) o.surface_lloyd_split_rounds = std::atoi(e);
      if (const char* e = std::getenv("CVT_SPLIT_IT")) o.surface_lloyd_split_iterations = std::atoi(e);
      if (const char* e = std::getenv("CVT_REFINE")) o.refine_small_angles = std::atoi(e) != 0;
      if (const char* e = std::getenv("CVT_ORDERING"))  // amd | metis | automatic
        o.ordering = !std::strcmp(e, "amd") ? FillOrdering::amd
                     : !std::strcmp(e, "metis") ? FillOrdering::metis : FillOrdering::automatic;
      auto run = [&]() {
        return centroidal_voronoi(m.V, m.F, lap, o, {}, [&](const CvtIterationStats& s) {
          std::fprintf(stderr, "  it %d: %.3f s, phi_min %.1f phi_m %.2f, spots %d, inserted %d, omega %.2f, aa %d, res %.3g, move %.3g\n",
                       s.iteration, s.seconds, s.phi_min_deg, s.phi_mean_deg, s.nonmanifold_spots, s.inserted_sites,
                       s.relaxation, s.anderson_columns, s.residual, s.max_move);
          return true;
        });
      };
      CvtResult r = run();
      // --repeat: the same (deterministic) computation again, interleaved with CGAL, for the spread
      std::vector<double> ttq_times = {laplacian_s + r.total_seconds};
      for (int rep = 1; rep < repeat; ++rep) {
        if (!no_cgal) cgal_times.push_back(cgal_remesh(m, c.sites).seconds);
        ttq_times.push_back(laplacian_s + run().total_seconds);
      }
      cgal_cols = cgal_columns();
      double per_iteration = 0;
      for (const auto& s : r.iterations) per_iteration += s.seconds;
      per_iteration /= std::max<size_t>(1, r.iterations.size());
      const TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
      const bool valid = validate_triangle_mesh(r.dual.V, r.dual.F, vo).ok();
      const double ttq = laplacian_s + r.total_seconds;
      std::fprintf(stderr,
                   "  default: laplacian %.3f s, factor %.3f s, graph Lloyd %d it %.3f s, surface Lloyd %d it %.3f s, "
                   "setup %.3f s, start quality phi_min %.1f phi_m %.2f spots %d after %d split rounds (%d refined sites) (%.3f s), total %.3f s\n",
                   laplacian_s, r.factor_seconds, r.graph_lloyd_iterations, r.graph_lloyd_seconds,
                   r.surface_lloyd_iterations, r.surface_lloyd_seconds, r.setup_seconds, r.start_phi_min_deg,
                   r.start_phi_mean_deg, r.start_spots, r.start_rounds, r.refined_sites, r.start_quality_seconds, r.total_seconds);
      row = std::string("| ") + c.name + " | " + std::to_string(nv) + " | " +
            (r.inserted_sites ? std::to_string(c.sites) + " + " + std::to_string(r.inserted_sites)
                              : std::to_string(c.sites)) +
            " | " + fmt(r.factor_seconds, "%.3f s") + " | " + fmt(r.factor_bytes / 1e6, "%.0f MB") + " | " +
            fmt(q.min_angle_deg, "%.1f°") + " | " + fmt(q.mean_min_angle_deg, "%.1f°") + " | " +
            (r.iterations.empty() ? std::string("– (0 it)") : fmt(per_iteration, "%.3f s")) + " | " +
            (valid ? "yes" : "NO") + " | " +
            (r.reached_quality ? median_range(ttq_times) + " (" + std::to_string(r.iterations.size()) + " it)"
                               : std::string("not reached: ") + (r.stalled ? "φm stalled after " : "stopped after ") +
                                     std::to_string(r.iterations.size()) + " it (" + fmt(ttq, "%.1f s") + ")") +
            " | " + cgal_cols;
      std::printf("%s\n", row.c_str());
      std::fflush(stdout);
      rows.push_back(row);
    }
    if (config != "default") {
    CvtOptions o;
    o.sites = c.sites;
    o.iterations = quick ? std::min(iterations, 20) : iterations;
    o.threads = threads;
    o.quality_every = quality_every;
    double ttq = -1, elapsed = 0;
    int ttq_iteration = -1;
    CvtResult r = centroidal_voronoi(m.V, m.F, lap, o, {}, [&](const CvtIterationStats& s) {
      elapsed += s.seconds;
      if (ttq < 0 && s.phi_mean_deg >= kTargetMean && s.phi_min_deg >= kTargetMin) {
        ttq = elapsed + s.quality_seconds;
        ttq_iteration = s.iteration;
      }
      return true;
    });
    if (ttq >= 0) ttq += laplacian_s + r.setup_seconds;
    double per_iteration = 0;
    for (const auto& s : r.iterations) per_iteration += s.seconds;
    per_iteration /= std::max<size_t>(1, r.iterations.size());
    const TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
    const bool valid = validate_triangle_mesh(r.dual.V, r.dual.F, vo).ok();
    // best quality seen during the run (evaluations) and when
    double best_m = -1;
    int best_it = 0;
    for (const auto& s : r.iterations)
      if (s.phi_mean_deg > best_m) best_m = s.phi_mean_deg, best_it = s.iteration;
    row = std::string("| ") + c.name + " (paper config) | " + std::to_string(nv) + " | " + std::to_string(c.sites) +
                      " | " + fmt(r.factor_seconds, "%.3f s") + " | " + fmt(r.factor_bytes / 1e6, "%.0f MB") + " | " +
                      fmt(q.min_angle_deg, "%.1f°") + " | " + fmt(q.mean_min_angle_deg, "%.1f°") + " | " +
                      fmt(per_iteration, "%.3f s") + " | " + (valid ? "yes" : "NO") + " | " +
                      (ttq >= 0 ? fmt(ttq, "%.1f s") + " (it " + std::to_string(ttq_iteration) + ")"
                                : std::string("not reached (best φm ") + fmt(best_m, "%.1f") + " at it " +
                                      std::to_string(best_it) + ")") +
                      " | " + cgal_cols;
    std::printf("%s\n", row.c_str());
    std::fflush(stdout);
    rows.push_back(row);
    }
    std::string paper = c.paper.model[0] ? std::string("| paper: ") + c.paper.model + " | " + c.paper.vertices +
                                               " | " + std::to_string(c.paper.generators) + " | " +
                                               fmt(c.paper.factor_s, "%.3f s") + " | " +
                                               fmt(c.paper.memory_mb, "%.0f MB") + " | " +
                                               fmt(c.paper.phi_min, "%.1f°") + " | " + fmt(c.paper.phi_m, "%.1f°") +
                                               " | " + fmt(c.paper.per_iteration_s, "%.3f s") +
                                               " | | | | | | |"
                                         : std::string();
    if (!paper.empty()) std::printf("%s\n", paper.c_str());
    std::fflush(stdout);
    if (!paper.empty()) rows.push_back(paper);
  }
  std::printf("\n| model | vertices | sites | factor time | factor memory | φmin | φm | time / iteration | dual valid | "
              "time to quality | CGAL vertices | CGAL φmin | CGAL φm | CGAL time |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) std::printf("%s\n", r.c_str());
  return 0;
}
