// Reconstruction benchmark: heatcvt (cloud2mesh's reconstruct_surface) against PCL greedy
// projection triangulation, PCL Poisson, CGAL Poisson, CGAL advancing-front reconstruction, and
// each Poisson followed by CGAL isotropic remeshing to `sites` vertices (the two-step pipelines a
// careful user would run); on clouds sampled (without normals) from closed meshes of known genus,
// clean and with Gaussian noise (0.25 % of the bbox diagonal). One run per cell; prints a markdown
// table with the acceptance verdict per heatcvt row.
//
// Usage: bench_reconstruct [points=50000] [sites=3000]
//            [shapes=bunny_pmp.off,armadillo.obj,kitten.obj,fertility.off,elephant.off]
//            [--only-heatcvt] [--clean-only | --noisy-only] [--threads T] [--anisotropy L] [--adaptive A]
//            [--iterations N] [--relaxation W] [--tolerance X] [--random-start | --fast-start]
//            [--surface-lloyd N] [--points-per-site X] [--polish N] [--no-smooth] [--no-tips]
//            (heatcvt options; --no-tips: no repair of the tips after the mesher, coverage.rounds = 0)
//            [--save-dir DIR]   (writes each cloud as DIR/<shape>_<clean|noisy>.xyz and heatcvt's mesh
//            beside it as .ply, to look at where the distances come from)
// The Poisson and remeshing peers are those of the acceptance test (tests/support/peer_pipelines.h).
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <pcl/PolygonMesh.h>
#include <pcl/point_types.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <stdexcept>
#include <sstream>
#include <string>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/validate.h"
#include "peer_pipelines.h"

using namespace heatcvt;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Row {
  std::string shape, method;
  double seconds = 0;  // the method itself
  double pipeline_seconds = 0;  // end to end from the bare cloud (normals + Poisson + remesh for two-step rows)
  long V = 0, F = 0;
  bool manifold = false, closed = false, self_intersecting = false;
  int genus = -1, source_genus = -1;
  double phi_m = 0, phi_min = 0, mean_dist = 0, hausdorff = 0;
  double ratio = -1;  // heatcvt rows: mean distance / best two-step mean distance
  bool noisy = false, heat = false, accepted = false;
  std::string note;
};

void measure(Row& r, const TriangleMesh& m, const TriangleMesh& src, double diag, bool check_self_intersections) {
  r.V = m.V.rows();
  r.F = m.F.rows();
  if (m.F.rows() == 0) {
    r.note = "no faces";
    return;
  }
  ValidationOptions vo;
  vo.require_closed = false;
  vo.check_self_intersections = check_self_intersections;
  vo.max_listed = 1;
  const ValidationReport rep = validate_triangle_mesh(m.V, m.F, vo);
  auto passed = [&](const char* n) {
    const MeshCheck* c = rep.find(n);
    return c && c->ran && c->passed;
  };
  r.manifold = passed("manifold_edges") && passed("manifold_vertices") && passed("consistent_orientation");
  r.closed = r.manifold && rep.boundary_loops == 0;
  r.genus = rep.genus;
  r.self_intersecting = check_self_intersections && rep.self_intersecting_pairs != 0;
  if (rep.components != 1) r.note += std::to_string(rep.components) + " components ";
  if (r.self_intersecting) r.note += "self-intersecting ";
  if (rep.boundary_loops > 0) r.note += std::to_string(rep.boundary_loops) + " boundary loops ";
  const TriangleQuality q = triangle_quality(m.V, m.F);
  r.phi_m = q.mean_min_angle_deg;
  r.phi_min = q.min_angle_deg;
  const SurfaceDistance d = surface_distance(src.V, src.F, m.V, m.F, 20000);
  r.mean_dist = d.mean / diag;
  r.hausdorff = d.hausdorff / diag;
}

// The benchmark's command line: [points] [sites] [shapes] and the heatcvt options (< 0: the
// library default).
struct BenchOptions {
  std::vector<std::string> pos;
  bool only_heat = false, clean = true, noisy = true;
  int threads = 0;
  double anisotropy = -1;  // < 0: the library default
  double adaptivity = -1;  // < 0: the library default (uniform sizing)
  int iterations = -1;     // < 0: the library default (as the next two)
  double relaxation = -1, tolerance = -1;
  bool random_start = false, fast_start = false;
  int surface_lloyd = -1;       // < 0: the library default
  double points_per_site = -1;  // < 0: the library default
  int polish = -1;              // < 0: the library default (relaxation_iterations)
  bool no_smooth = false;       // smooth_cvt_points = false
  bool no_tips = false;         // coverage.rounds = 0: the tips' repair off
  std::string save_dir;         // non-empty: clouds and heatcvt meshes written there
};

