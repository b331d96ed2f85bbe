// Collapse of short edges of slivers.
#include "heatcvt/mesher/sliver_collapse.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <iterator>

#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesh_checks.h"

namespace heatcvt {
namespace {

struct CollapsePass {
  WorkingMesh& mesh;
  const SurfaceProjector& surface;
  const SliverCollapseOptions& o;
  std::vector<std::vector<int>> vf;
  std::vector<char> dead, touched;
  BorderLinks links;

  // Tries to collapse edge (a, b) (collapse_topology()); returns whether it did.
  bool try_collapse(int a0, int b0) {
    EdgeCollapse edge;
    if (!collapse_topology(mesh, vf, links, a0, b0, edge)) return false;
    const int a = edge.kept, b = edge.gone;
    const std::vector<int>& shared = edge.shared;
    const std::vector<int>& others = edge.others;
    const Eigen::MatrixX3d& S = mesh.V;
    // The ring after the collapse: faces of a and b except the two shared ones, b -> a.
    std::vector<int> ring;
    for (int g : vf[a])
      if (std::find(shared.begin(), shared.end(), g) == shared.end()) ring.push_back(g);
    for (int g : others) ring.push_back(g);
    double old_min = M_PI;
    for (int g : vf[a]) old_min = std::min(old_min, face_min_angle(mesh, mesh.face(g)));
    for (int g : others) old_min = std::min(old_min, face_min_angle(mesh, mesh.face(g)));
    Eigen::Vector3d mid_pos, mid_nrm;
    surface.project(0.5 * (S.row(a) + S.row(b)).transpose(), mesh.anchor[a], mid_pos, mid_nrm);
    const Eigen::Vector3d cand_pos[3] = {mid_pos, S.row(a).transpose(), S.row(b).transpose()};
    const Eigen::Vector3d cand_nrm[3] = {mid_nrm, mesh.N.row(a).transpose(), mesh.N.row(b).transpose()};
    const double min_cos = std::cos(o.max_normal_turn_deg * M_PI / 180.0);
    double best_min = old_min;
    int best = -1;
    const bool keep_a = edge.keep_place;
    for (int c = keep_a ? 1 : 0; c < (keep_a ? 2 : 3); ++c) {
      if (!cand_pos[c].allFinite() || !cand_nrm[c].allFinite()) continue;
      double m = M_PI;
      bool ok = true;
      for (int g : ring) {
        const MeshFace& h = mesh.face(g);
        Eigen::Vector3d p[3];
        for (int q = 0; q < 3; ++q) p[q] = (h[q] == a || h[q] == b) ? cand_pos[c] : Eigen::Vector3d(S.row(h[q]));
        const Eigen::Vector3d old_n = (S.row(h[1]) - S.row(h[0])).cross(S.row(h[2]) - S.row(h[0])).transpose();
        const Eigen::Vector3d new_n = (p[1] - p[0]).cross(p[2] - p[0]);
        if (!(new_n.norm() > 0) || !(old_n.norm() > 0) || new_n.normalized().dot(old_n.normalized()) < min_cos) {
          ok = false;
          break;
        }
        m = std::min(m, triangle_min_angle(p[0], p[1], p[2]));
      }
      if (ok && m > best_min + 1e-9) best_min = m, best = c;
    }
    if (best < 0) return false;
    mesh.V.row(a) = cand_pos[best].transpose();
    mesh.N.row(a) = cand_nrm[best].transpose();
    for (int g : shared) dead[g] = 1;
    for (int g : others) {
      MeshFace h = mesh.face(g);
      for (int q = 0; q < 3; ++q)
        if (h[q] == b) h[q] = a;
      mesh.replace_face(g, h);
    }
    for (int g : ring)
      for (int v : mesh.face(g)) touched[v] = 1;
    touched[a] = touched[b] = 1;
    return true;
  }

