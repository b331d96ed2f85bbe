// The last repair of slivers: the best of several local edits per sliver.
#include "heatcvt/mesher/sliver_repair.h"

#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/sliver_collapse.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

namespace heatcvt {
namespace {

// A border vertex within this many mean edges of the surface's own border lies on it.
constexpr double kOnBorder = 1e-3;

// A local edit, described before it is made so that it can be scored: faces that go, faces that
// get new corners, at most one vertex that moves (the one a collapse keeps, or a moved corner).
struct Edit {
  std::vector<int> removed;
  std::vector<std::pair<int, MeshFace>> changed;
  int flip_face = -1, flip_k = -1, flip_other = -1;  // a flip: WorkingMesh::flip(f1, k, f2)
  int moved = -1;
  Eigen::Vector3d position, normal;
  int anchor = -1;
  int lost_vertices = 0;
};

// The faces with a smallest angle below sliver_angle_deg, with that angle, smallest first.
std::vector<std::pair<double, int>> slivers_of(const WorkingMesh& mesh, const SliverRepairOptions& o) {
  const double thr = o.sliver_angle_deg * M_PI / 180.0;
  std::vector<std::pair<double, int>> slivers;
  for (int id = 0; id < mesh.num_faces(); ++id) {
    const double m = face_min_angle(mesh, mesh.face(id));
    if (m < thr) slivers.emplace_back(m, id);
  }
  std::sort(slivers.begin(), slivers.end());
  return slivers;
}

class SliverRepair {
 public:
  SliverRepair(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverRepairOptions& o,
               const std::vector<char>& frozen)
      : mesh_(mesh), surface_(surface), o_(o), frozen_(frozen),
        min_cos_(std::cos(o.max_normal_turn_deg * M_PI / 180.0)),
        side_margin_(std::sin(o.side_margin_deg * M_PI / 180.0)) {
    frozen_.resize(mesh.num_vertices(), 0);
    double sum = 0;
    long count = 0;
    for (const MeshFace& f : mesh.faces())
      for (int k = 0; k < 3; ++k, ++count) sum += (mesh.V.row(f[k]) - mesh.V.row(f[(k + 1) % 3])).norm();
    mean_edge_ = count > 0 ? sum / count : 0;
  }

  // One pass; returns the edits made. `vertices`: the vertices in faces, kept at least `floor`.
  int pass(int& vertices, int floor) {
    const std::vector<std::pair<double, int>> slivers = start_pass();
    int done = 0;
    for (const auto& [angle, id] : slivers) {
      const MeshFace f = mesh_.face(id);
      if (dead_[id] || touched_[f[0]] || touched_[f[1]] || touched_[f[2]]) continue;
      const std::vector<int> region = faces_at(f);
      std::vector<std::pair<double, Edit>> edits = improving_edits(id, region, vertices, floor);
      if (edits.empty()) continue;
      std::size_t pick = 0;  // the first best: a later edit only where it scores more than 1e-9 higher
      for (std::size_t i = 1; i < edits.size(); ++i)
        if (edits[i].first > edits[pick].first + 1e-9) pick = i;
      const Edit chosen = std::move(edits[pick].second);
      apply(chosen, region);
      vertices -= chosen.lost_vertices;
      ++done;
    }
    mesh_.remove_faces(dead_);
    return done;
  }

  // One edit that makes no faces cross: for the slivers smallest first, the edits that raise the
  // smallest angle around the sliver, best first, each made and checked against `pairs` (the
  // crossing pairs now, crossing_face_pairs_after()) and undone where it adds a pair. Returns
  // whether an edit was kept (`pairs` then updated).
  bool edit_without_crossing(int& vertices, int floor, std::vector<FacePair>& pairs) {
    for (const auto& [angle, id] : start_pass()) {
      const MeshFace f = mesh_.face(id);
      if (touched_[f[0]] || touched_[f[1]] || touched_[f[2]]) continue;
      const std::vector<int> region = faces_at(f);
      std::vector<std::pair<double, Edit>> ranked = improving_edits(id, region, vertices, floor);
      std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      const std::vector<char> touched = touched_;
      for (const auto& [m, e] : ranked) {
        const WorkingMesh::Checkpoint undo = mesh_.checkpoint();
        apply(e, region);
        mesh_.remove_faces(dead_);
        std::vector<FacePair> after = crossing_face_pairs_after(mesh_, undo, pairs);
        if (after.size() <= pairs.size()) {
          pairs = std::move(after);
          vertices -= e.lost_vertices;
          return true;
        }
        mesh_.rollback(undo);
        dead_.assign(mesh_.num_faces(), 0);
        touched_ = touched;
      }
    }
    return false;
  }