// Parses the command line into `o`; false (after a message on stderr) for an unknown option.
bool parse_arguments(int argc, char** argv, BenchOptions& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--only-heatcvt") o.only_heat = true;
    else if (a == "--clean-only") o.noisy = false;
    else if (a == "--noisy-only") o.clean = false;
    else if (a == "--threads" && i + 1 < argc) o.threads = std::atoi(argv[++i]);
    else if (a == "--anisotropy" && i + 1 < argc) o.anisotropy = std::atof(argv[++i]);
    else if (a == "--adaptive" && i + 1 < argc) o.adaptivity = std::atof(argv[++i]);
    else if (a == "--iterations" && i + 1 < argc) o.iterations = std::atoi(argv[++i]);
    else if (a == "--relaxation" && i + 1 < argc) o.relaxation = std::atof(argv[++i]);
    else if (a == "--tolerance" && i + 1 < argc) o.tolerance = std::atof(argv[++i]);
    else if (a == "--random-start") o.random_start = true;
    else if (a == "--fast-start") o.fast_start = true;
    else if (a == "--surface-lloyd" && i + 1 < argc) o.surface_lloyd = std::atoi(argv[++i]);
    else if (a == "--points-per-site" && i + 1 < argc) o.points_per_site = std::atof(argv[++i]);
    else if (a == "--polish" && i + 1 < argc) o.polish = std::atoi(argv[++i]);
    else if (a == "--no-smooth") o.no_smooth = true;
    else if (a == "--no-tips") o.no_tips = true;
    else if (a == "--save-dir" && i + 1 < argc) o.save_dir = argv[++i];
    else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "bench_reconstruct: unknown option %s\n", a.c_str());
      return false;
    } else o.pos.push_back(a);
  }
  return true;
}

// The shapes to sample: the third positional argument (comma-separated) or the default five.
std::vector<std::string> shape_list(const BenchOptions& o) {
  std::vector<std::string> shapes = {"bunny_pmp.off", "armadillo.obj", "kitten.obj", "fertility.off", "elephant.off"};
  if (o.pos.size() > 2) {
    shapes.clear();
    std::stringstream ss(o.pos[2]);
    for (std::string s; std::getline(ss, s, ',');) shapes.push_back(s);
  }
  return shapes;
}

// The options of heatcvt's reconstruction: the library defaults with what the arguments set.
ReconstructionOptions heat_options(const BenchOptions& o, int sites) {
  ReconstructionOptions opt;
  opt.sites = sites;
  opt.threads = o.threads;
  if (o.anisotropy >= 0) opt.anisotropy = o.anisotropy;
  if (o.adaptivity >= 0) opt.adaptive.adaptivity = o.adaptivity;
  if (o.iterations >= 0) opt.iterations = o.iterations;
  if (o.relaxation >= 0) opt.lloyd_relaxation = o.relaxation;
  if (o.tolerance >= 0) opt.lloyd_tolerance = o.tolerance;
  if (o.random_start) opt.farthest_point_start = false;
  if (o.fast_start) opt.farthest_point_start = true;
  if (o.surface_lloyd >= 0) opt.surface_lloyd_iterations = o.surface_lloyd;
  if (o.points_per_site >= 0) opt.cvt_points_per_site = o.points_per_site;
  if (o.polish >= 0) opt.relaxation_iterations = o.polish;
  if (o.no_smooth) opt.smooth_cvt_points = false;
  if (o.no_tips) opt.coverage.rounds = 0;
  return opt;
}

