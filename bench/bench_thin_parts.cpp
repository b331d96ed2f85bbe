// Two faces closer than a site spacing (tests/support/thin_scenes.h): closed plates 1–10 cm thick,
// a wall 3 cm thick on a floor, two scans of a plane 1–4 cm apart across their overlap; 40,000–
// 80,000 points with 0.5 mm noise, reconstructed at -n 1,000 to 4,000. Rows: heatcvt as cloud2mesh
// runs it; heatcvt without the offset rule for the faces of a thin part (`--across-offset 0`,
// CloudPreparationOptions::across_min_offset), for a comparison in the same build; PCL's greedy
// projection on the cloud voxel-downsampled to about -n points, the peer.
//
// Usage: bench_thin_parts [--no-peer] [--threads T]
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "bench_util.h"
#include "cloud_rows.h"
#include "heatcvt/reconstruct.h"
#include "thin_scenes.h"

namespace {

using namespace heatcvt;

struct Scene {
  std::string name;
  Eigen::MatrixX3d P;
  std::vector<int> sizes;
};

void print_row(const std::string& scene, long points, int n, const char* method, const bench::Row& r) {
  std::printf("| %s | %ld | %d | %s | %d (%+.1f %%) | %d | %d | %d | %.1f | %.1f | %.3f | %.2f |\n", scene.c_str(), points,
              n, method, r.vertices, 100.0 * (r.vertices - n) / n, r.components, r.loops, r.genus, r.phi_min, r.phi_mean,
              r.covered, r.seconds);
}

void run_heatcvt(const Scene& s, int n, const char* method, double across, int threads) {
  ReconstructionOptions o;
  o.sites = n;
  o.threads = threads;
  o.cloud.across_min_offset = across;
  const std::vector<char> no_border(static_cast<size_t>(s.P.rows()), 0);
  const double t0 = bench::now_seconds();
  try {
    const ReconstructionResult r = reconstruct_surface(s.P, o);
    print_row(s.name, static_cast<long>(s.P.rows()), n, method,
              bench::describe(r.mesh, bench::now_seconds() - t0, s.P, no_border));
  } catch (const std::exception& e) {
    std::printf("| %s | %ld | %d | %s | failed: %s |||||||\n", s.name.c_str(), static_cast<long>(s.P.rows()), n, method,
                e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool peer = true;
  int threads = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--no-peer") peer = false;
    else if (s == "--threads" && a + 1 < argc) threads = std::atoi(argv[++a]);
    else {
      std::fprintf(stderr, "usage: bench_thin_parts [--no-peer] [--threads T]\n");
      return 2;
    }
  }
  const double sigma = 0.0005;
  std::vector<Scene> scenes;
  for (double t : {0.01, 0.03, 0.05, 0.1})
    scenes.push_back({"plate " + std::to_string(static_cast<int>(t * 100 + 0.5)) + " cm", test::thin_plate(t, 40000, sigma),
                      {1000, 2000, 4000}});
  scenes.push_back({"wall 3 cm on a floor", test::wall_on_floor(0.03, 80000, sigma), {1000, 2000, 4000}});
  for (double d : {0.01, 0.02, 0.04})
    scenes.push_back({"two scans " + std::to_string(static_cast<int>(d * 100 + 0.5)) + " cm apart",
                      test::offset_scans(d, 30000, sigma), {1000, 2000}});
  std::printf("Two faces closer than a site spacing, noise 0.5 mm; covered = share of the points within one mean "
              "edge length of the mesh. Peer: PCL GreedyProjectionTriangulation on the cloud voxel-downsampled to "
              "about -n points.\n\n");
  std::printf("| scene | points | -n | method | V (vs -n) | components | loops | genus | phi_min | phi_m | covered | time s |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  const double rule = CloudPreparationOptions{}.across_min_offset;
  for (const Scene& s : scenes)
    for (int n : s.sizes) {
      run_heatcvt(s, n, "heatcvt", rule, threads);
      run_heatcvt(s, n, "heatcvt --across-offset 0", 0.0, threads);
      if (peer) {
        const std::vector<char> no_border(static_cast<size_t>(s.P.rows()), 0);
        print_row(s.name, static_cast<long>(s.P.rows()), n, "PCL GP3", bench::greedy_projection(s.P, n, no_border));
      }
      std::fflush(stdout);
    }
  return 0;
}
