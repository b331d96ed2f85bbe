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

// The benchmark's command line.
struct BenchOptions {
  int iterations = 100, threads = 0, quality_every = 5;
  std::string only;
  bool quick = false, no_cgal = false;
  int repeat = 1;  // default config and CGAL run R times, interleaved: median (min–max) times
  std::string config = "both";
};

// Parses the command line into `o`: -1 to go on, else the exit status (after a message on stderr).
int parse_arguments(int argc, char** argv, BenchOptions& o) {
  for (int i = 1; i < argc; ++i) {
    auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_cvt: %s needs a value\n", argv[i]);
        std::exit(1);
      }
      return argv[++i];
    };
    if (!std::strcmp(argv[i], "--iterations")) o.iterations = std::atoi(next());
    else if (!std::strcmp(argv[i], "--threads")) o.threads = std::atoi(next());
    else if (!std::strcmp(argv[i], "--quality-every")) o.quality_every = std::atoi(next());
    else if (!std::strcmp(argv[i], "--only")) o.only = next();
    else if (!std::strcmp(argv[i], "--quick")) o.quick = true;
    else if (!std::strcmp(argv[i], "--no-cgal")) o.no_cgal = true;
    else if (!std::strcmp(argv[i], "--config")) o.config = next();
    else if (!std::strcmp(argv[i], "--repeat")) o.repeat = std::max(1, std::atoi(next()));
    else {
      std::fprintf(stderr,
                   "usage: bench_cvt [--iterations N] [--threads T] [--quality-every K] [--only NAME] [--quick] [--no-cgal] [--repeat R] "
                   "[--config default|paper|both]\n");
      return 1;
    }
  }
  return -1;
}

// The models of the table at Table-1 sizes, with the paper's row where it has a comparable one.
const std::vector<Case>& table_cases() {
  static const std::vector<Case> cases = {
      {"armadillo", "meshes/armadillo.obj", 0, 1000, {"", "", 0, 0, 0, 0, 0, 0}},
      {"armadillo-L1", "meshes/armadillo.obj", 1, 1644, {"", "", 0, 0, 0, 0, 0, 0}},
      {"casting-L2", "meshes/casting.obj", 2, 1000, {"Casting", "109k", 1000, 0.437, 54, 23.2, 50.6, 0.564}},
      {"dragon-L1", "meshes/dragon_23k.obj", 1, 1500, {"Dragon", "153k", 1500, 0.479, 71, 27.6, 51.6, 0.786}},
      {"kitten-L2", "meshes/kitten.obj", 2, 2000, {"Kitten", "442k", 2000, 3.069, 244, 38.4, 53.6, 3.536}},
      {"fertility-L3", "meshes/fertility.off", 3, 2000, {"Fertility", "499k", 2000, 3.290, 277, 35.6, 53.2, 3.646}},
  };
  return cases;
}

// The Lloyd iterations a run does: N, at most 20 with --quick.
int run_iterations(const BenchOptions& o) { return o.quick ? std::min(o.iterations, 20) : o.iterations; }

// A model prepared for the runs: the subdivided mesh, its Laplacian (timed) and the checks of a dual.
struct Model {
  TriangleMesh m;
  int nv = 0;
  Laplacian lap;
  double laplacian_s = 0;
  ValidationOptions vo;
};

// Reads and subdivides the model's mesh, notes its size on stderr and builds its Laplacian.
Model prepare_model(const Case& c) {
  Model model;
  model.m = read_mesh(std::string(HEATCVT_DATA_DIR) + "/" + c.file);
  for (int s = 0; s < c.subdivisions; ++s) model.m = loop_subdivide(model.m);
  model.nv = static_cast<int>(model.m.V.rows());
  std::fprintf(stderr, "%s: %d vertices, %d sites ...\n", c.name, model.nv, c.sites);
  const double t0 = bench::now_seconds();
  model.lap = cotan_laplacian(model.m.V, model.m.F);
  model.laplacian_s = bench::now_seconds() - t0;
  model.vo.expected_genus = mesh_genus(model.m.F, model.nv);
  model.vo.check_self_intersections = false;
  return model;
}

// CGAL's remeshing of a model: its first run and the times of every run (--repeat).
struct CgalColumns {
  CgalResult first;
  std::vector<double> times;

  // The CGAL columns of a row: vertices, angles, time (median and range), target and validity notes.
  std::string text() const {
    const bool ok = first.quality.mean_min_angle_deg >= kTargetMean && first.quality.min_angle_deg >= kTargetMin;
    return std::to_string(first.vertices) + " | " + fmt(first.quality.min_angle_deg, "%.1f°") + " | " +
           fmt(first.quality.mean_min_angle_deg, "%.1f°") + " | " + median_range(times) +
           (ok ? "" : " (targets not met)") + (first.valid ? "" : " (invalid)") + " |";
  }
};