  // One pass over the faces; returns the collapses done.
  int run(const std::vector<char>& frozen) {
    const double thr = o.sliver_angle_deg * M_PI / 180.0;
    const Eigen::MatrixX3d& S = mesh.V;
    vf = mesh.vertex_faces();
    dead.assign(mesh.num_faces(), 0);
    links = border_links(mesh);
    touched.assign(mesh.num_vertices(), 0);
    // A frozen vertex is treated as touched: no collapse reaches its ring.
    if (!frozen.empty()) touched = frozen;
    int done = 0;
    for (int id = 0; id < mesh.num_faces(); ++id) {
      const MeshFace f = mesh.face(id);
      if (dead[id] || touched[f[0]] || touched[f[1]] || touched[f[2]]) continue;
      if (face_min_angle(mesh, f) >= thr) continue;
      // Edges by increasing length; the first one whose collapse is allowed and helps.
      std::array<int, 3> order = {0, 1, 2};
      std::sort(order.begin(), order.end(), [&](int x, int y) {
        const double lx = (S.row(f[x]) - S.row(f[(x + 1) % 3])).norm(), ly = (S.row(f[y]) - S.row(f[(y + 1) % 3])).norm();
        return lx != ly ? lx < ly : x < y;
      });
      for (int k : order)
        if (try_collapse(f[k], f[(k + 1) % 3])) {
          ++done;
          break;
        }
    }
    if (done > 0) mesh.remove_faces(dead);
    return done;
  }
};

// Face pairs crossing in the state `mesh` had at `saved` (no vertex added since).
long crossing_at(const WorkingMesh& mesh, const WorkingMesh::Checkpoint& saved) {
  WorkingMesh then = mesh;
  then.rollback(saved, true);
  return self_intersecting_pairs(then);
}

// Valence-3 vertices of remaining slivers (no flip removes them); undone if that makes more face
// pairs cross. `crossing`: the pairs crossing in `mesh` (−1 = not counted yet); `frozen`: one
// entry per vertex, or empty.
void remove_sliver_valence3(WorkingMesh& mesh, const SliverCollapseOptions& o, MesherStats& stats, long crossing,
                            const std::vector<char>& frozen) {
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const int flips_before = stats.flipped_edges;
  std::vector<char> in_sliver(mesh.num_vertices(), 0);
  for (const MeshFace& f : mesh.faces())
    if (face_min_angle(mesh, f) < o.sliver_angle_deg * M_PI / 180.0)
      for (int v : f) in_sliver[v] = frozen.empty() || !frozen[v];
  if (remove_valence3(mesh, o.valence3, &in_sliver) > 0) {
    FlipOptions fo = o.flips;
    fo.valence_mode = false;
    stats.flipped_edges += flip_edges(mesh, fo, &in_sliver);
    const long after = self_intersecting_pairs(mesh);
    if (after > 0 && crossing < 0) crossing = crossing_at(mesh, before);
    if (after > 0 && after > crossing) {
      mesh.rollback(before, true);
      stats.flipped_edges = flips_before;
    }
  }
}

// Whether face f, with two border edges, is an ear that can be cut: its lone corner c (on both
// border edges, in no other face) goes, the border moves onto the opposite edge (a, b), which
// needs a and b to keep other faces. Marks the corners touched when it is.
bool removable_ear(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, const MeshFace& f,
                   std::vector<char>& touched) {
  int k = 0;
  while (k < 3 && vf[f[k]].size() != 1) ++k;
  if (k == 3) return false;
  const int c = f[k], a = f[(k + 1) % 3], b = f[(k + 2) % 3];
  if (touched[a] || touched[b] || touched[c] || vf[a].size() < 2 || vf[b].size() < 2 || mesh.edge_face_count(a, b) != 2)
    return false;
  touched[a] = touched[b] = touched[c] = 1;
  return true;
}

// Whether the sliver f, with one border edge, is at a spike of the border: its corner v on that
// edge has only one other face g, whose edge with f goes to an interior vertex, and the surface
// angle at v (over f and g) is below `spike`. Marks both faces to go and their corners touched.
bool cut_spike(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, const std::vector<char>& border,
               int id, double spike, std::vector<char>& drop, std::vector<char>& touched) {
  const MeshFace& f = mesh.face(id);
  for (int k = 0; k < 3; ++k) {
    const int v = f[k];
    if (vf[v].size() != 2) continue;
    const int g = vf[v][0] == id ? vf[v][1] : vf[v][0];
    double angle = 0;
    int inner = -1;
    for (int h : {id, g}) {
      const MeshFace& t = mesh.face(h);
      int q = 0;
      while (t[q] != v) ++q;
      angle += corner_angle(mesh, t, q);
      for (int u : t)
        if (u != v && mesh.edge_face_count(v, u) == 2) inner = u;
    }
    if (inner < 0 || border[inner] || !(angle < spike)) continue;
    bool free = true;
    for (int h : {id, g})
      for (int u : mesh.face(h)) free = free && !touched[u] && (u == v || u == inner || vf[u].size() >= 2);
    if (!free) continue;
    for (int h : {id, g}) {
      drop[h] = 1;
      for (int u : mesh.face(h)) touched[u] = 1;
    }
    return true;
  }
  return false;
}

// The apex of a sliver being cut is on the border: all of its `fans` but the largest are marked
// to go too, unless one of their corners is already touched this pass. Returns whether marked.
bool cut_neck_fans(const WorkingMesh& mesh, const std::vector<std::vector<int>>& fans, std::vector<char>& drop,
                   std::vector<char>& touched) {
  std::size_t keep = 0;
  for (std::size_t i = 1; i < fans.size(); ++i)
    if (fans[i].size() > fans[keep].size()) keep = i;
  for (std::size_t i = 0; i < fans.size(); ++i)
    for (int g : fans[i])
      for (int v : mesh.face(g))
        if (i != keep && touched[v]) return false;
  for (std::size_t i = 0; i < fans.size(); ++i)
    if (i != keep)
      for (int g : fans[i]) {
        drop[g] = 1;
        for (int v : mesh.face(g)) touched[v] = 1;
      }
  return true;
}

}  // namespace

bool collapse_topology(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf, const BorderLinks& links,
                       int a, int b, EdgeCollapse& collapse) {
  const bool border_edge = mesh.edge_face_count(a, b) == 1;
  if (border_edge ? !(links.simple(a) && links.simple(b)) : (links.on(a) && links.on(b))) return false;
  if (links.on(b) && !border_edge) std::swap(a, b);
  std::vector<int> shared, others, na, nb;
  for (int g : vf[a]) {
    const MeshFace& h = mesh.face(g);
    if (h[0] == b || h[1] == b || h[2] == b) shared.push_back(g);
    for (int v : h)
      if (v != a && v != b) na.push_back(v);
  }
  for (int g : vf[b]) {
    const MeshFace& h = mesh.face(g);
    if (!(h[0] == a || h[1] == a || h[2] == a)) others.push_back(g);
    for (int v : h)
      if (v != a && v != b) nb.push_back(v);
  }
  const std::size_t sides = border_edge ? 1 : 2;
  if (shared.size() != sides) return false;
  for (std::vector<int>* n : {&na, &nb}) {
    std::sort(n->begin(), n->end());
    n->erase(std::unique(n->begin(), n->end()), n->end());
  }
  std::vector<int> common;
  std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  if (common.size() != sides) return false;  // link condition
  for (int v : common)
    if (mesh.valence(v) < 4) return false;  // the opposite vertices keep faces enough
  if (vf[a].size() + vf[b].size() < (border_edge ? 4u : 7u)) return false;
  collapse = {a, b, border_edge, links.on(a) && !border_edge, std::move(shared), std::move(others)};
  return true;
}

double midpoint_offset(const WorkingMesh& mesh, const SurfaceProjector& surface, int a, int b) {
  const Eigen::Vector3d mid = 0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose();
  Eigen::Vector3d pos, nrm;
  int hint = mesh.anchor[a];
  surface.project(mid, hint, pos, nrm);
  return pos.allFinite() ? (pos - mid).norm() : std::numeric_limits<double>::infinity();
}

int collapse_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverCollapseOptions& options,
                     MesherStats& stats, const std::vector<char>* frozen) {
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  // One entry per vertex (collapses add none), or empty when nothing is frozen.
  std::vector<char> fixed;
  if (frozen) {
    fixed = *frozen;
    fixed.resize(mesh.num_vertices(), 0);
  }
  std::vector<char> movable;
  FlipOptions fo = options.flips;
  fo.valence_mode = false;
  int collapsed = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    CollapsePass p{mesh, surface, options, {}, {}, {}, {}};
    const int done = p.run(fixed);
    if (done == 0) break;
    collapsed += done;
    // Flips only at vertices with no frozen vertex in their ring (of the faces after the pass).
    movable.assign(mesh.num_vertices(), 1);
    if (!fixed.empty())
      for (const MeshFace& f : mesh.faces())
        if (fixed[f[0]] || fixed[f[1]] || fixed[f[2]]) movable[f[0]] = movable[f[1]] = movable[f[2]] = 0;
    stats.flipped_edges += flip_edges(mesh, fo, fixed.empty() ? nullptr : &movable);
  }
  // Undone when more face pairs cross than in the input (counted only when some cross now).
  long crossing = collapsed > 0 ? self_intersecting_pairs(mesh) : -1;
  if (crossing > 0) {
    const long crossing_before = crossing_at(mesh, before);
    if (crossing > crossing_before) {
      mesh.rollback(before, true);
      collapsed = 0;
      crossing = crossing_before;
    }
  }
  remove_sliver_valence3(mesh, options, stats, crossing, fixed);
  return collapsed;
}

