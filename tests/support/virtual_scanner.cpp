// The virtual depth camera of virtual_scanner.h.
#include "virtual_scanner.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

namespace heatcvt::test {

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<K::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

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
Eigen::MatrixX3d sense(const DepthImage& img, bool stereo, const ScanOptions& o, std::uint32_t seed) {
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

}  // namespace

TriangleMesh normalised(const TriangleMesh& m) {
  TriangleMesh out = m;
  const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
  out.V = ((m.V.rowwise() - 0.5 * (lo + hi)) / (hi - lo).norm()).eval();
  return out;
}

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

DepthFrame virtual_scan(const TriangleMesh& scene, const View& view, bool stereo, const ScanOptions& options,
                        std::uint32_t seed) {
  const Triangles tri = triangles(scene);
  Tree tree(tri.begin(), tri.end());
  const DepthImage img = render(tree, view, options);
  DepthFrame f;
  f.width = options.width;
  f.height = options.height;
  f.eye = img.eye;
  f.P = sense(img, stereo, options, seed);
  return f;
}

Eigen::MatrixX3d lidar_scan(const TriangleMesh& scene, const LidarOptions& o, std::uint32_t seed) {
  const Triangles tri = triangles(scene);
  Tree tree(tri.begin(), tri.end());
  const int turn = static_cast<int>(std::lround(360.0 / o.azimuth_step_deg));
  std::vector<double> range(static_cast<size_t>(o.beams) * turn, 0.0);
  const K::Point_3 eye(o.origin.x(), o.origin.y(), o.origin.z());
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < o.beams; ++b) {
    const double t = o.beams > 1 ? static_cast<double>(b) / (o.beams - 1) : 0.5;
    const double e = (o.min_elevation_deg + t * (o.max_elevation_deg - o.min_elevation_deg)) * M_PI / 180;
    for (int a = 0; a < turn; ++a) {
      const double az = a * o.azimuth_step_deg * M_PI / 180;
      const K::Ray_3 ray(eye, K::Vector_3(std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e)));
      const auto hit = tree.first_intersection(ray);
      if (!hit) continue;
      const K::Point_3* q = boost::get<K::Point_3>(&hit->first);
      if (q) range[static_cast<size_t>(b) * turn + a] = std::sqrt(CGAL::to_double(CGAL::squared_distance(eye, *q)));
    }
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, o.range_sigma);
  std::vector<Eigen::RowVector3d> rows;
  for (int b = 0; b < o.beams; ++b) {
    const double t = o.beams > 1 ? static_cast<double>(b) / (o.beams - 1) : 0.5;
    const double e = (o.min_elevation_deg + t * (o.max_elevation_deg - o.min_elevation_deg)) * M_PI / 180;
    for (int a = 0; a < turn; ++a) {
      const double r = range[static_cast<size_t>(b) * turn + a];
      if (!(r > 0) || r > o.max_range) continue;
      const double az = a * o.azimuth_step_deg * M_PI / 180;
      const Eigen::RowVector3d d(std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e));
      rows.push_back(o.origin.transpose() + (r + noise(rng)) * d);
    }
  }
  Eigen::MatrixX3d P(static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t i = 0; i < rows.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = rows[i];
  return P;
}

namespace {

// Appends the quad (a, b, c, d), counter-clockwise seen from where it faces, as two triangles.
void add_quad(std::vector<Eigen::RowVector3d>& V, std::vector<Eigen::RowVector3i>& F, const Eigen::RowVector3d& a,
              const Eigen::RowVector3d& b, const Eigen::RowVector3d& c, const Eigen::RowVector3d& d) {
  const int n = static_cast<int>(V.size());
  V.insert(V.end(), {a, b, c, d});
  F.emplace_back(n, n + 1, n + 2);
  F.emplace_back(n, n + 2, n + 3);
}

// The closed box [lo, hi] as six quads.
void add_box(std::vector<Eigen::RowVector3d>& V, std::vector<Eigen::RowVector3i>& F, const Eigen::RowVector3d& lo,
             const Eigen::RowVector3d& hi) {
  auto p = [&](int i, int j, int k) { return Eigen::RowVector3d(i ? hi.x() : lo.x(), j ? hi.y() : lo.y(), k ? hi.z() : lo.z()); };
  add_quad(V, F, p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0));
  add_quad(V, F, p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1));
  add_quad(V, F, p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1));
  add_quad(V, F, p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0));
  add_quad(V, F, p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0));
  add_quad(V, F, p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1));
}

}  // namespace

TriangleMesh lidar_scene(const std::string& name) {
  std::vector<Eigen::RowVector3d> V;
  std::vector<Eigen::RowVector3i> F;
  const double r = 40;
  add_quad(V, F, {-r, -r, 0}, {r, -r, 0}, {r, r, 0}, {-r, r, 0});
  if (name == "yard") {
    add_box(V, F, {4, -1, 0}, {6, 1, 1.5});
    const int sides = 32;  // the post: a prism of 32 sides
    for (int i = 0; i < sides; ++i) {
      const double a0 = 2 * M_PI * i / sides, a1 = 2 * M_PI * (i + 1) / sides;
      const Eigen::RowVector3d p0(-3 + 0.6 * std::cos(a0), 3 + 0.6 * std::sin(a0), 0);
      const Eigen::RowVector3d p1(-3 + 0.6 * std::cos(a1), 3 + 0.6 * std::sin(a1), 0);
      add_quad(V, F, p0, p1, p1 + Eigen::RowVector3d(0, 0, 2), p0 + Eigen::RowVector3d(0, 0, 2));
    }
  } else if (name == "street") {
    add_quad(V, F, {-30, 6, 0}, {30, 6, 0}, {30, 6, 5}, {-30, 6, 5});
    add_quad(V, F, {-30, -6, 0}, {-30, -6, 5}, {30, -6, 5}, {30, -6, 0});
  } else if (name != "floor") {
    throw std::invalid_argument("lidar_scene: no scene named " + name);
  }
  TriangleMesh m;
  m.V.resize(static_cast<Eigen::Index>(V.size()), 3);
  m.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t i = 0; i < V.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = V[i];
  for (size_t i = 0; i < F.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) = F[i];
  return m;
}

void write_organised_pcd(const std::string& path, const DepthFrame& frame) {
  const Eigen::MatrixX3d& P = frame.P;
  const Eigen::Vector3d& eye = frame.eye;
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f, "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
               "COUNT 1 1 1\nWIDTH %d\nHEIGHT %d\nVIEWPOINT %.9g %.9g %.9g 1 0 0 0\nPOINTS %ld\nDATA ascii\n",
               frame.width, frame.height, eye.x(), eye.y(), eye.z(), static_cast<long>(P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (P.row(i).allFinite()) std::fprintf(f, "%.9g %.9g %.9g\n", P(i, 0), P(i, 1), P(i, 2));
    else std::fprintf(f, "nan nan nan\n");
  std::fclose(f);
}


}  // namespace heatcvt::test
