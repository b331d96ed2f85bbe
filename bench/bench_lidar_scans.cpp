// Rotating-lidar frames (tests/support/virtual_scanner.h: lidar_scan(), lidar_scene()) of three
// scenes built in code, reconstructed at -n 500 and 2,000: vertices against -n, pieces, boundary
// loops, angles, the share of the returns within one mean edge length of the mesh, and time. The
// returns lie in rings (a floor) and rows (walls), dense along them and up to several site
// spacings apart across. Rows: heatcvt as cloud2mesh runs it; heatcvt with the neighbourhoods
// fixed at -k 30 (`--spread-factor 0`, neighbour_spread.h), for a comparison in the same build;
// PCL's greedy projection on the frame voxel-downsampled to about -n points, the peer.
//
// Usage: bench_lidar_scans [--sizes 500,2000] [--no-peer] [--threads T]
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "cloud_rows.h"
#include "heatcvt/reconstruct.h"
#include "virtual_scanner.h"

namespace {

using namespace heatcvt;

struct Sensor {
  const char* name;
  test::LidarOptions options;
};

std::vector<Sensor> sensors() {
  std::vector<Sensor> s(3);
  s[0].name = "16 beams ±15°";
  s[0].options.beams = 16, s[0].options.min_elevation_deg = -15, s[0].options.max_elevation_deg = 15;
  s[0].options.azimuth_step_deg = 0.2;
  s[1].name = "32 beams −30°…+10°";
  s[1].options.beams = 32, s[1].options.min_elevation_deg = -30, s[1].options.max_elevation_deg = 10;
  s[1].options.azimuth_step_deg = 0.16;
  s[2].name = "64 beams ±22.5°";
  s[2].options.beams = 64, s[2].options.min_elevation_deg = -22.5, s[2].options.max_elevation_deg = 22.5;
  s[2].options.azimuth_step_deg = 0.35;
  return s;
}

void print_row(const char* method, const bench::Row& r, int n, const std::string& note) {
  std::printf("| %s | %d (%+.1f %%) | %d | %d | %.1f | %.1f | %.3f | %.2f | %s |\n", method, r.vertices,
              100.0 * (r.vertices - n) / n, r.components, r.loops, r.phi_min, r.phi_mean, r.covered, r.seconds,
              note.c_str());
}

void run_heatcvt(const char* method, const Eigen::MatrixX3d& P, ReconstructionOptions o) {
  const std::vector<char> no_border(static_cast<size_t>(P.rows()), 0);
  const double t0 = bench::now_seconds();
  try {
    const ReconstructionResult r = reconstruct_surface(P, o);
    const bench::Row row = bench::describe(r.mesh, bench::now_seconds() - t0, P, no_border);
    print_row(method, row, o.sites, "k " + std::to_string(r.neighbors_cvt) + " / " + std::to_string(r.neighbors_fit));
  } catch (const std::exception& e) {
    std::printf("| %s | failed: %s ||||||||\n", method, e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes{500, 2000};
  bool peer = true;
  int threads = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--no-peer") peer = false;
    else if (s == "--threads" && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (s == "--sizes" && a + 1 < argc) {
      sizes.clear();
      std::stringstream list(argv[++a]);
      for (std::string item; std::getline(list, item, ',');) sizes.push_back(std::atoi(item.c_str()));
    } else {
      std::fprintf(stderr, "usage: bench_lidar_scans [--sizes 500,2000] [--no-peer] [--threads T]\n");
      return 2;
    }
  }
  for (int n : sizes)
    if (n < 1) {
      std::fprintf(stderr, "bench_lidar_scans: every size must be >= 1\n");
      return 2;
    }
  std::printf("One turn of a rotating lidar 1.8 m above the floor (range noise 1 cm, returns up to 40 m); covered = "
              "share of the returns within one mean edge length of the mesh; k = neighbourhood sizes used on the CVT "
              "points / in the surface fit. Peer: PCL GreedyProjectionTriangulation on the frame voxel-downsampled to "
              "about -n points (PCA/MST normals, radius 3 voxels, mu 2.5, 10-120 deg).\n\n");
  std::printf("| sensor | scene | returns | -n | method | V (vs -n) | components | loops | phi_min | phi_m | covered | time s | note |\n");
  std::printf("|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|\n");
  for (const Sensor& sensor : sensors())
    for (const char* scene : {"floor", "yard", "street"}) {
      const Eigen::MatrixX3d P = test::lidar_scan(test::lidar_scene(scene), sensor.options, 1);
      for (int n : sizes) {
        auto head = [&] { std::printf("| %s | %s | %ld | %d ", sensor.name, scene, static_cast<long>(P.rows()), n); };
        ReconstructionOptions o;
        o.sites = n;
        o.threads = threads;
        head();
        run_heatcvt("heatcvt", P, o);
        o.cloud.spread.factor = 0;
        head();
        run_heatcvt("heatcvt -k 30 fixed", P, o);
        if (peer) {
          head();
          const std::vector<char> no_border(static_cast<size_t>(P.rows()), 0);
          print_row("PCL GP3", bench::greedy_projection(P, n, no_border), n, "");
        }
        std::fflush(stdout);
      }
    }
  return 0;
}
