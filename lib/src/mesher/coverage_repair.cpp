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
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/point_index.h"

namespace heatcvt {

namespace {

// Insertions per growth round: each round measures the gaps of every sample again.
constexpr int kMaxInsertionsPerRound = 64;
// A face at a grown vertex and its neighbour across the edge opposite it must not meet at a
// dihedral angle above 120° (the cosine of their unit normals above −0.5): a fold, not a side.
constexpr double kMinGrowthFoldCos = -0.5;

// Unit normal of face f of `mesh` (zero for a degenerate face).
Eigen::Vector3d face_normal(const WorkingMesh& mesh, const MeshFace& f) {
  const Eigen::Vector3d n =
      (mesh.V.row(f[1]) - mesh.V.row(f[0])).cross(mesh.V.row(f[2]) - mesh.V.row(f[0])).transpose();
  return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
}

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
      for (const Eigen::Vector3d& x : {Eigen::Vector3d(old.row(v).transpose()), Eigen::Vector3d(mesh_.V.row(v).transpose())})
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

// Splits the edge of face `face` whose midpoint is nearest q (an interior edge, neither end
// locked) at that midpoint projected to the surface, and updates `vf`; returns the new vertex,
// or −1 where no edge of the face may be split. Faces (a, b, c) and its twin (b, a, d) become
// (a, m, c), (m, b, c) and (b, m, d), (m, a, d): the orientation is kept.
int split_towards(WorkingMesh& mesh, const SurfaceProjector& surface, std::vector<std::vector<int>>& vf,
                  const std::vector<char>& locked, int face, const Eigen::Vector3d& q) {
  const MeshFace f = mesh.face(face);
  int best = -1;
  double nearest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const int a = f[k], b = f[(k + 1) % 3];
    if ((locked[a] && locked[b]) || mesh.edge_face_count(a, b) != 2) continue;
    const double d = (0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose() - q).squaredNorm();
    if (d < nearest) nearest = d, best = k;
  }
  if (best < 0) return -1;
  const int a = f[best], b = f[(best + 1) % 3], c = f[(best + 2) % 3];
  const int other = mesh.half_edge_face(b, a);
  if (other < 0) return -1;
  int d = -1;
  for (int v : mesh.face(other))
    if (v != a && v != b) d = v;
  if (d < 0 || d == c) return -1;
  Eigen::Vector3d pos, nrm;
  int hint = mesh.anchor[a];
  surface.project(0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose(), hint, pos, nrm);
  if (!pos.allFinite() || !nrm.allFinite()) return -1;
  const int m = mesh.add_vertex(pos, nrm, hint);
  mesh.replace_face(face, {a, m, c});
  mesh.replace_face(other, {b, m, d});
  const int f3 = mesh.add_face({m, b, c}), f4 = mesh.add_face({m, a, d});
  vf.resize(static_cast<std::size_t>(mesh.num_vertices()));
  vf[m] = {face, other, f3, f4};
  std::replace(vf[a].begin(), vf[a].end(), other, f4);
  std::replace(vf[b].begin(), vf[b].end(), face, f3);
  vf[c].push_back(f3);
  vf[d].push_back(f4);
  return m;
}

// Move attempts known to fail. A failed move_towards() changes nothing, and its outcome reads only
// the face it was given and the vertices within two rings of that face's corners (positions,
// projector hints, faces, busy marks). So an attempt that failed while none of those vertices was
// busy fails again, for the same face with the same corners, while none of them has changed since
// and none is busy: it is skipped, with the same result as trying it.
class FailedMoves {
 public:
  explicit FailedMoves(Eigen::Index samples) : when_(static_cast<std::size_t>(samples), -1), face_(when_.size(), -1), corners_(when_.size()) {}

  // Vertices moved, added or given other faces now.
  void changed(const std::vector<int>& vertices) {
    for (int v : vertices) {
      if (v >= static_cast<int>(changed_at_.size())) changed_at_.resize(static_cast<std::size_t>(v) + 1, 0);
      changed_at_[static_cast<std::size_t>(v)] = ++clock_;
    }
  }
  bool known(int sample, int face, const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf,
             const std::vector<char>& busy) const {
    const std::size_t i = static_cast<std::size_t>(sample);
    if (when_[i] < 0 || face_[i] != face || corners_[i] != mesh.face(face)) return false;
    for (int u : region(mesh, vf, face))
      if (busy[u] || (u < static_cast<int>(changed_at_.size()) && changed_at_[u] > when_[i])) return false;
    return true;
  }
  void failed(int sample, int face, const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf,
              const std::vector<char>& busy) {
    const std::size_t i = static_cast<std::size_t>(sample);
    when_[i] = -1;
    for (int u : region(mesh, vf, face))
      if (busy[u]) return;
    when_[i] = clock_;
    face_[i] = face;
    corners_[i] = mesh.face(face);
  }