// Prints on stderr the CVT configuration that reconstruct_surface runs with these options.
void print_cvt_configuration(const ReconstructionOptions& options) {
  const CvtOptions c = reconstruction_cvt_options(options);  // what reconstruct_surface runs
  std::fprintf(stderr, "heatcvt CVT: %d sites, %d heat iterations, %s start, %d surface-Lloyd iterations (omega %.2f), "
               "%d graph-Lloyd iterations, relaxation %.2f, Voronoi rings %d\n", c.sites, c.iterations,
               c.initialization == CvtInitialization::farthest_point ? "farthest-point" : "random",
               c.surface_lloyd_iterations, c.surface_lloyd_relaxation, c.graph_lloyd_iterations, c.relaxation,
               c.voronoi_rings);
}

// The rows of one cloud (a shape, clean or noisy): each method run, timed and measured against the source.
struct Cell {
  std::string label;
  bool noisy = false;
  int genus = -1;
  const TriangleMesh& src;
  double diag = 0;
  std::vector<Row> rows;

  // Runs one method, measures its mesh (a failure is a row with the error as its note), logs the
  // row on stderr and appends it; returns the mesh.
  TriangleMesh run(const std::string& method, const std::function<TriangleMesh()>& f, bool check_si = true) {
    Row r;
    r.shape = label;
    r.method = method;
    r.noisy = noisy;
    r.source_genus = genus;
    const double t0 = now();
    TriangleMesh m;
    try {
      m = f();
      r.seconds = now() - t0;
      measure(r, m, src, diag, check_si);
    } catch (const std::exception& e) {
      r.seconds = now() - t0;
      r.note = std::string("failed: ") + e.what();
    }
    r.pipeline_seconds = r.seconds;
    std::fprintf(stderr, "   %-28s %.2fs V %ld F %ld genus %d phi_m %.1f phi_min %.1f dist %.5f %s\n",
                 method.c_str(), r.seconds, r.V, r.F, r.genus, r.phi_m, r.phi_min, r.mean_dist, r.note.c_str());
    rows.push_back(r);
    return m;
  }
};

// CGAL's advancing-front reconstruction of the points (their own vertices, unused ones dropped).
TriangleMesh advancing_front(const Eigen::MatrixX3d& P) {
  std::vector<K::Point_3> pts;
  for (Eigen::Index i = 0; i < P.rows(); ++i) pts.emplace_back(P(i, 0), P(i, 1), P(i, 2));
  std::vector<std::array<std::size_t, 3>> facets;
  CGAL::advancing_front_surface_reconstruction(pts.begin(), pts.end(), std::back_inserter(facets));
  TriangleMesh m;
  m.V = P;
  m.F.resize(facets.size(), 3);
  for (size_t i = 0; i < facets.size(); ++i)
    for (int k = 0; k < 3; ++k) m.F(i, k) = static_cast<int>(facets[i][k]);
  return test::compact(m);
}

// Runs the other methods on the cloud: PCL GP3, CGAL advancing front, both Poissons and both
// Poisson + remesh pipelines, with their end-to-end times.
void run_peers(Cell& cell, const Eigen::MatrixX3d& P, int threads, int sites) {
  // Normals for the other methods: PCA (k = 30) + MST orientation, the same as heatcvt uses
  // (heatcvt receives the bare points; its time includes its own normals).
  const double tn = now();
  const Eigen::MatrixX3d N = test::peer_normals(P, threads);
  const double normal_seconds = now() - tn;
  // Mean spacing for the radius-based methods.
  const Eigen::MatrixXi nn = k_nearest_neighbors(P, 1);
  double spacing = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) spacing += (P.row(i) - P.row(nn(i, 0))).norm();
  spacing /= P.rows();

  cell.run("PCL GP3", [&]() { return test::pcl_greedy_projection(P, N, 4 * spacing); }, false);
  cell.rows.back().pipeline_seconds += normal_seconds;
  cell.run("CGAL advancing front", [&]() { return advancing_front(P); }, false);
  const TriangleMesh pcl_poisson = cell.run("PCL Poisson (depth 8)", [&]() { return test::pcl_poisson(P, N, 8); }, false);
  const double pcl_poisson_seconds = cell.rows.back().seconds + normal_seconds;
  cell.rows.back().pipeline_seconds = pcl_poisson_seconds;
  const TriangleMesh cgal_poisson = cell.run("CGAL Poisson", [&]() { return test::cgal_poisson(P, N); }, false);
  const double cgal_poisson_seconds = cell.rows.back().seconds + normal_seconds;
  cell.rows.back().pipeline_seconds = cgal_poisson_seconds;
  // The remeshing's time is that of its last run (remesh_to() searches the edge length that
  // gives the count; a user who knew it would run once).
  const auto two_step = [&](const std::string& method, const TriangleMesh& poisson, double poisson_seconds) {
    double last_run = 0;
    cell.run(method, [&]() {
      if (poisson.F.rows() == 0) throw std::runtime_error("no Poisson mesh");
      return test::remesh_to(poisson, sites, &last_run);
    });
    if (last_run > 0) cell.rows.back().seconds = last_run;
    cell.rows.back().pipeline_seconds = cell.rows.back().seconds + poisson_seconds;
  };
  two_step("PCL Poisson + CGAL remesh", pcl_poisson, pcl_poisson_seconds);
  two_step("CGAL Poisson + CGAL remesh", cgal_poisson, cgal_poisson_seconds);
}

