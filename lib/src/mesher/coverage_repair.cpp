// Coverage repair of the working mesh (mesher/coverage_repair.h).
#include "heatcvt/mesher/coverage_repair.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

#include "heatcvt/closest_point.h"
#include "heatcvt/mesh.h"
#include "heatcvt/point_index.h"

namespace heatcvt {

namespace {

// Distances from the samples to the mesh, kept up to date as vertices move. For each sample, the
// distance to the faces around its nearest vertex (`bound`) bounds its distance to the mesh, and
// is it wherever the closest point lies in that fan; only the samples whose bound exceeds the
// limit (they may be uncovered), or the largest distance found, are searched in the whole mesh.
// After moves, only the samples a moved vertex's faces can have been nearest (within the limit
// plus the longest edge of the old or the new position) and the uncovered ones are measured again.
class Gaps {
 public:
  Gaps(const WorkingMesh& mesh, const Eigen::MatrixX3d& samples, double limit)
      : mesh_(mesh), samples_(samples), limit_(limit), sample_index_(samples),
        bound_(static_cast<std::size_t>(samples.rows()), 0.0) {
    std::vector<int> all(bound_.size());
    std::iota(all.begin(), all.end(), 0);
    measure(all);
  }

  // Measures again after the vertices `moved` went from their positions in `old` (#V by 3).
  void update(const std::vector<int>& moved, const Eigen::MatrixX3d& old) {
    double longest = 0;
    for (const MeshFace& f : mesh_.faces())
      for (int k = 0; k < 3; ++k) longest = std::max(longest, (mesh_.V.row(f[k]) - mesh_.V.row(f[(k + 1) % 3])).norm());
    std::vector<char> again(bound_.size(), 0);
    for (std::size_t i = 0; i < bound_.size(); ++i) again[i] = distance[i] > limit_;
    for (int v : moved)
      for (const Eigen::Vector3d x : {Eigen::Vector3d(old.row(v).transpose()), Eigen::Vector3d(mesh_.V.row(v).transpose())})
        for (int i : sample_index_.within(x, limit_ + longest)) again[static_cast<std::size_t>(i)] = 1;
    std::vector<int> which;
    for (std::size_t i = 0; i < again.size(); ++i)
      if (again[i]) which.push_back(static_cast<int>(i));
    measure(which);
  }

  std::vector<double> distance;  // to the mesh where above the limit, else −1
  std::vector<int> face;         // the nearest face where above the limit, else −1
  double largest = 0;            // over every sample

 private:
  void measure(const std::vector<int>& which) {
    const Eigen::Index n = samples_.rows();
    distance.resize(static_cast<std::size_t>(n), -1.0);
    face.resize(static_cast<std::size_t>(n), -1);
    Eigen::MatrixX3i F(mesh_.num_faces(), 3);
    for (int f = 0; f < mesh_.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) F(f, k) = mesh_.face(f)[k];
    const std::vector<std::vector<int>> vf = mesh_.vertex_faces();
    std::vector<int> corner;  // the vertices in faces, as rows of `corners`
    for (int v = 0; v < mesh_.num_vertices(); ++v)
      if (!vf[v].empty()) corner.push_back(v);
    Eigen::MatrixX3d corners(static_cast<Eigen::Index>(corner.size()), 3);
    for (std::size_t r = 0; r < corner.size(); ++r) corners.row(static_cast<Eigen::Index>(r)) = mesh_.V.row(corner[r]);
    const PointIndex index(corners);
#pragma omp parallel for schedule(static)
    for (std::size_t r = 0; r < which.size(); ++r) {
      const int i = which[r];
      const Eigen::Vector3d q = samples_.row(i).transpose();
      double d = 0, b = std::numeric_limits<double>::infinity();
      for (int f : vf[corner[static_cast<std::size_t>(index.nearest(q, d))]]) {
        const Eigen::Vector3d a = mesh_.V.row(F(f, 0)).transpose(), e = mesh_.V.row(F(f, 1)).transpose(),
                              c = mesh_.V.row(F(f, 2)).transpose();
        const Eigen::Vector3d w = closest_point_barycentric(q, a, e, c);
        b = std::min(b, (w[0] * a + w[1] * e + w[2] * c - q).norm());
      }
      bound_[static_cast<std::size_t>(i)] = b;
      distance[static_cast<std::size_t>(i)] = -1;
      face[static_cast<std::size_t>(i)] = -1;
    }
    std::vector<int> order(bound_.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return bound_[a] > bound_[b]; });
    const ClosestPointTree tree(mesh_.V, F);
    const auto exact = [&](int i) {
      const SurfacePoint p = tree.closest(samples_.row(i).transpose());
      const double d = (position(mesh_.V, F, p) - samples_.row(i).transpose()).norm();
      distance[static_cast<std::size_t>(i)] = d > limit_ ? d : -1;
      face[static_cast<std::size_t>(i)] = d > limit_ ? p.face : -1;
      return d;
    };
    // Every sample whose bound is beyond the limit may be uncovered.
    const int candidates =
        static_cast<int>(std::count_if(bound_.begin(), bound_.end(), [&](double d) { return d > limit_; }));
    std::vector<double> found(static_cast<std::size_t>(candidates), 0.0);
#pragma omp parallel for schedule(dynamic, 64)
    for (int r = 0; r < candidates; ++r) found[static_cast<std::size_t>(r)] = exact(order[static_cast<std::size_t>(r)]);
    largest = 0;
    for (double d : found) largest = std::max(largest, d);
    // The others only for the largest distance.
    for (std::size_t r = static_cast<std::size_t>(candidates); r < order.size() && bound_[order[r]] > largest; ++r)
      largest = std::max(largest, exact(order[r]));
  }