 private:
  WorkingMesh& mesh_;
  const SurfaceProjector& surface_;
  const SliverRepairOptions& o_;
  std::vector<char> frozen_;
  const double min_cos_, side_margin_;
  double mean_edge_ = 0;
  std::vector<std::vector<int>> vf_;
  BorderLinks links_;
  std::vector<char> touched_, dead_;

  // The adjacency of the mesh as it is, no face touched or removed yet, and its slivers.
  std::vector<std::pair<double, int>> start_pass() {
    vf_ = mesh_.vertex_faces();
    links_ = border_links(mesh_);
    touched_ = frozen_;
    dead_.assign(mesh_.num_faces(), 0);
    return slivers_of(mesh_, o_);
  }

  // The candidate edits of sliver `id` that raise the smallest angle of `region` (the faces at
  // its corners) by more than 1e-9 and keep at least `floor` vertices, with that angle after
  // each, in candidate order.
  std::vector<std::pair<double, Edit>> improving_edits(int id, const std::vector<int>& region, int vertices, int floor) {
    const double before = min_angle(region, nullptr);
    std::vector<std::pair<double, Edit>> out;
    for (Edit& e : candidates(id)) {
      if (vertices - e.lost_vertices < floor) continue;
      const double m = min_angle(region, &e);
      if (m > before + 1e-9) out.emplace_back(m, std::move(e));
    }
    return out;
  }

