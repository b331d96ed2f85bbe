// Virtual range scans: partial views of every shared mesh taken by a simulated depth camera, so
// that cloud2mesh meets scans of shapes it was never tuned on. Each view is a pinhole camera of
// W × H pixels looking at the mesh (scaled to a bounding-box diagonal of 1 m) from a fixed set of
// directions, with a floor under the object in the "scene" views. Each pixel's ray hits the
// scene (CGAL AABB tree) and the depth gets a sensor model:
//   rgbd:   structured-light camera: depth noise σ(z) = rgbd_sigma · z², depth quantised to
//           disparity steps Δz(z) = rgbd_step · z², and flying pixels: where neighbouring pixels
//           differ by more than a jump, half of those pixels get a depth between the two;
//   stereo: twice the noise, no quantisation, and speckle: 1 % of the pixels off by up to 3 σ more.
// Every cloud is written to --keep-dir (an organised PCD with the camera as VIEWPOINT, beside the scene as OBJ and the output as PLY) and
// reconstructed as cloud2mesh does, at -n N; the
// table gives vertices, components, boundary loops, φmin, φ of boundary triangles, φm, the
// checks (manifold, oriented, no self-intersections), the mean and largest distance from the
// output surface to the scanned scene (‰ of the diagonal) and the time.
//
// Usage: bench_virtual_scans [N = 2000] [--only a,b] [--noise rgbd|stereo|both] [--views K]
//                            [--keep-dir D] [--threads T] [--no-peer]
// Beside each row, in the same run: PCL's greedy projection triangulation of the frame's points
// voxel-downsampled to about -n (the usual PCL meshing of a scan; peer_pipelines.h).
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <stdexcept>
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

namespace {

using namespace heatcvt;
using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

/// The camera and sensor constants of the simulation (scene in metres, diagonal 1).
struct ScanOptions {
  int width = 320, height = 240;       ///< pixels
  double fov_deg = 50;                 ///< horizontal field of view
  double distance = 1.3;               ///< camera to object centre
  double rgbd_sigma = 0.0015;          ///< σ(z) = rgbd_sigma · z² (m)
  double rgbd_step = 0.0025;           ///< quantisation step Δz(z) = rgbd_step · z² (m)
  double flying_jump = 0.05;           ///< neighbour depth jump (m) that makes flying pixels
  double flying_share = 0.5;           ///< share of the pixels at a jump that fly
  double stereo_sigma_factor = 2.0;    ///< stereo σ over the rgbd σ
  double speckle_share = 0.01;         ///< stereo pixels off by up to 3 σ more
  std::uint32_t seed = 1;
};

struct View {
  double azimuth_deg, elevation_deg;
  bool floor;
};

/// The mesh (scaled to diagonal 1, centred at the origin) with a floor quad under it
/// (z = min z, 1.6 diagonals wide) when `floor` is set.
TriangleMesh scene_mesh(const TriangleMesh& m, bool floor) {
  if (!floor) return m;
  TriangleMesh s;
  const Eigen::Index nv = m.V.rows(), nf = m.F.rows();
  s.V.resize(nv + 4, 3);
  s.F.resize(nf + 2, 3);
  s.V.topRows(nv) = m.V;
  s.F.topRows(nf) = m.F;
  const double z = m.V.col(2).minCoeff(), r = 0.8;
  s.V.bottomRows(4) << -r, -r, z, r, -r, z, r, r, z, -r, r, z;
  s.F.bottomRows(2) << nv, nv + 1, nv + 2, nv, nv + 2, nv + 3;
  return s;
}

Triangles triangles(const TriangleMesh& m) {
  Triangles t;
  auto p = [&](int v) { return K::Point_3(m.V(v, 0), m.V(v, 1), m.V(v, 2)); };
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) t.emplace_back(p(m.F(f, 0)), p(m.F(f, 1)), p(m.F(f, 2)));
  return t;
}

/// Depth image of the scene from one view: for every pixel the hit point's depth along the
/// optical axis (0 where the ray misses), and the camera frame.
struct DepthImage {
  std::vector<double> z;
  Eigen::Vector3d eye, forward, right, up;
  double focal = 0;
};

DepthImage render(const Tree& tree, const View& view, const ScanOptions& o) {
  DepthImage img;
  const double az = view.azimuth_deg * M_PI / 180, el = view.elevation_deg * M_PI / 180;
  const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  img.eye = o.distance * dir;
  img.forward = -dir;
  img.right = img.forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  img.up = img.right.cross(img.forward);
  img.focal = 0.5 * o.width / std::tan(0.5 * o.fov_deg * M_PI / 180);
  img.z.assign(static_cast<size_t>(o.width) * o.height, 0.0);
  const K::Point_3 eye(img.eye.x(), img.eye.y(), img.eye.z());
#pragma omp parallel for schedule(dynamic, 8)
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const Eigen::Vector3d d = (img.forward * img.focal + img.right * (x + 0.5 - 0.5 * o.width) -
                                 img.up * (y + 0.5 - 0.5 * o.height)).normalized();
      const K::Ray_3 ray(eye, K::Vector_3(d.x(), d.y(), d.z()));
      const auto hit = tree.first_intersection(ray);
      if (!hit) continue;
      const K::Point_3* q = boost::get<K::Point_3>(&hit->first);
      if (!q) continue;
      const Eigen::Vector3d h(q->x(), q->y(), q->z());
      img.z[static_cast<size_t>(y) * o.width + x] = (h - img.eye).dot(img.forward);
    }
  return img;
}

