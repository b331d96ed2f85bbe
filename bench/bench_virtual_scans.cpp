// Virtual range scans: partial views of every shared mesh taken by the simulated depth camera of
// tests/support/virtual_scanner.h (rgbd: noise, quantisation and flying pixels; stereo: noise and
// speckle; a floor under the object in the scene views), so that cloud2mesh meets scans of shapes
// it was never tuned on. Every frame is written to --keep-dir (an organised PCD with the camera as
// VIEWPOINT, beside the scene as OBJ and the output as PLY) and reconstructed as cloud2mesh does,
// at -n N. The table gives vertices, components, boundary loops, φmin, φ of boundary triangles,
// φm, the failed checks (manifold, oriented, no self-intersections; an open mesh is expected),
// the mean and largest distance from the output surface to the scanned scene (‰ of the
// diagonal) and the time.
//
// Usage: bench_virtual_scans [N = 2000] [--only a,b] [--noise rgbd|stereo|both] [--views K]
//                            [--keep-dir D] [--threads T] [--no-peer]
// Beside each row, in the same run: PCL's greedy projection triangulation of the frame's points
// voxel-downsampled to about -n (the usual PCL meshing of a scan; peer_pipelines.h).

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/validate.h"
#include "peer_pipelines.h"
#include "virtual_scanner.h"

namespace {

using namespace heatcvt;
using test::DepthFrame;
using test::ScanOptions;
using test::View;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(item);
  return out;
}

/// Mean and largest distance (‰ of the diagonal 1) from area-uniform samples of the output to the
/// scanned scene.
std::pair<double, double> distance_to_truth(const TriangleMesh& out, const ClosestPointTree& truth,
                                            const TriangleMesh& m) {
  const Eigen::MatrixX3d S = sample_surface(out.V, out.F, 20000, 3);
  double sum = 0, worst = 0;
  for (Eigen::Index i = 0; i < S.rows(); ++i) {
    const SurfacePoint sp = truth.closest(S.row(i).transpose());
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) q += sp.bary[k] * m.V.row(m.F(sp.face, k)).transpose();
    const double d = (q - S.row(i).transpose()).norm();
    sum += d;
    worst = std::max(worst, d);
  }
  return {1000 * sum / S.rows(), 1000 * worst};
}

/// The figures of one reconstructed frame, for the summary.
struct FrameFigures {
  bool valid = false, count_ok = false;
  double min_angle = 0, mean_angle = 0, mean_dist = 0, max_dist = 0, seconds = 0;
};

/// The frames of one method and one sensor model.
struct Summary {
  std::vector<FrameFigures> frames;
  void print(const char* method, const char* noise) const {
    if (frames.empty()) return;
    auto count = [&](auto pred) { return std::count_if(frames.begin(), frames.end(), pred); };
    auto values = [&](double FrameFigures::*field) {
      std::vector<double> v;
      for (const FrameFigures& f : frames) v.push_back(f.*field);
      std::sort(v.begin(), v.end());
      return v;
    };
    const auto lo_hi = [&](double FrameFigures::*field) {
      const std::vector<double> v = values(field);
      return std::make_pair(v.front(), v.back());
    };
    const auto median = [&](double FrameFigures::*field) { return values(field)[frames.size() / 2]; };
    const auto [phi_lo, phi_hi] = lo_hi(&FrameFigures::min_angle);
    const auto [phim_lo, phim_hi] = lo_hi(&FrameFigures::mean_angle);
    std::printf("| %s, %s | %zu | %ld | %ld | %ld | %ld | %.1f-%.1f | %.1f-%.1f | %.2f / %.2f | %.1f / %.1f | %.2f |\n",
                method, noise, frames.size(), count([](const FrameFigures& f) { return f.valid; }),
                count([](const FrameFigures& f) { return f.count_ok; }),
                count([](const FrameFigures& f) { return f.min_angle >= 25; }),
                count([](const FrameFigures& f) { return f.mean_angle >= 52; }), phi_lo, phi_hi, phim_lo, phim_hi,
                median(&FrameFigures::mean_dist), lo_hi(&FrameFigures::mean_dist).second,
                median(&FrameFigures::max_dist), lo_hi(&FrameFigures::max_dist).second, median(&FrameFigures::seconds));
  }
};

