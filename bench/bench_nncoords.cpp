// bench_nncoords: skinning weights (natural-neighbour coordinates by area stealing, paper §7.2)
// for all vertices of a mesh with a few handles, propagated from exact samples, against the
// direct per-vertex computation on a random subset of vertices.
//
//   bench_nncoords [--mesh PATH] [--handles 7] [--threads 2] [--samples N[,N...]] [--check 200]
//
// Handles: farthest-point sampling on the edge graph (seed 1), i.e. the extremities.
// Prints one table row per sample count beside the paper's figure.
#include <sys/resource.h>

#include <cstdio>
#include <fstream>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/cvt.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/natural_neighbour.h"

using namespace heatcvt;

namespace {
// CPU seconds (user + system) of this process: with other jobs on the machine the wall time is
// pessimistic, CPU time / threads is what the run would take on idle cores.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
}
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a;
  in >> a;
  return a.empty() ? "?" : a;
}
}  // namespace

int main(int argc, char** argv) {
  std::string mesh_path = std::string(HEATCVT_DATA_DIR) + "/meshes/armadillo.obj";
  int handles = 7, threads = 2, check = 200;
  std::vector<int> sample_counts = {0};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_nncoords: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--mesh") mesh_path = next();
    else if (a == "--handles") handles = std::stoi(next());
    else if (a == "--threads") threads = std::stoi(next());
    else if (a == "--check") check = std::stoi(next());
    else if (a == "--samples") {
      sample_counts.clear();
      std::stringstream ss(next());
      for (std::string x; std::getline(ss, x, ',');) sample_counts.push_back(std::stoi(x));
    } else {
      std::fprintf(stderr,
                   "usage: bench_nncoords [--mesh PATH] [--handles 7] [--threads 2] [--samples N[,N...] (0 = auto)] "
                   "[--check 200]\n");
      return 2;
    }
  }
  TriangleMesh mesh;
  try {
    mesh = read_mesh(mesh_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_nncoords: error: %s\n", e.what());
    return 1;
  }
  const int nv = static_cast<int>(mesh.V.rows());
  const std::vector<SurfacePoint> sites =
      initial_sites(mesh.V, mesh.F, handles, CvtInitialization::farthest_point, 1);

  // direct reference on `check` random vertices (fixed seed)
  std::mt19937 rng(1);
  std::vector<int> probe;
  for (int i = 0; i < check; ++i) probe.push_back(std::uniform_int_distribution<int>(0, nv - 1)(rng));
  NaturalNeighbourOptions base;
  base.threads = threads;
  double t0 = bench::now_seconds();
  NaturalNeighbourCoordinates ref(mesh.V, mesh.F, sites, base);
  const double setup_s = bench::now_seconds() - t0;
  t0 = bench::now_seconds();
  const auto direct = ref.query(surface_points_at_vertices(mesh.F, nv, probe));
  const double direct_s = bench::now_seconds() - t0;
  const double direct_ms = 1e3 * direct_s / check;

  std::printf("mesh %s: %d vertices, %ld faces, %d handles, %d threads; setup (Laplacian, factor, %d diffusions, "
              "tessellation) %.3f s\n",
              mesh_path.c_str(), nv, static_cast<long>(mesh.F.rows()), handles, threads, handles, setup_s);
  std::printf("direct exact queries: %.3f ms / vertex (%d vertices) -> all %d vertices would take %.1f s\n\n", direct_ms,
              check, nv, direct_ms * nv / 1e3);
  std::printf("| mesh | vertices | handles | threads | exact vertices | total time (wall) | CPU time / threads | "
              "time / vertex (wall) | max error vs direct | mean error | rows summing to 1 | load average |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int samples : sample_counts) {
    NaturalNeighbourOptions o = base;
    o.samples = samples;
    t0 = bench::now_seconds();
    const double c0 = cpu_seconds();
    NaturalNeighbourCoordinates nn(mesh.V, mesh.F, sites, o);
    std::vector<int> exact_vertices;
    const VertexWeights W = nn.vertex_weights({}, &exact_vertices);
    const double total = bench::now_seconds() - t0;
    const double cpu = cpu_seconds() - c0;
    const std::string load = load_average();
    double max_err = 0, sum_err = 0;
    for (int i = 0; i < check; ++i) {
      Eigen::VectorXd exact = Eigen::VectorXd::Zero(handles);
      for (const auto& [s, w] : direct[i].weights) exact[s] = w;
      const Eigen::VectorXd got = Eigen::VectorXd(W.row(probe[i]).transpose());
      const double e = (got - exact).cwiseAbs().maxCoeff();
      max_err = std::max(max_err, e);
      sum_err += e;
    }
    int unit_rows = 0;
    for (int v = 0; v < nv; ++v) unit_rows += std::abs(W.row(v).sum() - 1.0) < 1e-9;
    const int used = static_cast<int>(exact_vertices.size());
    std::printf("| %s | %d | %d | %d | %d | %.2f s | %.2f s | %.3f ms | %.2e | %.2e | %d / %d | %s |\n", "armadillo", nv,
                handles, threads, used, total, cpu / threads, 1e3 * total / nv, max_err, sum_err / check, unit_rows, nv,
                load.c_str());
    std::fflush(stdout);
  }
  std::printf("| paper (Armadillo, i7 4 cores) | 55,102 | 7 | 4 | all (direct) | ~1 min | | ~1.1 ms | – | – | – | |\n");
  std::printf("| direct (this machine) | %d | %d | %d | all | %.1f s (extrapolated) | | %.3f ms | 0 | 0 | | |\n", nv,
              handles, threads, direct_ms * nv / 1e3, direct_ms);
  return 0;
}