  // The faces at the corners of f (each once, ascending).
  std::vector<int> faces_at(const MeshFace& f) const {
    std::vector<int> out;
    for (int v : f) out.insert(out.end(), vf_[v].begin(), vf_[v].end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  Eigen::Vector3d position(int v, const Edit* e) const {
    return e && v == e->moved ? e->position : Eigen::Vector3d(mesh_.V.row(v).transpose());
  }
  // The surface normal at v after e. A moved vertex takes the normal of the surface at its new
  // place unless that turns by more than max_normal_turn from its normal before: the fitted
  // normals of a scan are unreliable at its border and a move spans a fraction of an edge.
  Eigen::Vector3d normal(int v, const Edit* e) const {
    const Eigen::Vector3d old = mesh_.N.row(v).transpose();
    return e && v == e->moved && e->normal.dot(old) >= min_cos_ ? e->normal : old;
  }

  // Corners of the face with corners h (positions after e) whose surface normal the face's
  // normal u does not face along: u·n <= margin. -1 for a degenerate face.
  int corners_against(const MeshFace& h, const Edit* e, double margin, Eigen::Vector3d& u) const {
    const Eigen::Vector3d p0 = position(h[0], e), p1 = position(h[1], e), p2 = position(h[2], e);
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (!(n.norm() > 0)) return -1;
    u = n.normalized();
    int against = 0;
    for (int v : h) against += !(u.dot(normal(v, e)) > margin);
    return against;
  }

  // Whether the edited face g (corners h) faces within max_normal_turn of each corner's surface
  // normal, or turns by at most max_normal_turn against the face it replaces and faces against
  // no more corner normals than that face did. Scan normals are noisy at borders and depth jumps
  // and may be flipped on a patch, so a face may already face against some of them; a corner
  // within side_margin of the face's plane counts as against before the edit and as along
  // after it, so that a corner normal lying in the plane does not decide.
  bool unfolded(int g, const MeshFace& h, const Edit& e) const {
    Eigen::Vector3d u, m;
    const int against = corners_against(h, &e, -side_margin_, u);
    if (against < 0) return false;
    bool along_surface = true;
    for (int v : h) along_surface = along_surface && u.dot(normal(v, &e)) >= min_cos_;
    if (along_surface) return true;
    const int was_against = corners_against(mesh_.face(g), nullptr, side_margin_, m);
    return was_against >= 0 && against <= was_against && u.dot(m) >= min_cos_;
  }

  // Smallest angle of the faces of `region` after the edit e (before any edit when e is null);
  // −1 when the edit folds one of them.
  double min_angle(const std::vector<int>& region, const Edit* e) const {
    double m = M_PI;
    for (int g : region) {
      if (e && std::find(e->removed.begin(), e->removed.end(), g) != e->removed.end()) continue;
      MeshFace h = mesh_.face(g);
      bool edited = false;
      if (e) {
        for (const auto& [id, corners] : e->changed)
          if (id == g) h = corners, edited = true;
        edited = edited || (e->moved >= 0 && (h[0] == e->moved || h[1] == e->moved || h[2] == e->moved));
      }
      if (edited && !unfolded(g, h, *e)) return -1;
      m = std::min(m, triangle_min_angle(position(h[0], e), position(h[1], e), position(h[2], e)));
    }
    return m;
  }

  bool on_border(int v) const { return links_.on(v); }

  std::vector<Edit> candidates(int id) {
    std::vector<Edit> out;
    const MeshFace f = mesh_.face(id);  // no corner frozen: pass() skips those
    for (int k = 0; k < 3; ++k) add_collapses(f[k], f[(k + 1) % 3], out);
    for (int k = 0; k < 3; ++k) add_flip(id, k, out);
    for (int v : f) add_moves(v, out);
    add_trim(id, out);
    return out;
  }

  // Collapses of (a, b) (collapse_topology()) into the projected midpoint or into one end.
  void add_collapses(int a0, int b0, std::vector<Edit>& out) const {
    EdgeCollapse c;
    if (!collapse_topology(mesh_, vf_, links_, a0, b0, c)) return;
    const int a = c.kept, b = c.gone;
    Edit base;
    base.removed = c.shared;
    for (int g : c.others) {
      MeshFace h = mesh_.face(g);
      for (int& v : h)
        if (v == b) v = a;
      base.changed.emplace_back(g, h);
    }
    base.moved = a;
    base.lost_vertices = 1;
    if (!c.keep_place) {
      Edit e = base;
      e.anchor = mesh_.anchor[a];
      surface_.project(0.5 * (mesh_.V.row(a) + mesh_.V.row(b)).transpose(), e.anchor, e.position, e.normal);
      if (e.position.allFinite() && e.normal.allFinite()) out.push_back(std::move(e));
    }
    for (int end : {a, b}) {
      if (c.keep_place && end == b) continue;
      Edit e = base;
      e.position = mesh_.V.row(end).transpose();
      e.normal = mesh_.N.row(end).transpose();
      e.anchor = mesh_.anchor[end];
      out.push_back(std::move(e));
    }
  }

  // Flip of the edge between corners k and k+1 of face id.
  void add_flip(int id, int k, std::vector<Edit>& out) const {
    const MeshFace& t = mesh_.face(id);
    const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    const int other = mesh_.half_edge_face(b, a);
    if (other < 0 || mesh_.edge_face_count(a, b) != 2) return;
    int d = -1;
    for (int v : mesh_.face(other))
      if (v != a && v != b) d = v;
    if (d < 0 || d == c || frozen_[d] || mesh_.edge_face_count(c, d) > 0 || mesh_.valence(a) <= 3 ||
        mesh_.valence(b) <= 3)
      return;
    const double length = (mesh_.V.row(c) - mesh_.V.row(d)).norm();
    if (!(midpoint_offset(mesh_, surface_, c, d) <= std::max(midpoint_offset(mesh_, surface_, a, b), o_.max_flip_offset * length))) return;
    Edit e;
    e.changed = {{id, MeshFace{c, a, d}}, {other, MeshFace{d, b, c}}};
    e.flip_face = id, e.flip_k = k, e.flip_other = other;
    out.push_back(std::move(e));
  }

  // Moves of an interior vertex v towards the centroid of its neighbours; a border vertex moves
  // along its border only (add_border_moves): where scans overlap, a move across the border can
  // take its projection onto the other scan's layer.
  void add_moves(int v, std::vector<Edit>& out) const {
    if (on_border(v)) {
      add_border_moves(v, out);
      return;
    }
    std::vector<int> ring;
    for (int g : vf_[v])
      for (int u : mesh_.face(g))
        if (u != v) ring.push_back(u);
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    if (ring.empty()) return;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int u : ring) centroid += mesh_.V.row(u).transpose();
    centroid /= static_cast<double>(ring.size());
    const Eigen::Vector3d here = mesh_.V.row(v).transpose();
    for (double step : {1.0, 0.5}) {
      Edit e;
      e.moved = v;
      e.anchor = mesh_.anchor[v];
      surface_.project(here + step * (centroid - here), e.anchor, e.position, e.normal);
      if (e.position.allFinite() && e.normal.allFinite()) out.push_back(std::move(e));
    }
  }

  // Moves of a simple border vertex v along its border chord (prev to next) towards the
  // chord's midpoint, the whole way or half of it, projected to the surface: the border keeps
  // its course and only the spacing of its vertices changes.
  void add_border_moves(int v, std::vector<Edit>& out) const {
    if (!links_.simple(v) || !o_.move_border) return;
    const Eigen::Vector3d here = mesh_.V.row(v).transpose();
    const Eigen::Vector3d a = mesh_.V.row(links_.prev[v]).transpose(), b = mesh_.V.row(links_.next[v]).transpose();
    const Eigen::Vector3d chord = b - a;
    if (!(chord.norm() > 0)) return;
    const Eigen::Vector3d t = chord.normalized();
    const double along = (0.5 * (a + b) - here).dot(t);
    // A vertex on the surface's own border (an input mesh's boundary) stays on it.
    Eigen::Vector3d on, n;
    const bool on_surface_border = surface_.has_border() && surface_.project_to_border(here, on, n) &&
                                   (on - here).norm() <= kOnBorder * mean_edge_;
    for (double step : {1.0, 0.5}) {
      Edit e;
      e.moved = v;
      e.anchor = mesh_.anchor[v];
      const Eigen::Vector3d target = here + step * along * t;
      if (!(on_surface_border && surface_.project_to_border(target, e.position, e.normal)))
        surface_.project(target, e.anchor, e.position, e.normal);
      if (e.position.allFinite() && e.normal.allFinite()) out.push_back(std::move(e));
    }
  }

  // Cutting off a border face: one border edge with an interior apex, or an ear (two border
  // edges, the lone corner leaves the mesh), no higher than max_trim_height mean edges.
  void add_trim(int id, std::vector<Edit>& out) const {
    const MeshFace& f = mesh_.face(id);
    int borders = 0, k_edge = -1;
    for (int k = 0; k < 3; ++k)
      if (mesh_.edge_face_count(f[k], f[(k + 1) % 3]) == 1) ++borders, k_edge = k;
    Edit e;
    e.removed = {id};
    int a, b, c;
    if (borders == 1) {
      a = f[k_edge], b = f[(k_edge + 1) % 3], c = f[(k_edge + 2) % 3];
      if (on_border(c)) return;  // the apex would be left with two fans
    } else if (borders == 2) {
      int k = 0;
      while (k < 3 && vf_[f[k]].size() != 1) ++k;
      if (k == 3) return;
      c = f[k], a = f[(k + 1) % 3], b = f[(k + 2) % 3];
      if (mesh_.edge_face_count(a, b) != 2) return;
      e.lost_vertices = 1;
    } else {
      return;
    }
    if (vf_[a].size() < 2 || vf_[b].size() < 2) return;
    const Eigen::Vector3d pa = mesh_.V.row(a), pb = mesh_.V.row(b), pc = mesh_.V.row(c);
    const double base = (pb - pa).norm();
    if (!(base > 0)) return;
    const double allowed = o_.max_trim_height * mean_edge_;
    if ((pb - pa).cross(pc - pa).norm() / base <= allowed || midpoint_offset(mesh_, surface_, a, b) > allowed)
      out.push_back(std::move(e));
  }

  void apply(const Edit& e, const std::vector<int>& region) {
    if (e.moved >= 0) {
      mesh_.V.row(e.moved) = e.position.transpose();
      mesh_.N.row(e.moved) = normal(e.moved, &e).transpose();
      mesh_.anchor[e.moved] = e.anchor;
    }
    if (e.flip_face >= 0) {
      mesh_.flip(e.flip_face, e.flip_k, e.flip_other);
    } else {
      for (const auto& [g, h] : e.changed) mesh_.replace_face(g, h);
    }
    for (int g : e.removed) dead_[g] = 1;
    for (int g : region)
      for (int v : mesh_.face(g)) touched_[v] = 1;
    for (const auto& [g, h] : e.changed)
      for (int v : h) touched_[v] = 1;
  }
};

}  // namespace

int repair_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverRepairOptions& options,
                   const std::vector<char>& frozen, int min_vertices) {
  SliverRepair repair(mesh, surface, options, frozen);
  int vertices = vertices_in_faces(mesh), edits = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const int done = repair.pass(vertices, min_vertices);
    if (done == 0) break;
    edits += done;
  }
  return edits;
}

int repair_slivers_without_crossings(WorkingMesh& mesh, const SurfaceProjector& surface,
                                     const SliverRepairOptions& options, const std::vector<char>& frozen,
                                     int min_vertices, std::vector<FacePair> pairs) {
  SliverRepair repair(mesh, surface, options, frozen);
  int vertices = vertices_in_faces(mesh), edits = 0;
  const int max_edits = options.passes * static_cast<int>(slivers_of(mesh, options).size());
  while (edits < max_edits && repair.edit_without_crossing(vertices, min_vertices, pairs)) ++edits;
  return edits;
}

}  // namespace heatcvt