// The default configuration: fast_cvt_options() with the development overrides of the environment.
CvtOptions default_cvt_options(const Case& c, const BenchOptions& b) {
  CvtOptions o = fast_cvt_options(c.sites);
  o.iterations = run_iterations(b);
  o.threads = b.threads;
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
  return o;
}

// Notes one Lloyd iteration of the default configuration on stderr; always goes on.
bool log_iteration(const CvtIterationStats& s) {
  std::fprintf(stderr, "  it %d: %.3f s, phi_min %.1f phi_m %.2f, spots %d, inserted %d, omega %.2f, aa %d, res %.3g, move %.3g\n",
               s.iteration, s.seconds, s.phi_min_deg, s.phi_mean_deg, s.nonmanifold_spots, s.inserted_sites,
               s.relaxation, s.anderson_columns, s.residual, s.max_move);
  return true;
}

// Mean seconds per Lloyd iteration of a run (0 without iterations).
double mean_iteration_seconds(const CvtResult& r) {
  double per_iteration = 0;
  for (const auto& s : r.iterations) per_iteration += s.seconds;
  per_iteration /= std::max<size_t>(1, r.iterations.size());
  return per_iteration;
}

// Runs the default configuration (R times with --repeat, interleaved with CGAL's remeshing, whose
// times go to `cgal`), notes its stage times on stderr and returns its row.
std::string run_default_config(const Case& c, const Model& model, const BenchOptions& b, CgalColumns& cgal) {
  const CvtOptions o = default_cvt_options(c, b);
  auto run = [&]() { return centroidal_voronoi(model.m.V, model.m.F, model.lap, o, {}, log_iteration); };
  CvtResult r = run();
  // --repeat: the same (deterministic) computation again, interleaved with CGAL, for the spread
  std::vector<double> ttq_times = {model.laplacian_s + r.total_seconds};
  for (int rep = 1; rep < b.repeat; ++rep) {
    if (!b.no_cgal) cgal.times.push_back(cgal_remesh(model.m, c.sites).seconds);
    ttq_times.push_back(model.laplacian_s + run().total_seconds);
  }
  const double per_iteration = mean_iteration_seconds(r);
  const TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
  const bool valid = validate_triangle_mesh(r.dual.V, r.dual.F, model.vo).ok();
  const double ttq = model.laplacian_s + r.total_seconds;
  std::fprintf(stderr,
               "  default: laplacian %.3f s, factor %.3f s, graph Lloyd %d it %.3f s, surface Lloyd %d it %.3f s, "
               "setup %.3f s, start quality phi_min %.1f phi_m %.2f spots %d after %d split rounds (%d refined sites) (%.3f s), total %.3f s\n",
               model.laplacian_s, r.factor_seconds, r.graph_lloyd_iterations, r.graph_lloyd_seconds,
               r.surface_lloyd_iterations, r.surface_lloyd_seconds, r.setup_seconds, r.start_phi_min_deg,
               r.start_phi_mean_deg, r.start_spots, r.start_rounds, r.refined_sites, r.start_quality_seconds, r.total_seconds);
  return std::string("| ") + c.name + " | " + std::to_string(model.nv) + " | " +
         (r.inserted_sites ? std::to_string(c.sites) + " + " + std::to_string(r.inserted_sites)
                           : std::to_string(c.sites)) +
         " | " + fmt(r.factor_seconds, "%.3f s") + " | " + fmt(r.factor_bytes / 1e6, "%.0f MB") + " | " +
         fmt(q.min_angle_deg, "%.1f°") + " | " + fmt(q.mean_min_angle_deg, "%.1f°") + " | " +
         (r.iterations.empty() ? std::string("– (0 it)") : fmt(per_iteration, "%.3f s")) + " | " +
         (valid ? "yes" : "NO") + " | " +
         (r.reached_quality ? median_range(ttq_times) + " (" + std::to_string(r.iterations.size()) + " it)"
                            : std::string("not reached: ") + (r.stalled ? "φm stalled after " : "stopped after ") +
                                  std::to_string(r.iterations.size()) + " it (" + fmt(ttq, "%.1f s") + ")") +
         " | " + cgal.text();
}

