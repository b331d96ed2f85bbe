// bench_remesh: heatcvt::remesh_cvt (meshcvt's defaults) against CGAL's isotropic remeshing
// (Polygon_mesh_processing::isotropic_remeshing, 5 iterations) on every mesh of
// ../shared/data/meshes at its own resolution × a list of vertex counts, in the same run.
// Prints a markdown table: time, φmin, φm, two-sided sampled Hausdorff distance to the input
// (surface_distance, in ‰ of the input's bounding-box diagonal) and validity (manifold,
// closed or the input's boundary loop count, the input's genus, no self-intersections).
//
// CGAL's target edge length is searched so that its vertex count is within 2 % of the
// requested one: L₀ = sqrt(2A / (√3 n)) (equilateral triangles, ~2n of them for n vertices),
// then L ← L · sqrt(v / n) from the count v obtained, at most kMaxLengthSearch runs; its time is
// that of the last run (the one compared), not of the search.
//
// Usage: bench_remesh [--sizes 1000,3000,10000] [--only spot,torus] [--threads T] [--samples S]
//                     [--no-features] (heatcvt without the crease stage, as meshcvt --no-features)
//                     [--dir DIR] (the meshes of DIR instead, e.g. scripts/make_shapes.py's)
//                     [--adaptive A] (heatcvt with curvature-adaptive sizing, as meshcvt --adaptive A;
//                     CGAL stays uniform: Debian 12's CGAL 5.5 has no adaptive sizing field)
// Inputs that are not edge manifolds or not orientable are skipped with the reason printed.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/remesh.h"
#include "heatcvt/validate.h"

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using namespace heatcvt;

namespace {

constexpr int kCgalIterations = 5;     // isotropic_remeshing iterations (as bench_cvt, bench_reconstruct)
constexpr int kMaxLengthSearch = 4;    // CGAL runs to hit the vertex count
constexpr double kCountTolerance = 0.02;

struct Row {
  int vertices = 0;
  double seconds = 0;
  TriangleQuality quality;
  double hausdorff = 0;  // ‰ of the input's bounding-box diagonal
  std::string valid;     // "yes" or the failed checks
};

// CGAL isotropic remeshing of `m` with target edge length L; returns the mesh and its time.
TriangleMesh cgal_isotropic(const TriangleMesh& m, double L, double* seconds) {
  std::vector<Kernel::Point_3> points;
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) points.emplace_back(m.V(v, 0), m.V(v, 1), m.V(v, 2));
  std::vector<std::vector<std::size_t>> polygons;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    polygons.push_back({static_cast<std::size_t>(m.F(f, 0)), static_cast<std::size_t>(m.F(f, 1)),
                        static_cast<std::size_t>(m.F(f, 2))});
  CgalMesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  const double t0 = bench::now_seconds();
  PMP::isotropic_remeshing(faces(mesh), L, mesh, CGAL::parameters::number_of_iterations(kCgalIterations));
  mesh.collect_garbage();
  *seconds = bench::now_seconds() - t0;
  TriangleMesh out;
  out.V.resize(static_cast<Eigen::Index>(num_vertices(mesh)), 3);
  out.F.resize(static_cast<Eigen::Index>(num_faces(mesh)), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    out.V.row(v.idx()) << p.x(), p.y(), p.z();
  }
  for (auto face : mesh.faces()) {
    int k = 0;
    for (auto v : vertices_around_face(mesh.halfedge(face), mesh)) out.F(face.idx(), k++) = static_cast<int>(v.idx());
  }
  return out;
}

// Validity of an output against the input's topology: the failed checks, or "yes".
std::string validity(const TriangleMesh& out, const SurfaceDescription& input, int input_loops) {
  ValidationOptions vo;
  vo.require_closed = input.closed();
  vo.expected_genus = input.genus;
  const ValidationReport rep = validate_triangle_mesh(out.V, out.F, vo);
  std::string failed;
  for (const auto& c : rep.checks)
    if (!c.ran || !c.passed) failed += (failed.empty() ? "" : ", ") + c.name;
  if (rep.boundary_loops != input_loops)
    failed += (failed.empty() ? "" : ", ") + std::to_string(rep.boundary_loops) + " boundary loops";
  return failed.empty() ? "yes" : "no: " + failed;
}

Row measure(const TriangleMesh& out, double seconds, const TriangleMesh& input, const SurfaceDescription& desc,
            int input_loops, double diagonal, int samples) {
  Row r;
  r.vertices = static_cast<int>(out.V.rows());
  r.seconds = seconds;
  r.quality = triangle_quality(out.V, out.F);
  r.hausdorff = out.F.rows() ? 1000 * surface_distance(out.V, out.F, input.V, input.F, samples).hausdorff / diagonal : -1;
  r.valid = out.F.rows() ? validity(out, desc, input_loops) : "no: empty";
  return r;
}

Row run_cgal(const TriangleMesh& input, int n, const SurfaceDescription& desc, int loops, double diagonal, int samples) {
  double L = std::sqrt(2.0 * surface_area(input.V, input.F) / (std::sqrt(3.0) * n));
  TriangleMesh out;
  double seconds = 0;
  for (int run = 0; run < kMaxLengthSearch; ++run) {
    out = cgal_isotropic(input, L, &seconds);
    const double v = static_cast<double>(out.V.rows());
    if (std::abs(v - n) <= kCountTolerance * n) break;
    L *= std::sqrt(v / n);
  }
  return measure(out, seconds, input, desc, loops, diagonal, samples);
}