  const WorkingMesh& mesh_;
  const Eigen::MatrixX3d& samples_;
  const double limit_;
  const PointIndex sample_index_;
  std::vector<double> bound_;
};

// The shape of faces after a move: their smallest angle and whether the move is allowed
// (faces_shape()).
struct RingShape {
  double min_angle = M_PI;
  bool ok = true;
};

// A vertex's place after a move: position and normal on the surface, and the projector's hint.
struct Placed {
  int v = -1;
  Eigen::Vector3d x, n;
  int hint = -1;
};

// The shape of faces `faces` with the vertices of `moved` at their new places: the smallest angle,
// and whether every face turns by at most `max_turn` (cosine) from its current normal and, where
// it has v as a corner, faces along `normal`.
RingShape faces_shape(const WorkingMesh& mesh, const std::vector<int>& faces, const std::vector<Placed>& moved, int v,
                      const Eigen::Vector3d& normal, double cos_max_turn) {
  const auto at = [&](int w) -> Eigen::Vector3d {
    for (const Placed& m : moved)
      if (m.v == w) return m.x;
    return mesh.V.row(w).transpose();
  };
  RingShape r;
  for (int id : faces) {
    const MeshFace& f = mesh.face(id);
    Eigen::Vector3d p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      q[k] = mesh.V.row(f[k]).transpose();
      p[k] = at(f[k]);
    }
    const Eigen::Vector3d now = (q[1] - q[0]).cross(q[2] - q[0]), after = (p[1] - p[0]).cross(p[2] - p[0]);
    const double ln = now.norm(), la = after.norm();
    const bool at_v = f[0] == v || f[1] == v || f[2] == v;
    if (!(la > 0) || (at_v && !(after.dot(normal) > 0)) || (ln > 0 && after.dot(now) < cos_max_turn * ln * la))
      r.ok = false;
    r.min_angle = std::min(r.min_angle, triangle_min_angle(p[0], p[1], p[2]));
  }
  return r;
}

// Vertex w moved by d and projected to the surface.
Placed place(const WorkingMesh& mesh, const SurfaceProjector& surface, int w, const Eigen::Vector3d& d) {
  Placed m;
  m.v = w;
  m.hint = mesh.anchor[w];
  surface.project(mesh.V.row(w).transpose() + d, m.hint, m.x, m.n);
  return m;
}

// v's ring neighbours that may move with it (not locked, not busy), and the faces of v and of
// those neighbours: the faces whose shape a dragged move changes.
void drag_region(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, const std::vector<char>& locked,
                 const std::vector<char>& busy, int v, std::vector<int>& ring, std::vector<int>& faces) {
  for (int id : vf[v])
    for (int w : mesh.face(id))
      if (w != v && !locked[w] && !busy[w] && std::find(ring.begin(), ring.end(), w) == ring.end()) ring.push_back(w);
  for (int w : ring) faces.insert(faces.end(), vf[w].begin(), vf[w].end());
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
}