/// One table row: vertices against -n, pieces, loops, angles, failed checks (manifold,
/// orientation, self-intersections; an open mesh is expected), distances to the scene, time.
FrameFigures print_row(const std::string& row, const char* method, const TriangleMesh& out, const ClosestPointTree& truth,
                       const TriangleMesh& scene, int n, double seconds) {
  if (out.F.rows() == 0) {
    std::printf("%s| %s | no faces |||||||||\n", row.c_str(), method);
    return {};
  }
  ValidationOptions vo;
  vo.require_closed = false;
  const ValidationReport rep = validate_triangle_mesh(out.V, out.F, vo);
  const TriangleQuality q = triangle_quality(out.V, out.F);
  std::string checks;
  for (const MeshCheck& c : rep.checks)
    if (!c.passed && c.name != "closed") checks += (checks.empty() ? "" : ",") + c.name;
  const auto [mean, worst] = distance_to_truth(out, truth, scene);
  std::printf("%s| %s | %d (%+.1f %%) | %d | %d | %.1f | %.1f | %.1f | %s | %.2f | %.1f | %.2f |\n", row.c_str(), method,
              rep.vertices, 100.0 * (rep.vertices - n) / n, rep.components, rep.boundary_loops, q.min_angle_deg,
              q.boundary_min_angle_deg, q.mean_min_angle_deg, checks.empty() ? "ok" : checks.c_str(), mean, worst,
              seconds);
  return {checks.empty(), std::abs(rep.vertices - n) <= 0.02 * n, q.min_angle_deg, q.mean_min_angle_deg, mean, worst,
          seconds};
}

}  // namespace