// Ratio of the heatcvt row (the first) and of the two-step rows against the best two-step pipeline.
void set_ratios(std::vector<Row>& cell) {
  double best = std::numeric_limits<double>::infinity();
  for (const Row& r : cell)
    if (r.method.find("+ CGAL remesh") != std::string::npos && r.F > 0) best = std::min(best, r.mean_dist);
  Row& h = cell.front();
  if (std::isfinite(best) && best > 0) h.ratio = h.mean_dist / best;
  for (Row& r : cell)
    if (r.method.find("+ CGAL remesh") != std::string::npos && r.F > 0 && std::isfinite(best) && best > 0)
      r.ratio = r.mean_dist / best;
}

// The acceptance verdict of a heatcvt row: closed oriented manifold of the source genus, no
// self-intersections, the angle targets, and the distance ratio when there is one.
void judge(Row& h, int genus) {
  h.accepted = h.closed && h.manifold && !h.self_intersecting && h.genus == genus && h.phi_m >= 52.0 &&
               h.phi_min >= 25.0 && (h.ratio < 0 || h.ratio <= (h.noisy ? 1.5 : 1.2));
}

// Prints on stderr heatcvt's stage times and mesher counts for one cloud, with its verdict.
void print_heat_details(const ReconstructionResult& heat, const Row& h) {
  double iteration_sum = 0;
  for (double s : heat.iteration_seconds) iteration_sum += s;
  std::fprintf(stderr, "   heatcvt: laplacian %.2fs factor %.2fs cvt %.2fs (%d it, %.2fs in them) total %.2fs; holes %d "
               "rejected %d removed %d unused %d fallback %d angle-undone %d; ratio %.3f %s\n",
               heat.laplacian_seconds, heat.factor_seconds, heat.cvt_seconds, heat.iterations, iteration_sum,
               heat.total_seconds,
               heat.holes_filled, heat.rejected_triangles, heat.removed_triangles, heat.unused_sites,
               heat.polish_fallback ? 1 : 0, heat.angle_polish_undone ? 1 : 0, h.ratio, h.accepted ? "ACCEPTED" : "NOT accepted");
  std::fprintf(stderr, "   heatcvt tips: %d moves kept, CVT points farther than half a spacing %d before, %d after\n",
               heat.coverage.moves, heat.coverage.uncovered_before, heat.coverage.uncovered_after);
}

// A source mesh of the benchmark with its bounding-box diagonal and genus.
struct Shape {
  std::string name;
  TriangleMesh mesh;
  double diag = 0;
  int genus = -1;
};

// Reads meshes/<name> from the shared data.
Shape load_shape(const std::string& name) {
  Shape shape{name, read_mesh(std::string(HEATCVT_DATA_DIR) + "/meshes/" + name)};
  const TriangleMesh& src = shape.mesh;
  shape.diag = (src.V.colwise().maxCoeff() - src.V.colwise().minCoeff()).norm();
  shape.genus = mesh_genus(src.F, static_cast<int>(src.V.rows()));
  return shape;
}