Row run_heatcvt(const TriangleMesh& input, int n, int threads, bool features, double adaptivity,
                const SurfaceDescription& desc, int loops, double diagonal, int samples) {
  RemeshOptions opt;
  opt.creases.enabled = features;
  opt.adaptive.adaptivity = adaptivity;
  opt.cvt.sites = n;
  opt.cvt.threads = threads;
  const double t0 = bench::now_seconds();
  try {
    const RemeshResult r = remesh_cvt(input, opt);
    Row row = measure(r.mesh, bench::now_seconds() - t0, input, desc, loops, diagonal, samples);
    if (r.input_self_intersections > 0)  // no close remesh can avoid them (remesh.h)
      row.valid += " (the input has " + std::to_string(r.input_self_intersections) + " crossing face pairs)";
    return row;
  } catch (const std::exception& e) {
    Row row;
    row.seconds = bench::now_seconds() - t0;
    row.valid = std::string("error: ") + e.what();
    return row;
  }
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

std::string cell(const Row& r) {
  char buf[160];
  if (r.vertices == 0) {
    std::snprintf(buf, sizeof buf, "– | %.2f | – | – | – | %s", r.seconds, r.valid.c_str());
  } else {
    std::snprintf(buf, sizeof buf, "%d | %.2f | %.1f | %.1f | %.2f | %s", r.vertices, r.seconds, r.quality.min_angle_deg,
                  r.quality.mean_min_angle_deg, r.hausdorff, r.valid.c_str());
  }
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes = {1000, 3000, 10000};
  std::vector<std::string> only;
  int threads = 0, samples = 20000;
  bool features = true;
  double adaptivity = 0;
  std::filesystem::path dir = std::filesystem::path(HEATCVT_DATA_DIR) / "meshes";
  for (int i = 1; i < argc; ++i) {
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_remesh: %s needs a value\n", argv[i]);
        std::exit(2);
      }
      return argv[++i];
    };
    if (!std::strcmp(argv[i], "--sizes")) {
      sizes.clear();
      for (const auto& s : split_list(next())) sizes.push_back(std::atoi(s.c_str()));
    } else if (!std::strcmp(argv[i], "--only")) {
      only = split_list(next());
    } else if (!std::strcmp(argv[i], "--threads")) {
      threads = std::atoi(next().c_str());
    } else if (!std::strcmp(argv[i], "--no-features")) {
      features = false;
    } else if (!std::strcmp(argv[i], "--samples")) {
      samples = std::atoi(next().c_str());
    } else if (!std::strcmp(argv[i], "--dir")) {
      dir = next();
    } else if (!std::strcmp(argv[i], "--adaptive")) {
      adaptivity = std::atof(next().c_str());
      if (!(adaptivity >= 0 && adaptivity <= 2)) {
        std::fprintf(stderr, "bench_remesh: --adaptive must be in [0, 2]\n");
        return 2;
      }
    } else {
      std::fprintf(stderr, "bench_remesh: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (!std::filesystem::is_directory(dir)) {
    std::fprintf(stderr, "bench_remesh: %s: not a directory\n", dir.string().c_str());
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::printf("| mesh | #V | n | heatcvt V | time s | φmin | φm | Hausdorff ‰ | valid | CGAL V | time s | φmin | φm | "
              "Hausdorff ‰ | valid |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  for (const auto& path : files) {
    const std::string name = path.stem().string();
    if (!only.empty() && std::find(only.begin(), only.end(), name) == only.end()) continue;
    TriangleMesh input;
    try {
      input = read_mesh(path.string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "skip %s: %s\n", name.c_str(), e.what());
      continue;
    }
    const SurfaceDescription desc = describe_surface(input);
    if (desc.topology.nonmanifold_edges > 0) {
      std::printf("| %s | %d | skipped: %d non-manifold edges |\n", name.c_str(), static_cast<int>(input.V.rows()),
                  desc.topology.nonmanifold_edges);
      continue;
    }
    if (desc.non_orientable || desc.genus < 0) {
      std::printf("| %s | %d | skipped: %s |\n", name.c_str(), static_cast<int>(input.V.rows()),
                  desc.non_orientable ? "not orientable" : "not an oriented manifold (non-manifold vertices)");
      continue;
    }
    ValidationOptions io;
    io.check_self_intersections = false;
    io.require_closed = false;
    const int loops = validate_triangle_mesh(input.V, input.F, io).boundary_loops;
    const double diagonal = (input.V.colwise().maxCoeff() - input.V.colwise().minCoeff()).norm();
    for (int n : sizes) {
      const Row h = run_heatcvt(input, n, threads, features, adaptivity, desc, loops, diagonal, samples);
      const Row c = run_cgal(input, n, desc, loops, diagonal, samples);
      std::printf("| %s | %d | %d | %s | %s |\n", name.c_str(), static_cast<int>(input.V.rows()), n, cell(h).c_str(),
                  cell(c).c_str());
      std::fflush(stdout);
    }
  }
  return 0;
}
