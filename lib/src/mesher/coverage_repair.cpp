// Coverage repair of the working mesh (mesher/coverage_repair.h).
#include "heatcvt/mesher/coverage_repair.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "heatcvt/closest_point.h"
#include "heatcvt/mesh.h"

namespace heatcvt {

namespace {

// Distance from each sample to the mesh and the face it is nearest.
struct Gaps {
  std::vector<double> distance;
  std::vector<int> face;
  double largest = 0;
};

Gaps measure_gaps(const WorkingMesh& mesh, const Eigen::MatrixX3d& samples) {
  Gaps g;
  Eigen::MatrixX3i F(mesh.num_faces(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = mesh.face(f)[k];
  const std::vector<SurfacePoint> nearest = closest_surface_points(mesh.V, F, samples);
  g.distance.resize(static_cast<std::size_t>(samples.rows()));
  g.face.resize(g.distance.size());
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    const SurfacePoint& p = nearest[static_cast<std::size_t>(i)];
    g.face[static_cast<std::size_t>(i)] = p.face;
    g.distance[static_cast<std::size_t>(i)] = (position(mesh.V, F, p) - samples.row(i).transpose()).norm();
    g.largest = std::max(g.largest, g.distance[static_cast<std::size_t>(i)]);
  }
  return g;
}

// Smallest angle of the faces `ring` around v with v at `x`, and whether every one of them faces
// along `normal` and turns by at most `max_turn` (cosine) from its current normal.
struct RingShape {
  double min_angle = M_PI;
  bool ok = true;
};

RingShape ring_shape(const WorkingMesh& mesh, const std::vector<int>& ring, int v, const Eigen::Vector3d& x,
                     const Eigen::Vector3d& normal, double cos_max_turn) {
  RingShape r;
  for (int id : ring) {
    const MeshFace& f = mesh.face(id);
    Eigen::Vector3d p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.V.row(f[k]).transpose();
      p[k] = f[k] == v ? x : q[k];
    }
    const Eigen::Vector3d now = (q[1] - q[0]).cross(q[2] - q[0]), moved = (p[1] - p[0]).cross(p[2] - p[0]);
    const double ln = now.norm(), lm = moved.norm();
    if (!(lm > 0) || !(moved.dot(normal) > 0) || (ln > 0 && moved.dot(now) < cos_max_turn * ln * lm)) r.ok = false;
    r.min_angle = std::min(r.min_angle, triangle_min_angle(p[0], p[1], p[2]));
  }
  return r;
}

// Tries to move a corner of face `face` towards sample q; returns whether a move was kept.
// Vertices in `busy` (moved this round, or next to a moved one) are not tried.
bool move_towards(WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<std::vector<int>>& vf,
                  const std::vector<char>& locked, std::vector<char>& busy, int face, const Eigen::Vector3d& q,
                  const CoverageRepairOptions& o) {
  const MeshFace& f = mesh.face(face);
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) {
    return (mesh.V.row(f[a]).transpose() - q).squaredNorm() < (mesh.V.row(f[b]).transpose() - q).squaredNorm();
  });
  const double floor = o.min_angle_deg * M_PI / 180.0, cos_turn = std::cos(o.max_turn_deg * M_PI / 180.0);
  for (int k : order) {
    const int v = f[k];
    if (locked[v] || busy[v]) continue;
    const Eigen::Vector3d x = mesh.V.row(v).transpose();
    const double before = ring_shape(mesh, vf[v], v, x, mesh.N.row(v).transpose(), -1).min_angle;
    for (double t : o.fractions) {
      int hint = mesh.anchor[v];
      Eigen::Vector3d p, n;
      surface.project(x + t * (q - x), hint, p, n);
      const RingShape s = ring_shape(mesh, vf[v], v, p, n, cos_turn);
      if (!s.ok || s.min_angle < std::min(floor, before)) continue;
      mesh.V.row(v) = p.transpose();
      mesh.N.row(v) = n.transpose();
      mesh.anchor[v] = hint;
      for (int id : vf[v])
        for (int w : mesh.face(id)) busy[w] = 1;
      return true;
    }
  }
  return false;
}

}  // namespace

CoverageRepairStats repair_coverage(WorkingMesh& mesh, const SurfaceProjector& surface,
                                    const Eigen::MatrixX3d& samples, double spacing,
                                    const CoverageRepairOptions& options, const std::vector<char>* fixed) {
  CoverageRepairStats stats;
  if (mesh.empty() || samples.rows() == 0) return stats;
  const double limit = options.max_gap * spacing;
  std::vector<char> locked = mesh.boundary_vertices();
  if (fixed)
    for (std::size_t v = 0; v < locked.size() && v < fixed->size(); ++v) locked[v] |= (*fixed)[v];
  const std::vector<std::vector<int>> vf = mesh.vertex_faces();  // moves keep the faces
  Gaps gaps = measure_gaps(mesh, samples);
  const auto uncovered = [&](const Gaps& g) {
    return static_cast<int>(std::count_if(g.distance.begin(), g.distance.end(), [&](double d) { return d > limit; }));
  };
  stats.gap_before = gaps.largest;
  stats.uncovered_before = uncovered(gaps);
  for (int round = 0; round < options.rounds && gaps.largest > limit; ++round) {
    std::vector<int> order;
    for (int i = 0; i < static_cast<int>(gaps.distance.size()); ++i)
      if (gaps.distance[i] > limit) order.push_back(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return gaps.distance[a] > gaps.distance[b]; });
    std::vector<char> busy(static_cast<std::size_t>(mesh.num_vertices()), 0);
    int moved = 0;
    for (int i : order)
      if (move_towards(mesh, surface, vf, locked, busy, gaps.face[i], samples.row(i).transpose(), options)) ++moved;
    stats.moves += moved;
    if (moved == 0) break;
    gaps = measure_gaps(mesh, samples);
  }
  stats.gap_after = gaps.largest;
  stats.uncovered_after = uncovered(gaps);
  return stats;
}

}  // namespace heatcvt