namespace {

// Whether triangle (a, b, c) faces like the normals of its corners.
bool faces_like_corners(const WorkingMesh& mesh, int a, int b, int c) {
  const Eigen::Vector3d n = (mesh.V.row(b) - mesh.V.row(a)).cross(mesh.V.row(c) - mesh.V.row(a)).transpose();
  if (!(n.norm() > 0)) return false;
  for (int v : {a, b, c})
    if (!(n.normalized().dot(mesh.N.row(v).transpose()) > 0)) return false;
  return true;
}

}  // namespace

int flip_sliver_edges(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverFlipOptions& o,
                      const std::vector<char>& frozen) {
  const double thr = o.sliver_angle_deg * M_PI / 180.0;
  int flips = 0;
  for (int f1 = 0; f1 < mesh.num_faces(); ++f1) {
    if (face_min_angle(mesh, mesh.face(f1)) >= thr) continue;
    for (int k = 0; k < 3; ++k) {
      const MeshFace& t = mesh.face(f1);
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const int f2 = mesh.half_edge_face(b, a);
      if (f2 < 0 || frozen[a] || frozen[b] || frozen[c]) continue;
      int d = -1;
      for (int v : mesh.face(f2))
        if (v != a && v != b) d = v;
      if (d < 0 || d == c || frozen[d] || mesh.edge_face_count(c, d) > 0 || mesh.valence(a) <= 3 || mesh.valence(b) <= 3)
        continue;
      const double before = std::min(face_min_angle(mesh, {a, b, c}), face_min_angle(mesh, {b, a, d}));
      const double after = std::min(face_min_angle(mesh, {c, a, d}), face_min_angle(mesh, {d, b, c}));
      if (!(after > before + 1e-9) || !faces_like_corners(mesh, c, a, d) || !faces_like_corners(mesh, d, b, c)) continue;
      const double length = (mesh.V.row(c) - mesh.V.row(d)).norm();
      if (!(midpoint_offset(mesh, surface, c, d) <= std::max(midpoint_offset(mesh, surface, a, b), o.max_offset * length)))
        continue;
      mesh.flip(f1, k, f2);
      ++flips;
      break;  // face f1 changed: move on to the next face
    }
  }
  return flips;
}

