// How closely cloud2mesh's border follows the edge of an open scan, on open surfaces sampled in
// code: a square, a disc, a square with a round hole, a saddle and an open hemisphere, uniformly
// sampled (20,000 points, seed 1, noise-free) and reconstructed with the defaults at several -n.
// Beside each row: the border fit (border_fit() against the cloud's border points, in site
// spacings = the output's mean edge length): the fraction of the scan's edge points within one
// spacing of the mesh and their 90th percentile distance; the fraction of the mesh's border
// vertices within one spacing of the scan's edge and their 90th percentile distance.
//
// Usage: bench_open_borders [--counts 100,300,1000,3000] [--points 20000] [--threads T]
//                           [--relaxation-iterations R] [--shape NAME]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "open_shapes.h"
#include "heatcvt/mesh.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/validate.h"

using namespace heatcvt;

int main(int argc, char** argv) {
  std::vector<int> counts = {100, 300, 1000, 3000};
  int points = 20000, threads = 0, relaxation = ReconstructionOptions{}.relaxation_iterations;
  std::string only;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--counts" && a + 1 < argc) {
      counts.clear();
      std::stringstream list(argv[++a]);
      for (std::string c; std::getline(list, c, ',');) counts.push_back(std::atoi(c.c_str()));
    } else if (s == "--points" && a + 1 < argc) points = std::atoi(argv[++a]);
    else if (s == "--threads" && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (s == "--relaxation-iterations" && a + 1 < argc) relaxation = std::atoi(argv[++a]);
    else if (s == "--shape" && a + 1 < argc) only = argv[++a];
    else {
      std::fprintf(stderr, "usage: bench_open_borders [--counts 100,300,1000,3000] [--points 20000] [--threads T] "
                           "[--relaxation-iterations R] [--shape NAME]\n");
      return 2;
    }
  }
  std::printf("cloud2mesh defaults on open shapes sampled in code (%d points, seed 1). edge covered = scan-edge "
              "points within one site spacing of the mesh; mesh border on edge = mesh border vertices within one "
              "spacing of the scan's edge; p90 in site spacings (output mean edge length).\n\n",
              points);
  std::printf("| shape | -n | V | loops | phi_min | phi_b | phi_m | edge covered | edge p90 | mesh border on edge | "
              "border p90 | time s |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& shape : test::open_shape_names()) {
    if (!only.empty() && only != shape) continue;
    const Eigen::MatrixX3d P = test::open_shape_samples(shape, points, 1);
    const Eigen::MatrixXi knn = k_nearest_neighbors(P, 30, threads);
    const std::vector<char> on_border = sample_border_points(P, estimate_normals(P, knn, threads), knn);
    for (int n : counts) {
      ReconstructionOptions o;
      o.sites = n;
      o.threads = threads;
      o.relaxation_iterations = relaxation;
      const double t0 = bench::now_seconds();
      try {
        const ReconstructionResult r = reconstruct_surface(P, o);
        const double seconds = bench::now_seconds() - t0;
        ValidationOptions vo;
        vo.require_closed = false;
        const ValidationReport v = validate_triangle_mesh(r.mesh.V, r.mesh.F, vo);
        const TriangleQuality q = triangle_quality(r.mesh.V, r.mesh.F);
        const BorderFit fit = border_fit(P, on_border, r.mesh, mean_edge_length(r.mesh.V, r.mesh.F));
        std::printf("| %s | %d | %d | %d | %.1f | %.1f | %.1f | %.3f | %.2f | %.3f | %.2f | %.2f |\n", shape.c_str(), n,
                    v.vertices, v.boundary_loops, q.min_angle_deg, q.boundary_min_angle_deg, q.mean_min_angle_deg,
                    fit.edge_covered, fit.edge_distance, fit.mesh_border_on_edge, fit.mesh_border_distance, seconds);
      } catch (const std::exception& e) {
        std::printf("| %s | %d | failed: %s ||||||||||\n", shape.c_str(), n, e.what());
      }
      std::fflush(stdout);
    }
  }
  return 0;
}