// Samples one cloud from the shape and runs every method on it; returns its rows, heatcvt's first.
std::vector<Row> bench_cloud(const Shape& shape, double noise, int points, int sites,
                             const ReconstructionOptions& options, const BenchOptions& o) {
  const TriangleMesh& src = shape.mesh;
  const int genus = shape.genus;
  const Eigen::MatrixX3d P = sample_surface(src.V, src.F, points, 11, noise * shape.diag);
  char label[128];
  std::snprintf(label, sizeof label, "%s (g%d) %s", shape.name.c_str(), genus, noise > 0 ? "noisy" : "clean");
  std::fprintf(stderr, "== %s\n", label);
  Cell cell{label, noise > 0, genus, src, shape.diag, {}};
  ReconstructionResult heat;
  cell.run("heatcvt (-n " + std::to_string(sites) + ")", [&]() {
    heat = reconstruct_surface(P, options);
    return heat.mesh;
  });
  cell.rows.back().heat = true;
  if (!o.save_dir.empty()) {
    const std::string stem = o.save_dir + "/" + shape.name + (noise > 0 ? "_noisy" : "_clean");
    write_points_xyz(stem + ".xyz", P);
    if (heat.mesh.F.rows() > 0) write_mesh(stem + ".ply", heat.mesh.V, heat.mesh.F);
  }
  if (!o.only_heat) {
    run_peers(cell, P, o.threads, sites);
    set_ratios(cell.rows);
  }
  Row& h = cell.rows.front();
  judge(h, genus);
  print_heat_details(heat, h);
  return cell.rows;
}

// Prints the markdown table of every row on stdout, after a paragraph saying what the columns are.
void print_table(const std::vector<Row>& rows, int points, int sites) {
  std::printf("\n%d points per cloud (area-uniform, seed 11, no normals given), noise = Gaussian sigma 0.25%% of the "
              "bbox diagonal; heatcvt -n %d; distances / bbox diagonal (20000 samples per side). \"time\" is the "
              "method alone; \"pipeline\" is end to end from the bare points: + PCA/MST normals for the other "
              "methods, + the Poisson run for the remeshing rows. \"ratio\" = mean distance / the best two-step "
              "(Poisson + remesh) mean distance of the same cloud. Self-intersections checked only for heatcvt and "
              "the two-step rows. \"ok\" = the acceptance targets (closed, oriented manifold, source genus, no "
              "self-intersections, phi_m >= 52, phi_min >= 25, ratio <= 1.2 clean / 1.5 noisy).\n\n",
              points, sites);
  std::printf("| cloud | method | time s | pipeline s | V | F | manifold | closed | genus | phi_min | phi_m | mean dist | "
              "Hausdorff | ratio | ok | note |\n");
  std::printf("|---|---|---:|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---|---|\n");
  for (const Row& r : rows) {
    char ratio[32] = "";
    if (r.ratio >= 0) std::snprintf(ratio, sizeof ratio, "%.2f", r.ratio);
    std::printf("| %s | %s | %.2f | %.2f | %ld | %ld | %s | %s | %d | %.1f | %.1f | %.5f | %.5f | %s | %s | %s |\n",
                r.shape.c_str(), r.method.c_str(), r.seconds, r.pipeline_seconds, r.V, r.F, r.manifold ? "yes" : "no",
                r.closed ? "yes" : "no", r.genus, r.phi_min, r.phi_m, r.mean_dist, r.hausdorff, ratio,
                r.heat ? (r.accepted ? "**yes**" : "no") : "", r.note.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions o;
  if (!parse_arguments(argc, argv, o)) return 2;
  if (!o.save_dir.empty() && !std::filesystem::is_directory(o.save_dir)) {
    std::fprintf(stderr, "bench_reconstruct: error: --save-dir %s: not a directory\n", o.save_dir.c_str());
    return 2;
  }
  const int points = o.pos.size() > 0 ? std::atoi(o.pos[0].c_str()) : 50000;
  const int sites = o.pos.size() > 1 ? std::atoi(o.pos[1].c_str()) : 3000;
  const std::vector<std::string> shapes = shape_list(o);
  const ReconstructionOptions options = heat_options(o, sites);
  print_cvt_configuration(options);
  std::vector<double> noises;
  if (o.clean) noises.push_back(0.0);
  if (o.noisy) noises.push_back(0.0025);
  std::vector<Row> rows;
  for (const std::string& name : shapes) {
    const Shape shape = load_shape(name);
    for (double noise : noises)
      for (const Row& r : bench_cloud(shape, noise, points, sites, options, o)) rows.push_back(r);
  }
  print_table(rows, points, sites);
  return 0;
}