int trim_boundary_slivers(WorkingMesh& mesh, const BoundaryTrimOptions& options) {
  if (!options.enabled) return 0;
  const double sliver = options.sliver_angle_deg * M_PI / 180.0, apex_min = options.min_apex_angle_deg * M_PI / 180.0;
  const double spike = options.spike_angle_deg * M_PI / 180.0;
  int removed = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<std::vector<int>> vf = mesh.vertex_faces();
    const std::vector<char> border = mesh.boundary_vertices();
    std::vector<char> drop(mesh.num_faces(), 0), touched(mesh.num_vertices(), 0);
    int dropped = 0;
    for (int id = 0; id < mesh.num_faces(); ++id) {
      const MeshFace& f = mesh.face(id);
      int boundary = 0, k_edge = -1;
      for (int k = 0; k < 3; ++k)
        if (mesh.edge_face_count(f[k], f[(k + 1) % 3]) == 1) ++boundary, k_edge = k;
      if (boundary == 0 || boundary == 3 || face_min_angle(mesh, f) >= sliver) continue;
      if (boundary == 2) {
        if (removable_ear(mesh, vf, f, touched)) drop[id] = 1, ++dropped;
        continue;
      }
      if (cut_spike(mesh, vf, border, id, spike, drop, touched)) {
        dropped += 2;
        continue;
      }
      const int a = f[k_edge], b = f[(k_edge + 1) % 3], c = f[(k_edge + 2) % 3];
      const Eigen::Vector3d ca = mesh.V.row(a) - mesh.V.row(c), cb = mesh.V.row(b) - mesh.V.row(c);
      if (!(ca.norm() > 0) || !(cb.norm() > 0) || std::acos(std::clamp(ca.normalized().dot(cb.normalized()), -1.0, 1.0)) < apex_min)
        continue;
      if (touched[a] || touched[b] || touched[c] || vf[a].size() < 2 || vf[b].size() < 2 || vf[c].size() < 2) continue;
      std::vector<int> rest;
      for (int g : vf[c])
        if (g != id) rest.push_back(g);
      const std::vector<std::vector<int>> fans = vertex_fans(mesh, c, rest);
      if (fans.size() != 1 && !(options.cut_necks && cut_neck_fans(mesh, fans, drop, touched))) continue;
      drop[id] = 1;
      touched[a] = touched[b] = touched[c] = 1;
      ++dropped;
    }
    if (dropped == 0) break;
    removed += mesh.remove_faces(drop);
    // A cut fan may have split a border vertex of its own into two fans.
    removed += make_vertices_manifold(mesh, ManifoldOptions{10, 0});
  }
  return removed;
}

}  // namespace heatcvt
