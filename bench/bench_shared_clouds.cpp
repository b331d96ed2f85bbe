// Reconstruction of every real cloud of ../shared/data/clouds with at least 10 points per requested
// vertex: vertices (against -n), components, boundary loops, genus, smallest angle overall and
// of the triangles on a boundary, mean smallest angle, time. Beside each row, in the same run,
// PCL's greedy projection triangulation (the usual PCL mesher of open scans) on the cloud voxel-
// downsampled to about the same number of vertices.
//
// Usage: bench_shared_clouds [N = 2000] [--no-peer] [--no-border-follow] [--threads T] [--mean-tolerance T]
//                            [--stream-per-site P] [--min-points-per-site M]
// --min-points-per-site M: the clouds with at least M points per requested vertex (default 10, the
// acceptance's; lower reaches the clouds sparser than -n asks for).
// --stream-per-site P: StreamOptions::max_raw_points_per_site = P (a cloud with more than P points
// per site is reconstructed from its voxel summary), for a comparison in the same build.
// --no-border-follow: border vertices move like interior ones in the relaxations (PolishOptions and
// IsotropicRemeshOptions::follow_sample_border off), for a comparison in the same build.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_util.h"
#include "cloud_rows.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/mesh.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/validate.h"
#include "peer_pipelines.h"

namespace {

using namespace heatcvt;
using bench::Row;
using bench::describe;
using bench::greedy_projection;
using bench::print;

}  // namespace

int main(int argc, char** argv) {
  int n = 2000, threads = 0;
  double min_per_site = 10;
  bool peer = true, follow = true;
  ReconstructionOptions defaults;
  double mean_tolerance = defaults.lloyd_mean_tolerance;
  StreamOptions stream;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--no-peer") peer = false;
    else if (s == "--no-border-follow") follow = false;
    else if (s == "--threads" && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (s == "--mean-tolerance" && a + 1 < argc) mean_tolerance = std::atof(argv[++a]);
    else if (s == "--stream-per-site" && a + 1 < argc) stream.max_raw_points_per_site = std::atof(argv[++a]);
    else if (s == "--min-points-per-site" && a + 1 < argc) min_per_site = std::atof(argv[++a]);
    else if (!s.empty() && std::isdigit(static_cast<unsigned char>(s[0]))) n = std::atoi(s.c_str());
    else {
      std::fprintf(stderr,
                   "usage: bench_shared_clouds [N = 2000] [--no-peer] [--no-border-follow] [--threads T] [--mean-tolerance T] "
                   "[--stream-per-site P] [--min-points-per-site M]\n");
      return 2;
    }
  }
  if (n < 1 || !(min_per_site >= 0)) {
    std::fprintf(stderr, "bench_shared_clouds: N must be >= 1 and M >= 0\n");
    return 2;
  }
  const std::filesystem::path dir = std::filesystem::path(HEATCVT_DATA_DIR) / "clouds";
  if (!std::filesystem::is_directory(dir)) {
    std::fprintf(stderr, "bench_shared_clouds: %s is missing (the shared data)\n", dir.c_str());
    return 2;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() != ".md") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::printf("cloud2mesh defaults, -n %d, every shared cloud with at least %.0f points; phi_b = smallest angle of the "
              "triangles on a boundary; on edge = fraction of the mesh's border vertices within one site spacing (its mean edge length) of the cloud's border points (sample_border.h), p90 = their 90th percentile distance in spacings; covered = fraction of the cloud's points within one spacing of the mesh; flying px = pixels of an organised frame dropped by the flying-pixel rule. Peer: PCL GreedyProjectionTriangulation on the cloud voxel-downsampled to about "
              "-n points (PCA/MST normals, radius 3 voxels, mu 2.5, 10-120 deg).\n\n",
              n, min_per_site * n);
  std::printf("| cloud | method | V (vs -n) | components | loops | genus | phi_min | phi_b | phi_m | on edge | p90 | covered | time s | flying px |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& f : files) {
    PointCloud cloud;
    try {
      cloud = read_cloud(f.string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", f.filename().c_str(), e.what());
      continue;
    }
    if (cloud.P.rows() < min_per_site * n) continue;
    const Eigen::MatrixXi knn = k_nearest_neighbors(cloud.P, 30, threads);
    const std::vector<char> on_border = sample_border_points(cloud.P, estimate_normals(cloud.P, knn, threads), knn);
    ReconstructionOptions o;
    o.sites = n;
    o.threads = threads;
    o.lloyd_mean_tolerance = mean_tolerance;
    o.mesher.polish.follow_sample_border = o.mesher.sizing.follow_sample_border = follow;
    const double t0 = bench::now_seconds();
    std::printf("| %s ", f.filename().c_str());
    try {
      // As cloud2mesh runs it: a file of more than StreamOptions::max_raw_points points is
      // streamed into a voxel summary, a smaller one reconstructed from its raw points.
      const StreamedReconstruction r = reconstruct_surface_streamed(f.string(), o, stream);
      Row row = describe(r.result.mesh, bench::now_seconds() - t0, cloud.P, on_border);
      row.flying_pixels = static_cast<long>(r.flying_pixels_removed);
      print("heatcvt", row, n);
    } catch (const std::exception& e) {
      std::printf("| heatcvt | failed: %s |||||||||||\n", e.what());
    }
    if (peer) {
      std::printf("| %s ", f.filename().c_str());
      print("PCL GP3", greedy_projection(cloud.P, n, on_border), n);
    }
    std::fflush(stdout);
  }
  return 0;
}