 private:
  // The vertices within two rings of the corners of `face`.
  static std::vector<int> region(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, int face) {
    std::vector<int> ring;
    for (int c : mesh.face(face))
      for (int id : vf[c]) ring.insert(ring.end(), mesh.face(id).begin(), mesh.face(id).end());
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    std::vector<int> r;
    for (int w : ring)
      for (int id : vf[w]) r.insert(r.end(), mesh.face(id).begin(), mesh.face(id).end());
    return r;
  }
  long clock_ = 0;
  std::vector<long> changed_at_;
  std::vector<long> when_;
  std::vector<int> face_;
  std::vector<MeshFace> corners_;
};

// The faces a growth attempt at face `face` may change, saved with the mesh's counts so that the
// attempt is undone without a copy of the whole mesh: the faces at the corners of `face` and at
// the vertices across its edges. Those hold every face the split (split_towards()) rewrites,
// whichever edge it takes, and every face at its four corners, the only faces the flips around
// the new vertex can change (flip_edges() with `only_at`).
struct LocalUndo {
  int vertices = 0, faces = 0;
  std::vector<int> ids;           // ascending
  std::vector<MeshFace> corners;  // the faces `ids` as saved
};

LocalUndo save_around(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, int face) {
  LocalUndo u;
  u.vertices = mesh.num_vertices();
  u.faces = mesh.num_faces();
  const MeshFace& f = mesh.face(face);
  std::vector<int> at(f.begin(), f.end());
  for (int k = 0; k < 3; ++k)
    if (const int g = mesh.half_edge_face(f[(k + 1) % 3], f[k]); g >= 0) at.insert(at.end(), mesh.face(g).begin(), mesh.face(g).end());
  for (int w : at) u.ids.insert(u.ids.end(), vf[w].begin(), vf[w].end());
  std::sort(u.ids.begin(), u.ids.end());
  u.ids.erase(std::unique(u.ids.begin(), u.ids.end()), u.ids.end());
  for (int id : u.ids) u.corners.push_back(mesh.face(id));
  return u;
}

// The faces an attempt may have changed: the saved ones and those added since.
std::vector<int> touched_faces(const WorkingMesh& mesh, const LocalUndo& u) {
  std::vector<int> t = u.ids;
  for (int id = u.faces; id < mesh.num_faces(); ++id) t.push_back(id);
  return t;
}

// Brings `vf` up to date (ascending lists, as WorkingMesh::vertex_faces()) after the faces
// `touched` (ascending; ids past the face count are gone) changed; `stale` holds every vertex
// whose list may name one of them.
void sync_vertex_faces(const WorkingMesh& mesh, const std::vector<int>& touched, std::vector<int> stale,
                       std::vector<std::vector<int>>& vf) {
  vf.resize(static_cast<std::size_t>(mesh.num_vertices()));
  for (int id : touched)
    if (id < mesh.num_faces()) stale.insert(stale.end(), mesh.face(id).begin(), mesh.face(id).end());
  std::sort(stale.begin(), stale.end());
  stale.erase(std::unique(stale.begin(), stale.end()), stale.end());
  const auto is_touched = [&](int id) { return std::binary_search(touched.begin(), touched.end(), id); };
  for (int v : stale)
    if (v < mesh.num_vertices()) vf[v].erase(std::remove_if(vf[v].begin(), vf[v].end(), is_touched), vf[v].end());
  for (int id : touched)
    if (id < mesh.num_faces())
      for (int w : mesh.face(id)) vf[w].push_back(id);
  for (int v : stale)
    if (v < mesh.num_vertices()) std::sort(vf[v].begin(), vf[v].end());
}

// Corners of the faces `ids` (those that exist).
std::vector<int> corners_of(const WorkingMesh& mesh, const std::vector<int>& ids) {
  std::vector<int> c;
  for (int id : ids)
    if (id < mesh.num_faces()) c.insert(c.end(), mesh.face(id).begin(), mesh.face(id).end());
  return c;
}

// Undoes an attempt: the saved faces back, the faces and vertices added since dropped; `vf` follows.
void undo_attempt(WorkingMesh& mesh, const LocalUndo& u, std::vector<std::vector<int>>& vf) {
  const std::vector<int> touched = touched_faces(mesh, u);
  const std::vector<int> stale = corners_of(mesh, touched);
  while (mesh.num_faces() > u.faces) mesh.pop_face();
  for (std::size_t i = 0; i < u.ids.size(); ++i) mesh.replace_face(u.ids[i], u.corners[i]);
  while (mesh.num_vertices() > u.vertices) mesh.pop_vertex();
  sync_vertex_faces(mesh, touched, stale, vf);
}

// One growth round (CoverageRepairOptions::grow_gap): for the samples farther than `grow_limit`
// (farthest first, one per region), the edge of the nearest face nearest to the sample is split
// (split_towards()) and the new vertex m moved the largest of options.fractions of the way to it,
// by at most `step`; max-min-angle flips then run around m, and the edit is kept where the faces
// around m keep a smallest angle of min(min_angle_deg, the smallest before) and no face at m folds
// over its neighbour (kMinGrowthFoldCos), else undone. At most `budget` vertices are added; `vf` and
// `locked` follow the mesh, the added vertices are appended to `moved` and the corners of every face
// a kept edit changed to `regrown`. Returns the vertices added.
int grow_towards(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& samples, const Gaps& gaps,
                 double grow_limit, double step, int budget, const CoverageRepairOptions& options,
                 std::vector<std::vector<int>>& vf, std::vector<char>& locked, std::vector<int>& moved,
                 std::vector<int>& regrown) {
  const double floor_angle = options.min_angle_deg * M_PI / 180.0;
  std::vector<int> order;
  for (int i = 0; i < static_cast<int>(gaps.distance.size()); ++i)
    if (gaps.distance[i] > grow_limit) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return gaps.distance[a] > gaps.distance[b]; });
  std::vector<char> busy(static_cast<std::size_t>(mesh.num_vertices()), 0);
  std::vector<char> near;  // the ring of the attempt's new vertex, cleared after each attempt
  int inserted = 0;
  for (int i : order) {
    if (inserted >= budget) break;
    const int face = gaps.face[i];
    const MeshFace old_face = mesh.face(face);
    if (busy[old_face[0]] || busy[old_face[1]] || busy[old_face[2]]) continue;
    const Eigen::Vector3d q = samples.row(i).transpose();
    // The shape to keep: the smallest angle of the faces around the split face's corners.
    double shape_before = M_PI;
    for (int w : old_face)
      for (int id : vf[w]) shape_before = std::min(shape_before, face_min_angle(mesh, mesh.face(id)));
    const double floor = std::min(floor_angle, shape_before) - 1e-12;
    const LocalUndo undo = save_around(mesh, vf, face);
    bool kept = false, capped = false;
    for (const double t : options.fractions) {
      if (capped) break;  // the step bound gave the last fraction the same move
      const int m = split_towards(mesh, surface, vf, locked, face, q);
      if (m < 0) break;
      Eigen::Vector3d d = t * (q - mesh.V.row(m).transpose());
      if (d.norm() > step) d *= step / d.norm(), capped = true;
      const Placed to = place(mesh, surface, m, d);
      mesh.V.row(m) = to.x.transpose();
      mesh.N.row(m) = to.n.transpose();
      mesh.anchor[m] = to.hint;
      // Max-min-angle flips around m: the split's halves become the diagonal the new vertex asks for.
      near.resize(static_cast<std::size_t>(mesh.num_vertices()), 0);
      std::vector<int> ring;
      for (int id : vf[m])
        for (int w : mesh.face(id))
          if (!near[w]) near[w] = 1, ring.push_back(w);
      const std::vector<int> touched = touched_faces(mesh, undo);
      flip_edges(mesh, FlipOptions{}, &near, nullptr, nullptr, nullptr, &touched);
      // Before the flips, the touched faces had the saved corners and m.
      std::vector<int> stale{m};
      for (const MeshFace& g : undo.corners) stale.insert(stale.end(), g.begin(), g.end());
      sync_vertex_faces(mesh, touched, stale, vf);
      // Kept where the faces around m keep their shape and none at m folds over its neighbour
      // across the edge opposite m (a finger's sides stand steep on the faces around its base,
      // at up to about 90°; a fold turns one back).
      double after = M_PI;
      bool unfolded = true;
      for (int w : ring)
        for (int id : vf[w]) after = std::min(after, face_min_angle(mesh, mesh.face(id)));
      for (int id : vf[m]) {
        const MeshFace& g = mesh.face(id);
        int k = 0;
        while (g[k] != m) ++k;
        const int u = g[(k + 1) % 3], x = g[(k + 2) % 3];
        const int across = mesh.half_edge_face(x, u);
        if (across < 0) continue;
        if (!(face_normal(mesh, g).dot(face_normal(mesh, mesh.face(across))) > kMinGrowthFoldCos)) unfolded = false;
      }
      for (int w : ring) near[w] = 0;
      if (unfolded && after >= floor) {
        kept = true;
        locked.resize(static_cast<std::size_t>(mesh.num_vertices()), 0);
        busy.resize(static_cast<std::size_t>(mesh.num_vertices()), 0);
        for (int w : ring) busy[w] = 1;
        moved.push_back(m);
        const std::vector<int> corners = corners_of(mesh, touched);
        regrown.insert(regrown.end(), corners.begin(), corners.end());
        for (const MeshFace& g : undo.corners) regrown.insert(regrown.end(), g.begin(), g.end());
        break;
      }
      undo_attempt(mesh, undo, vf);
    }
    if (kept) ++inserted;
  }
  return inserted;
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
  std::vector<std::vector<int>> vf = mesh.vertex_faces();  // moves keep the faces; splits update it
  auto gaps_ptr = std::make_unique<Gaps>(mesh, samples, limit);
  const auto uncovered = [&](const Gaps& g) {
    return static_cast<int>(std::count_if(g.distance.begin(), g.distance.end(), [&](double d) { return d > limit; }));
  };
  stats.gap_before = gaps_ptr->largest;
  stats.uncovered_before = uncovered(*gaps_ptr);
  if (stats.uncovered_before > options.max_uncovered_fraction * static_cast<double>(samples.rows())) {
    stats.skipped = true;
    stats.gap_after = stats.gap_before;
    stats.uncovered_after = stats.uncovered_before;
    return stats;
  }
  // With keep_narrowest_round, the state of the narrowest largest gap so far is kept to return.
  double best_gap = gaps_ptr->largest;
  int best_uncovered = stats.uncovered_before, best_moves = 0, best_inserted = 0;
  std::unique_ptr<WorkingMesh::Checkpoint> best;  // none: the state before the first round
  const WorkingMesh::Checkpoint start = options.keep_narrowest_round ? mesh.checkpoint() : WorkingMesh::Checkpoint{};
  FailedMoves failed(samples.rows());
  const auto move_rounds = [&]() {
    Gaps& gaps = *gaps_ptr;
    for (int round = 0; round < options.rounds && gaps.largest > limit; ++round) {
      std::vector<int> order;
      for (int i = 0; i < static_cast<int>(gaps.distance.size()); ++i)
        if (gaps.distance[i] > limit) order.push_back(i);
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return gaps.distance[a] > gaps.distance[b]; });
      std::vector<char> busy(static_cast<std::size_t>(mesh.num_vertices()), 0);
      const Eigen::MatrixX3d old = mesh.V;
      std::vector<int> moved;
      for (int i : order) {
        const int face = gaps.face[i];
        if (failed.known(i, face, mesh, vf, busy)) continue;
        const std::size_t before = moved.size();
        if (move_towards(mesh, surface, vf, locked, busy, face, samples.row(i).transpose(), options, moved))
          failed.changed(std::vector<int>(moved.begin() + static_cast<std::ptrdiff_t>(before), moved.end()));
        else
          failed.failed(i, face, mesh, vf, busy);
      }
      stats.moves += static_cast<int>(moved.size());
      if (moved.empty()) break;
      gaps.update(moved, old);
      stats.round_gaps.push_back(gaps.largest);
      if (options.keep_narrowest_round && gaps.largest < best_gap) {
        best_gap = gaps.largest;
        best_uncovered = uncovered(gaps);
        best_moves = stats.moves;
        best_inserted = stats.inserted;
        best = std::make_unique<WorkingMesh::Checkpoint>(mesh.checkpoint());
      }
    }
  };
  move_rounds();
  // Growth, then the move rounds again where it inserted vertices.
  const double grow_limit = options.grow_gap * spacing;
  int budget = static_cast<int>(std::floor(options.max_grown_fraction * vertices_in_faces(mesh)));
  for (int g = 0; g < options.grow_rounds && grow_limit > 0 && budget > 0 && gaps_ptr->largest > grow_limit; ++g) {
    std::vector<int> moved;
    std::vector<int> regrown;
    const int inserted = grow_towards(mesh, surface, samples, *gaps_ptr, grow_limit, options.grow_step * spacing,
                                      std::min(budget, kMaxInsertionsPerRound), options, vf, locked, moved, regrown);
    if (inserted == 0) break;
    failed.changed(regrown);
    stats.inserted += inserted;
    stats.moves += static_cast<int>(moved.size());
    budget -= inserted;
    gaps_ptr = std::make_unique<Gaps>(mesh, samples, limit);
    move_rounds();
  }
  const Gaps& gaps = *gaps_ptr;
  stats.gap_after = gaps.largest;
  stats.uncovered_after = uncovered(gaps);
  if (options.keep_narrowest_round && gaps.largest > best_gap) {
    mesh.rollback(best ? *best : start);
    stats.gap_after = best_gap;
    stats.uncovered_after = best_uncovered;
    stats.moves = best_moves;
    stats.inserted = best_inserted;
  }
  return stats;
}

}  // namespace heatcvt