// Runs the paper's configuration (plain Lloyd, quality every K) and returns its row with the time
// to quality, or the best φm seen when the targets were not reached.
std::string run_paper_config(const Case& c, const Model& model, const BenchOptions& b, const CgalColumns& cgal) {
  CvtOptions o;
  o.sites = c.sites;
  o.iterations = run_iterations(b);
  o.threads = b.threads;
  o.quality_every = b.quality_every;
  double ttq = -1, elapsed = 0;
  int ttq_iteration = -1;
  CvtResult r = centroidal_voronoi(model.m.V, model.m.F, model.lap, o, {}, [&](const CvtIterationStats& s) {
    elapsed += s.seconds;
    if (ttq < 0 && s.phi_mean_deg >= kTargetMean && s.phi_min_deg >= kTargetMin) {
      ttq = elapsed + s.quality_seconds;
      ttq_iteration = s.iteration;
    }
    return true;
  });
  if (ttq >= 0) ttq += model.laplacian_s + r.setup_seconds;
  const double per_iteration = mean_iteration_seconds(r);
  const TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
  const bool valid = validate_triangle_mesh(r.dual.V, r.dual.F, model.vo).ok();
  // best quality seen during the run (evaluations) and when
  double best_m = -1;
  int best_it = 0;
  for (const auto& s : r.iterations)
    if (s.phi_mean_deg > best_m) best_m = s.phi_mean_deg, best_it = s.iteration;
  return std::string("| ") + c.name + " (paper config) | " + std::to_string(model.nv) + " | " + std::to_string(c.sites) +
         " | " + fmt(r.factor_seconds, "%.3f s") + " | " + fmt(r.factor_bytes / 1e6, "%.0f MB") + " | " +
         fmt(q.min_angle_deg, "%.1f°") + " | " + fmt(q.mean_min_angle_deg, "%.1f°") + " | " +
         fmt(per_iteration, "%.3f s") + " | " + (valid ? "yes" : "NO") + " | " +
         (ttq >= 0 ? fmt(ttq, "%.1f s") + " (it " + std::to_string(ttq_iteration) + ")"
                   : std::string("not reached (best φm ") + fmt(best_m, "%.1f") + " at it " +
                         std::to_string(best_it) + ")") +
         " | " + cgal.text();
}

// The paper's Table-1 row of a model ("" when it has none).
std::string paper_row(const Case& c) {
  if (!c.paper.model[0]) return std::string();
  return std::string("| paper: ") + c.paper.model + " | " + c.paper.vertices + " | " +
         std::to_string(c.paper.generators) + " | " + fmt(c.paper.factor_s, "%.3f s") + " | " +
         fmt(c.paper.memory_mb, "%.0f MB") + " | " + fmt(c.paper.phi_min, "%.1f°") + " | " +
         fmt(c.paper.phi_m, "%.1f°") + " | " + fmt(c.paper.per_iteration_s, "%.3f s") + " | | | | | | |";
}

// Prints a row on stdout at once (the table is long to make) and keeps it for the final table.
void emit_row(const std::string& row, std::vector<std::string>& rows) {
  std::printf("%s\n", row.c_str());
  std::fflush(stdout);
  rows.push_back(row);
}

// Runs the configurations asked for on one model and CGAL's remeshing beside them; emits their rows.
void bench_model(const Case& c, const BenchOptions& b, std::vector<std::string>& rows) {
  const Model model = prepare_model(c);
  // (CGAL 5.5's remeshing spent > 8 minutes in Euler::does_satisfy_link_condition on dragon-L1
  // here; --no-cgal skips it.)
  CgalColumns cgal;
  cgal.first = b.no_cgal ? CgalResult{} : cgal_remesh(model.m, c.sites);
  cgal.times = {cgal.first.seconds};
  if (b.config != "paper") emit_row(run_default_config(c, model, b, cgal), rows);
  if (b.config != "default") emit_row(run_paper_config(c, model, b, cgal), rows);
  if (const std::string paper = paper_row(c); !paper.empty()) emit_row(paper, rows);
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions b;
  if (const int status = parse_arguments(argc, argv, b); status >= 0) return status;
  std::printf("bench_cvt: %d Lloyd iterations, %d threads (paper: 4 threads, i7 3.9 GHz), quality every %d "
              "iterations, targets phi_m >= %.0f, phi_min >= %.0f\n\n",
              run_iterations(b), resolve_threads(b.threads), b.quality_every, kTargetMean, kTargetMin);
  if (b.config != "default" && b.config != "paper" && b.config != "both") {
    std::fprintf(stderr, "bench_cvt: --config must be default, paper or both\n");
    return 1;
  }
  std::vector<std::string> rows;
  for (const Case& c : table_cases()) {
    if (!b.only.empty() && b.only != c.name) continue;
    if (b.quick && c.subdivisions > 1) continue;
    bench_model(c, b, rows);
  }
  std::printf("\n| model | vertices | sites | factor time | factor memory | φmin | φm | time / iteration | dual valid | "
              "time to quality | CGAL vertices | CGAL φmin | CGAL φm | CGAL time |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) std::printf("%s\n", r.c_str());
  return 0;
}
