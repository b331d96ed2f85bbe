#include "heatcvt/point_laplacian.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;

/// One triangle of a point's local fan: corners (CCW around that point's PCA normal), the
/// cotangent of the angle at each corner measured in that point's tangent plane, 3D area.
struct LocalTriangle {
  std::array<int, 3> v;
  std::array<double, 3> cot;
  double area = 0;
};

struct LocalFan {
  std::vector<LocalTriangle> triangles;
  int degenerate = 0;
};

}  // namespace

PointLaplacian point_laplacian(const Eigen::MatrixX3d& P, const PointLaplacianOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int k = options.k;
  if (k < 3) throw InvalidInputError("point_laplacian: k = " + std::to_string(k) + " is too small (need k >= 3)");
  if (options.threads < 0)
    throw InvalidInputError("point_laplacian: threads = " + std::to_string(options.threads) + " is negative");
  if (P.rows() < static_cast<Eigen::Index>(k) + 1)
    throw InvalidInputError("point_laplacian: the cloud has " + std::to_string(P.rows()) +
                            " points, need at least k + 1 = " + std::to_string(k + 1));
  if (!(options.cot_clamp > 0) || !(options.degenerate_area_epsilon >= 0) || !(options.min_mass_fraction > 0))
    throw InvalidInputError("point_laplacian: cot_clamp and min_mass_fraction must be > 0, "
                            "degenerate_area_epsilon >= 0");
  const int n = static_cast<int>(P.rows());
  const int threads = resolve_threads(options.threads);
  // Validates finiteness too (throws InvalidInputError naming the point).
  const Eigen::MatrixXi nb = k_nearest_neighbors(P, k, threads);

  PointLaplacian out;
  out.normals.resize(n, 3);
  std::vector<LocalFan> fans(n);

#pragma omp parallel num_threads(threads)
  {
    Delaunay dt;
    std::vector<Eigen::Vector2d> q(k + 1);
    std::vector<int> ids(k + 1);
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < n; ++i) {
      // PCA frame of the point and its neighbours.
      ids[0] = i;
      for (int c = 0; c < k; ++c) ids[c + 1] = nb(i, c);
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int id : ids) mean += P.row(id).transpose();
      mean /= (k + 1);
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      double mean_sq = 0;
      for (int id : ids) {
        const Eigen::Vector3d d = P.row(id).transpose() - mean;
        C += d * d.transpose();
        mean_sq += (P.row(id) - P.row(i)).squaredNorm();
      }
      mean_sq /= k;
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
      Eigen::Vector3d nrm = es.eigenvectors().col(0);
      Eigen::Vector3d e1 = es.eigenvectors().col(2);
      if (!nrm.allFinite() || !e1.allFinite()) {
        nrm = Eigen::Vector3d::UnitZ();
        e1 = Eigen::Vector3d::UnitX();
      }
      nrm.normalize();
      e1 = (e1 - e1.dot(nrm) * nrm).normalized();
      const Eigen::Vector3d e2 = nrm.cross(e1);  // (e1, e2, n) right-handed: CCW seen from +n
      out.normals.row(i) = nrm.transpose();

      // Projected neighbourhood and its Delaunay triangulation, the centre inserted first so
      // that it survives if a neighbour coincides with it.
      dt.clear();
      const Eigen::Vector3d pi = P.row(i).transpose();
      for (int c = 0; c <= k; ++c) {
        const Eigen::Vector3d d = P.row(ids[c]).transpose() - pi;
        q[c] = Eigen::Vector2d(d.dot(e1), d.dot(e2));
      }
      Delaunay::Vertex_handle centre = dt.insert(Kernel::Point_2(0.0, 0.0));
      centre->info() = 0;
      for (int c = 1; c <= k; ++c) {
        const auto before = dt.number_of_vertices();
        Delaunay::Vertex_handle vh = dt.insert(Kernel::Point_2(q[c].x(), q[c].y()));
        if (dt.number_of_vertices() != before) vh->info() = c;  // else: duplicate, keep the first
      }
      LocalFan& fan = fans[i];
      if (dt.dimension() < 2) continue;
      const double min_area = options.degenerate_area_epsilon * mean_sq;
      Delaunay::Face_circulator fc = dt.incident_faces(centre), done = fc;
      do {
        if (dt.is_infinite(fc)) continue;
        int local[3];
        for (int c = 0; c < 3; ++c) local[c] = fc->vertex(c)->info();
        // Rotate so the centre comes first (keeps CCW order, makes output deterministic).
        while (local[0] != 0) std::rotate(local, local + 1, local + 3);
        const Eigen::Vector2d a = q[local[0]], b = q[local[1]], d = q[local[2]];
        const double twice_area2d = (b - a).x() * (d - a).y() - (b - a).y() * (d - a).x();
        if (!(0.5 * twice_area2d > min_area) || !(twice_area2d > 0)) {
          ++fan.degenerate;
          continue;
        }
        LocalTriangle t;
        for (int c = 0; c < 3; ++c) {
          const Eigen::Vector2d& x = q[local[c]];
          const Eigen::Vector2d u = q[local[(c + 1) % 3]] - x, w = q[local[(c + 2) % 3]] - x;
          t.cot[c] = std::clamp(u.dot(w) / twice_area2d, -options.cot_clamp, options.cot_clamp);
          t.v[c] = ids[local[c]];
        }
        const Eigen::Vector3d A = P.row(t.v[0]), B = P.row(t.v[1]), D = P.row(t.v[2]);
        t.area = 0.5 * (B - A).cross(D - A).norm();
        fan.triangles.push_back(t);
      } while (++fc != done);
    }
  }

  // Sequential, ordered merge: results do not depend on the thread count.
  std::vector<std::pair<int64_t, double>> edge_weights;
  std::vector<std::pair<std::array<int, 3>, int64_t>> keyed;  // (sorted corners, occurrence)
  Eigen::VectorXd M = Eigen::VectorXd::Zero(n);
  int64_t occurrence = 0;
  for (int i = 0; i < n; ++i) {
    out.degenerate_triangles += fans[i].degenerate;
    for (const LocalTriangle& t : fans[i].triangles) {
      for (int c = 0; c < 3; ++c) {
        M[t.v[c]] += t.area / 9.0;  // (1/3 weight) · (area / 3 per corner), eq. 6
        const int a = t.v[(c + 1) % 3], b = t.v[(c + 2) % 3];
        const int64_t key = static_cast<int64_t>(std::min(a, b)) * n + std::max(a, b);
        edge_weights.emplace_back(key, t.cot[c] / 6.0);  // (1/3 weight) · ½ cot, eq. 5
      }
      std::array<int, 3> s = t.v;
      std::sort(s.begin(), s.end());
      keyed.emplace_back(s, occurrence++);
    }
  }
  if (keyed.empty())
    throw InvalidInputError("point_laplacian: no local triangle could be built (the " + std::to_string(n) +
                            " points are collinear or coincident)");

  // Distinct triangles, first occurrence kept, in order of occurrence.
  std::vector<std::array<int, 3>> all_tris;
  all_tris.reserve(keyed.size());
  for (const LocalFan& f : fans)
    for (const LocalTriangle& t : f.triangles) all_tris.push_back(t.v);
  std::sort(keyed.begin(), keyed.end());
  std::vector<int64_t> firsts;
  for (size_t r = 0; r < keyed.size(); ++r)
    if (r == 0 || keyed[r].first != keyed[r - 1].first) firsts.push_back(keyed[r].second);
  std::sort(firsts.begin(), firsts.end());
  out.triangles.resize(static_cast<Eigen::Index>(firsts.size()), 3);
  for (size_t r = 0; r < firsts.size(); ++r)
    for (int c = 0; c < 3; ++c) out.triangles(static_cast<Eigen::Index>(r), c) = all_tris[firsts[r]][c];

  // Sum the contributions per edge (sorted: deterministic order), clamp, assemble.
  std::sort(edge_weights.begin(), edge_weights.end());
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(edge_weights.size());
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(n);
  double length_sum = 0;
  int64_t edge_count = 0;
  for (size_t r = 0; r < edge_weights.size();) {
    const int64_t key = edge_weights[r].first;
    double w = 0;
    for (; r < edge_weights.size() && edge_weights[r].first == key; ++r) w += edge_weights[r].second;
    const int a = static_cast<int>(key / n), b = static_cast<int>(key % n);
    length_sum += (P.row(a) - P.row(b)).norm();
    ++edge_count;
    if (w < 0) {
      ++out.clamped_edges;
      continue;
    }
    if (w == 0) continue;
    triplets.emplace_back(a, b, w);
    triplets.emplace_back(b, a, w);
    diag[a] -= w;
    diag[b] -= w;
  }
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, diag[i]);

  Laplacian& lap = out.laplacian;
  lap.L.resize(n, n);
  lap.L.setFromTriplets(triplets.begin(), triplets.end());
  lap.L.makeCompressed();
  lap.mean_edge_length = edge_count > 0 ? length_sum / static_cast<double>(edge_count) : 0.0;
  const Eigen::Index positive = (M.array() > 0).count();
  const double floor_mass = options.min_mass_fraction * M.sum() / static_cast<double>(std::max<Eigen::Index>(1, positive));
  for (int i = 0; i < n; ++i)
    if (!(M[i] > 0)) {
      ++out.isolated_points;
      M[i] = floor_mass;
    } else if (M[i] < floor_mass) {
      M[i] = floor_mass;
    }
  lap.M = std::move(M);
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace heatcvt