// Tries to move a corner of face `face` towards sample q: each corner, nearest first, alone, then
// (options.ring_drag > 0) with its ring neighbours dragged along by that fraction of its
// displacement; appends the vertices moved to `moved` and returns whether any did. Vertices in
// `busy` (moved this round, or next to a moved one) are neither tried nor dragged.
bool move_towards(WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<std::vector<int>>& vf,
                  const std::vector<char>& locked, std::vector<char>& busy, int face, const Eigen::Vector3d& q,
                  const CoverageRepairOptions& o, std::vector<int>& moved) {
  const MeshFace& f = mesh.face(face);
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) {
    return (mesh.V.row(f[a]).transpose() - q).squaredNorm() < (mesh.V.row(f[b]).transpose() - q).squaredNorm();
  });
  const double floor = o.min_angle_deg * M_PI / 180.0, cos_turn = std::cos(o.max_turn_deg * M_PI / 180.0);
  std::vector<double> drags{0.0};
  if (o.ring_drag > 0) drags.push_back(o.ring_drag);
  for (const double drag : drags) {
    for (int k : order) {
      const int v = f[k];
      if (locked[v] || busy[v]) continue;
      std::vector<int> ring, faces = vf[v];
      if (drag > 0) drag_region(mesh, vf, locked, busy, v, ring, faces);
      if (drag > 0 && ring.empty()) continue;
      const double before = faces_shape(mesh, faces, {}, -1, Eigen::Vector3d::Zero(), -1).min_angle;
      // The side the ring faces now: a projector's normals need not be oriented like the faces (a
      // cloud's fit, after the closed pieces were turned outward).
      Eigen::Vector3d facing = Eigen::Vector3d::Zero();
      for (int id : vf[v]) {
        const MeshFace& g = mesh.face(id);
        facing += (mesh.V.row(g[1]) - mesh.V.row(g[0])).cross(mesh.V.row(g[2]) - mesh.V.row(g[0])).transpose();
      }
      for (double t : o.fractions) {
        const Eigen::Vector3d d = t * (q - mesh.V.row(v).transpose());
        std::vector<Placed> to{place(mesh, surface, v, d)};
        for (int w : ring) to.push_back(place(mesh, surface, w, drag * d));
        const Eigen::Vector3d& n = to.front().n;
        const RingShape s = faces_shape(mesh, faces, to, v, n.dot(facing) < 0 ? Eigen::Vector3d(-n) : n, cos_turn);
        if (!s.ok || s.min_angle < std::min(floor, before)) continue;
        for (const Placed& m : to) {
          mesh.V.row(m.v) = m.x.transpose();
          mesh.N.row(m.v) = m.n.transpose();
          mesh.anchor[m.v] = m.hint;
          moved.push_back(m.v);
          for (int id : vf[m.v])
            for (int u : mesh.face(id)) busy[u] = 1;
        }
        return true;
      }
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
  Gaps gaps(mesh, samples, limit);
  const auto uncovered = [&](const Gaps& g) {
    return static_cast<int>(std::count_if(g.distance.begin(), g.distance.end(), [&](double d) { return d > limit; }));
  };
  stats.gap_before = gaps.largest;
  stats.uncovered_before = uncovered(gaps);
  // With keep_narrowest_round, the state of the narrowest largest gap so far is kept to return.
  double best_gap = gaps.largest;
  int best_uncovered = stats.uncovered_before, best_moves = 0;
  std::unique_ptr<WorkingMesh::Checkpoint> best;  // none: the state before the first round
  const WorkingMesh::Checkpoint start = options.keep_narrowest_round ? mesh.checkpoint() : WorkingMesh::Checkpoint{};
  for (int round = 0; round < options.rounds && gaps.largest > limit; ++round) {
    std::vector<int> order;
    for (int i = 0; i < static_cast<int>(gaps.distance.size()); ++i)
      if (gaps.distance[i] > limit) order.push_back(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return gaps.distance[a] > gaps.distance[b]; });
    std::vector<char> busy(static_cast<std::size_t>(mesh.num_vertices()), 0);
    const Eigen::MatrixX3d old = mesh.V;
    std::vector<int> moved;
    for (int i : order) move_towards(mesh, surface, vf, locked, busy, gaps.face[i], samples.row(i).transpose(), options, moved);
    stats.moves += static_cast<int>(moved.size());
    if (moved.empty()) break;
    gaps.update(moved, old);
    stats.round_gaps.push_back(gaps.largest);
    if (options.keep_narrowest_round && gaps.largest < best_gap) {
      best_gap = gaps.largest;
      best_uncovered = uncovered(gaps);
      best_moves = stats.moves;
      best = std::make_unique<WorkingMesh::Checkpoint>(mesh.checkpoint());
    }
  }
  stats.gap_after = gaps.largest;
  stats.uncovered_after = uncovered(gaps);
  if (options.keep_narrowest_round && gaps.largest > best_gap) {
    mesh.rollback(best ? *best : start);
    stats.gap_after = best_gap;
    stats.uncovered_after = best_uncovered;
    stats.moves = best_moves;
  }
  return stats;
}

}  // namespace heatcvt