/// The sensor model on the depth image, then back-projection to points.
Eigen::MatrixX3d sense(DepthImage img, bool stereo, const ScanOptions& o, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int W = o.width, H = o.height;
  std::vector<double> z = img.z;
  if (!stereo)  // flying pixels between a pixel and a neighbour across a depth jump
    for (int y = 0; y < H; ++y)
      for (int x = 0; x + 1 < W; ++x) {
        const double a = img.z[y * W + x], b = img.z[y * W + x + 1];
        if (a > 0 && b > 0 && std::abs(a - b) > o.flying_jump && unit(rng) < o.flying_share)
          z[y * W + x] = a + unit(rng) * (b - a);
      }
  // Row-major W × H grid as a sensor writes it: NaN where the ray found nothing.
  Eigen::MatrixX3d P = Eigen::MatrixX3d::Constant(static_cast<Eigen::Index>(W) * H, 3, std::nan(""));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double d = z[y * W + x];
      if (d <= 0) continue;
      const double sigma = (stereo ? o.stereo_sigma_factor : 1.0) * o.rgbd_sigma * d * d;
      d += sigma * gauss(rng);
      if (stereo && unit(rng) < o.speckle_share) d += 3 * sigma * (2 * unit(rng) - 1);
      if (!stereo) {
        const double step = o.rgbd_step * d * d;
        d = step * std::round(d / step);
      }
      const Eigen::Vector3d ray =
          img.forward + (img.right * (x + 0.5 - 0.5 * W) - img.up * (y + 0.5 - 0.5 * H)) / img.focal;
      P.row(static_cast<Eigen::Index>(y) * W + x) = img.eye + d * ray;
    }
  return P;
}

/// Writes the grid as an organised ASCII PCD (WIDTH × HEIGHT, "nan" where there is no return)
/// with the camera position as its VIEWPOINT, as RGB-D drivers save their frames.
void write_organised_pcd(const std::string& path, const Eigen::MatrixX3d& P, int width, int height,
                         const Eigen::Vector3d& eye) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f, "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
               "COUNT 1 1 1\nWIDTH %d\nHEIGHT %d\nVIEWPOINT %.9g %.9g %.9g 1 0 0 0\nPOINTS %ld\nDATA ascii\n",
               width, height, eye.x(), eye.y(), eye.z(), static_cast<long>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (P.row(i).allFinite()) std::fprintf(f, "%.9g %.9g %.9g\n", P(i, 0), P(i, 1), P(i, 2));
    else std::fprintf(f, "nan nan nan\n");
  std::fclose(f);
}

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

/// One table row: vertices against -n, pieces, loops, angles, failed checks (manifold,
/// orientation, self-intersections; an open mesh is expected), distances to the scene, time.
void print_row(const std::string& row, const char* method, const TriangleMesh& out, const ClosestPointTree& truth,
               const TriangleMesh& scene, int n, double seconds) {
  if (out.F.rows() == 0) {
    std::printf("%s| %s | no faces |||||||||\n", row.c_str(), method);
    return;
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
    const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
    m.V = ((m.V.rowwise() - 0.5 * (lo + hi)) / (hi - lo).norm()).eval();
    for (int v = 0; v < std::min<int>(views, static_cast<int>(all_views.size())); ++v) {
      const View& view = all_views[v];
      const TriangleMesh scene = scene_mesh(m, view.floor);
      const ClosestPointTree truth(scene.V, scene.F);
      const Triangles tri = triangles(scene);
      Tree tree(tri.begin(), tri.end());
      tree.accelerate_distance_queries();
      const DepthImage img = render(tree, view, so);
      for (const bool stereo : {false, true}) {
        if ((stereo && noise == "rgbd") || (!stereo && noise == "stereo")) continue;
        const Eigen::MatrixX3d grid = sense(img, stereo, so, so.seed + 17 * v + (stereo ? 1 : 0));
        long finite = 0;
        for (Eigen::Index i = 0; i < grid.rows(); ++i) finite += grid.row(i).allFinite();
        const std::string label = std::string(stereo ? "stereo" : "rgbd");
        const std::filesystem::path path =
            std::filesystem::path(keep_dir) / (name + "_v" + std::to_string(v) + "_" + label + ".pcd");
        write_organised_pcd(path.string(), grid, so.width, so.height, img.eye);
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
          print_row(row, "heatcvt", r.result.mesh, truth, scene, n, seconds);
        } catch (const std::exception& e) {
          std::printf("%s| heatcvt | failed: %s |||||||||\n", row.c_str(), e.what());
        }
        if (peer) {  // the peer reads the same frame: its finite points, flying pixels included
          Eigen::MatrixX3d P(finite, 3);
          for (Eigen::Index i = 0, k = 0; i < grid.rows(); ++i)
            if (grid.row(i).allFinite()) P.row(k++) = grid.row(i);
          t0 = bench::now_seconds();
          const TriangleMesh m = test::pcl_greedy_projection_at_count(P, n);
          print_row(row, "PCL GP3", m, truth, scene, n, bench::now_seconds() - t0);
        }
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