int main(int argc, char** argv) {
  int n = 2000, threads = 0, views = 4;
  std::string noise = "both", keep_dir = "/tmp/virtual_scans";
  bool peer = true;
  std::vector<std::string> only;
  for (int a = 1; a < argc; ++a) {
    const std::string s = argv[a];
    if (s == "--only" && a + 1 < argc) only = split(argv[++a]);
    else if (s == "--noise" && a + 1 < argc) noise = argv[++a];
    else if (s == "--no-peer") peer = false;
    else if (s == "--views" && a + 1 < argc) views = std::atoi(argv[++a]);
    else if (s == "--keep-dir" && a + 1 < argc) keep_dir = argv[++a];
    else if (s == "--threads" && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (!s.empty() && std::isdigit(static_cast<unsigned char>(s[0]))) n = std::atoi(s.c_str());
    else {
      std::fprintf(stderr, "usage: bench_virtual_scans [N = 2000] [--only a,b] [--noise rgbd|stereo|both] "
                           "[--views K] [--keep-dir D] [--threads T] [--no-peer]\n");
      return 2;
    }
  }
  const std::filesystem::path dir = std::filesystem::path(HEATCVT_DATA_DIR) / "meshes";
  if (!std::filesystem::is_directory(dir)) {
    std::fprintf(stderr, "bench_virtual_scans: %s is missing (the shared data)\n", dir.c_str());
    return 2;
  }
  std::filesystem::create_directories(keep_dir);
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() != ".md") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  const std::vector<View> all_views = {{30, 25, true}, {150, 40, true}, {260, 10, false}, {0, 80, true},
                                       {90, -30, false}, {200, 60, false}};
  const ScanOptions so;
  Summary ours[2], peers[2];  // by sensor model: [0] rgbd, [1] stereo
  std::printf("Virtual scans at -n %d: %dx%d depth camera, mesh scaled to diagonal 1 m, camera %.1f m from its "
              "centre; rgbd sigma %.4f z^2, step %.4f z^2, flying pixels; stereo sigma x%.0f, speckle. "
              "Distances: output to the scanned mesh, permille of the diagonal.\n\n",
              n, so.width, so.height, so.distance, so.rgbd_sigma, so.rgbd_step, so.stereo_sigma_factor);
  std::printf("| mesh | view | noise | points | method | V (vs -n) | comp | loops | phi_min | phi_b | phi_m | checks | "
              "mean | max | time s |\n|---|---|---|---:|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n");
  for (const auto& f : files) {
    const std::string name = f.stem().string();
    if (!only.empty() && std::find(only.begin(), only.end(), name) == only.end()) continue;
    TriangleMesh m;
    try {
      m = read_mesh(f.string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", f.filename().c_str(), e.what());
      continue;
    }
    m = test::normalised(m);
    for (int v = 0; v < std::min<int>(views, static_cast<int>(all_views.size())); ++v) {
      const View& view = all_views[v];
      const TriangleMesh scene = test::scene_mesh(m, view.floor);
      const ClosestPointTree truth(scene.V, scene.F);
      for (const bool stereo : {false, true}) {
        if ((stereo && noise == "rgbd") || (!stereo && noise == "stereo")) continue;
        // Seeds 1, 2 for the first view's two frames, then 17 apart per view.
        const DepthFrame frame = test::virtual_scan(scene, view, stereo, so, 1 + 17 * v + (stereo ? 1 : 0));
        const Eigen::MatrixX3d& grid = frame.P;
        long finite = 0;
        for (Eigen::Index i = 0; i < grid.rows(); ++i) finite += grid.row(i).allFinite();
        const std::string label = std::string(stereo ? "stereo" : "rgbd");
        const std::filesystem::path path =
            std::filesystem::path(keep_dir) / (name + "_v" + std::to_string(v) + "_" + label + ".pcd");
        test::write_organised_pcd(path.string(), frame);
        write_mesh((std::filesystem::path(keep_dir) / (name + "_v" + std::to_string(v) + "_scene.obj")).string(),
                   scene.V, scene.F);
        const std::string row = "| " + name + " | " + std::to_string(v) + (view.floor ? " floor" : "") + " | " + label +
                                " | " + std::to_string(finite) + " ";
        if (finite < 10L * n) {
          std::printf("%s| heatcvt | fewer than 10 points per site |||||||||\n", row.c_str());
          continue;
        }
        ReconstructionOptions o;
        o.sites = n;
        o.threads = threads;
        double t0 = bench::now_seconds();
        try {
          const StreamedReconstruction r = reconstruct_surface_streamed(path.string(), o, StreamOptions{});
          const double seconds = bench::now_seconds() - t0;
          write_mesh(std::filesystem::path(path).replace_extension(".out.ply").string(), r.result.mesh.V,
                     r.result.mesh.F);
          ours[stereo].frames.push_back(print_row(row, "heatcvt", r.result.mesh, truth, scene, n, seconds));
        } catch (const std::exception& e) {
          std::printf("%s| heatcvt | failed: %s |||||||||\n", row.c_str(), e.what());
          ours[stereo].frames.push_back({});
        }
        if (peer) {  // the peer reads the same frame: its finite points, flying pixels included
          Eigen::MatrixX3d P(finite, 3);
          for (Eigen::Index i = 0, k = 0; i < grid.rows(); ++i)
            if (grid.row(i).allFinite()) P.row(k++) = grid.row(i);
          t0 = bench::now_seconds();
          const TriangleMesh m = test::pcl_greedy_projection_at_count(P, n);
          peers[stereo].frames.push_back(print_row(row, "PCL GP3", m, truth, scene, n, bench::now_seconds() - t0));
        }
        std::fflush(stdout);
      }
    }
  }
  std::printf("\nSummary over the frames with at least 10 points per site (a failed run counts as invalid, 0°):\n\n"
              "| method | frames | valid | count within 2 %% | phi_min >= 25 | phi_m >= 52 | phi_min | phi_m | "
              "mean distance, median / largest | largest distance, median / largest | time s, median |\n"
              "|---|---:|---:|---:|---:|---:|---|---|---|---|---:|\n");
  for (const bool stereo : {false, true}) ours[stereo].print("heatcvt", stereo ? "stereo" : "rgbd");
  for (const bool stereo : {false, true}) peers[stereo].print("PCL GP3", stereo ? "stereo" : "rgbd");
  return 0;
}
