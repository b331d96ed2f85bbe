// Collapse of short edges of slivers.
#include "heatcvt/mesher/sliver_collapse.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <set>

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

  // Tries to collapse edge (a, b) (b into a); returns whether it did.
  bool try_collapse(int a, int b) {
    const Eigen::MatrixX3d& S = mesh.V;
    std::vector<int> shared, others;
    std::set<int> na, nb;
    for (int g : vf[a]) {
      const MeshFace& h = mesh.face(g);
      if (h[0] == b || h[1] == b || h[2] == b) shared.push_back(g);
      for (int v : h)
        if (v != a) na.insert(v);
    }
    for (int g : vf[b]) {
      const MeshFace& h = mesh.face(g);
      if (!(h[0] == a || h[1] == a || h[2] == a)) others.push_back(g);
      for (int v : h)
        if (v != b) nb.insert(v);
    }
    if (shared.size() != 2) return false;
    std::vector<int> common;
    for (int v : na)
      if (v != b && nb.count(v)) common.push_back(v);
    if (common.size() != 2) return false;  // link condition
    if (vf[common[0]].size() < 4 || vf[common[1]].size() < 4 || vf[a].size() + vf[b].size() < 7) return false;
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
    for (int c = 0; c < 3; ++c) {
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
  int run() {
    const double thr = o.sliver_angle_deg * M_PI / 180.0;
    const Eigen::MatrixX3d& S = mesh.V;
    vf = mesh.vertex_faces();
    dead.assign(mesh.num_faces(), 0);
    // Vertices on a boundary are left alone (collapsing an inner edge between two of them would
    // pinch the surface into a non-manifold vertex).
    touched = mesh.boundary_vertices();
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

// Valence-3 vertices of remaining slivers (no flip removes them); undone if that self-intersects.
void remove_sliver_valence3(WorkingMesh& mesh, const SliverCollapseOptions& o, MesherStats& stats) {
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const int flips_before = stats.flipped_edges;
  std::vector<char> in_sliver(mesh.num_vertices(), 0);
  for (const MeshFace& f : mesh.faces())
    if (face_min_angle(mesh, f) < o.sliver_angle_deg * M_PI / 180.0)
      for (int v : f) in_sliver[v] = 1;
  if (remove_valence3(mesh, o.valence3, &in_sliver) > 0) {
    FlipOptions fo = o.flips;
    fo.valence_mode = false;
    stats.flipped_edges += flip_edges(mesh, fo, &in_sliver);
    if (self_intersecting_pairs(mesh) > 0) {
      mesh.rollback(before, true);
      stats.flipped_edges = flips_before;
    }
  }
}

}  // namespace

int collapse_slivers(WorkingMesh& mesh, const SurfaceProjector& surface, const SliverCollapseOptions& options,
                     MesherStats& stats) {
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  FlipOptions fo = options.flips;
  fo.valence_mode = false;
  int collapsed = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    CollapsePass p{mesh, surface, options, {}, {}, {}};
    const int done = p.run();
    if (done == 0) break;
    collapsed += done;
    stats.flipped_edges += flip_edges(mesh, fo);
  }
  if (collapsed > 0 && self_intersecting_pairs(mesh) > 0) {
    mesh.rollback(before, true);
    collapsed = 0;
  }
  remove_sliver_valence3(mesh, options, stats);
  return collapsed;
}

int trim_boundary_slivers(WorkingMesh& mesh, const BoundaryTrimOptions& options) {
  if (!options.enabled) return 0;
  const double sliver = options.sliver_angle_deg * M_PI / 180.0, apex_min = options.min_apex_angle_deg * M_PI / 180.0;
  int removed = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<std::vector<int>> vf = mesh.vertex_faces();
    std::vector<char> drop(mesh.num_faces(), 0), touched(mesh.num_vertices(), 0);
    int dropped = 0;
    for (int id = 0; id < mesh.num_faces(); ++id) {
      const MeshFace& f = mesh.face(id);
      int boundary = 0, k_edge = -1;
      for (int k = 0; k < 3; ++k)
        if (mesh.edge_face_count(f[k], f[(k + 1) % 3]) == 1) ++boundary, k_edge = k;
      if (boundary != 1 || face_min_angle(mesh, f) >= sliver) continue;
      const int a = f[k_edge], b = f[(k_edge + 1) % 3], c = f[(k_edge + 2) % 3];
      const Eigen::Vector3d ca = mesh.V.row(a) - mesh.V.row(c), cb = mesh.V.row(b) - mesh.V.row(c);
      if (!(ca.norm() > 0) || !(cb.norm() > 0) || std::acos(std::clamp(ca.normalized().dot(cb.normalized()), -1.0, 1.0)) < apex_min)
        continue;
      if (touched[a] || touched[b] || touched[c] || vf[a].size() < 2 || vf[b].size() < 2 || vf[c].size() < 2) continue;
      std::vector<int> rest;
      for (int g : vf[c])
        if (g != id) rest.push_back(g);
      if (vertex_fans(mesh, c, rest).size() != 1) continue;
      drop[id] = 1;
      touched[a] = touched[b] = touched[c] = 1;
      ++dropped;
    }
    if (dropped == 0) break;
    removed += mesh.remove_faces(drop);
  }
  return removed;
}

}  // namespace heatcvt
