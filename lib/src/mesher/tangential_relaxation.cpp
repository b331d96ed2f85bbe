// Tangential relaxation of the working mesh.
#include "heatcvt/mesher/tangential_relaxation.h"

#include <Eigen/Geometry>

#include <algorithm>

#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

// RelaxationBorder::follow_sample_border: the move of the simple border vertex v at x (normal
// nv) to the middle of its border neighbours along their chord and, across it, onto the mean of
// the samples' border points within a radius (its border edges' mean length, at most
// max_radius), by at most half the radius; no move at a corner (a turn of the border above
// `corner` radians); false where no border point is that near.
bool follow_sample_border(const WorkingMesh& mesh, const SurfaceProjector& surface, const BorderLinks& links, int v,
                          double corner, double max_radius, const Eigen::Vector3d& x, const Eigen::Vector3d& nv,
                          Eigen::Vector3d& d) {
  const Eigen::Vector3d p = mesh.V.row(links.prev[v]), q = mesh.V.row(links.next[v]);
  const double radius = std::min(0.5 * ((p - x).norm() + (q - x).norm()), max_radius);
  Eigen::Vector3d edge;
  if (!surface.sample_border_mean(x, radius, edge)) return false;
  if (border_turn(mesh, links, v) > corner) {
    d.setZero();
    return true;
  }
  Eigen::Vector3d along = q - p;
  along -= along.dot(nv) * nv;
  if (!(along.norm() > 0)) return false;  // a border folded back on itself: move like the interior
  along.normalize();
  const Eigen::Vector3d across = nv.cross(along);
  const double c = std::clamp((edge - x).dot(across), -0.5 * radius, 0.5 * radius);
  d = (0.5 * (p + q) - x).dot(along) * along + c * across;
  return true;
}

// Undoes the moves (moved[v]) that leave a face with a corner on the border with a smallest
// angle below both its smallest angle at the old positions (V0) and `floor` radians. The ring
// check of a move sees only whether a face turns over: a triangle bridging two border stretches
// closer than a spacing is narrowed to a sliver when its corners slide along them, and neither
// a flip (not across a border edge) nor the angle polish (a border vertex moves along the
// border only) can widen it again; an interior face narrowed by a step is left to them.
// Undoing a move can spoil a face shared with a kept move, so the sweep repeats until none is
// spoiled (each repeat follows a sweep that undid a move, so it ends).
void undo_spoiling_moves(WorkingMesh& mesh, const BorderLinks& links, const Eigen::MatrixX3d& V0,
                         const Eigen::MatrixX3d& N0, std::vector<char>& moved, double floor) {
  const auto min_angle = [](const Eigen::MatrixX3d& V, const MeshFace& f) {
    return triangle_min_angle(V.row(f[0]).transpose(), V.row(f[1]).transpose(), V.row(f[2]).transpose());
  };
  for (bool undone = true; undone;) {
    undone = false;
    for (const MeshFace& f : mesh.faces()) {
      if (!moved[f[0]] && !moved[f[1]] && !moved[f[2]]) continue;
      if (!links.on(f[0]) && !links.on(f[1]) && !links.on(f[2])) continue;
      if (!(min_angle(mesh.V, f) < std::min(min_angle(V0, f), floor))) continue;
      for (int v : f) {
        if (!moved[v]) continue;
        mesh.V.row(v) = V0.row(v);
        mesh.N.row(v) = N0.row(v);
        moved[v] = 0;
        undone = true;
      }
    }
  }
}

}  // namespace

void tangential_relaxation(WorkingMesh& mesh, const SurfaceProjector& surface, int threads,
                           const RelaxationBorder& border, const std::vector<char>* fixed) {
  const int ns = mesh.num_vertices();
  Eigen::MatrixX3d& S = mesh.V;
  Eigen::MatrixX3d& SN = mesh.N;
  Eigen::MatrixX3d C = Eigen::MatrixX3d::Zero(ns, 3);
  Eigen::VectorXd W = Eigen::VectorXd::Zero(ns);
  for (const MeshFace& f : mesh.faces()) {
    const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d g = (a + b + c) / 3.0;
    for (int v : f) {
      C.row(v) += area * g.transpose();
      W[v] += area;
    }
  }
  Eigen::MatrixX3d S2 = S, SN2 = SN;
  const bool follow = border.follow_sample_border;
  const bool guard = border.spoiled_angle_deg > 0;
  const BorderLinks links = border.slide || follow || guard ? border_links(mesh) : BorderLinks{};
  const double corner = border.corner_turn_deg * M_PI / 180.0;
  // The radius over which the samples' border is averaged is at most the mesh's mean edge length
  // times max_follow_radius: a long border edge (across a gap, along a sparse wire) does not
  // reach border points that belong elsewhere.
  double edge_sum = 0;
  if (follow)
    for (const MeshFace& f : mesh.faces())
      for (int k = 0; k < 3; ++k) edge_sum += (S.row(f[k]) - S.row(f[(k + 1) % 3])).norm();
  const double max_radius =
      mesh.num_faces() > 0 ? border.max_follow_radius * edge_sum / (3.0 * mesh.num_faces()) : 0.0;
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (int v = 0; v < ns; ++v) {
    if (!(W[v] > 0) || (fixed && (*fixed)[v])) continue;
    const Eigen::Vector3d x = S.row(v), nv = SN.row(v);
    Eigen::Vector3d d = C.row(v).transpose() / W[v] - x;
    d -= d.dot(nv) * nv;
    if (follow && links.simple(v) && follow_sample_border(mesh, surface, links, v, corner, max_radius, x, nv, d)) {
      // d follows the samples' border
    } else if (border.slide && links.on(v)) {
      if (!links.simple(v) || border_turn(mesh, links, v) > corner) continue;
      const Eigen::Vector3d p = S.row(links.prev[v]), q = S.row(links.next[v]);
      d = 0.5 * (p + q) - x;
      d -= d.dot(nv) * nv;
    }
    Eigen::Vector3d pos, nrm;
    surface.project(x + d, mesh.anchor[v], pos, nrm);
    S2.row(v) = pos.transpose();
    SN2.row(v) = nrm.transpose();
  }
  const std::vector<std::vector<int>> vf = mesh.vertex_faces();
  const Eigen::MatrixX3d V0 = guard ? S : Eigen::MatrixX3d(), N0 = guard ? SN : Eigen::MatrixX3d();  // for the guard
  std::vector<char> moved(ns, 0);
  for (int v = 0; v < ns; ++v) {
    bool ok = true;
    for (int id : vf[v]) {
      const MeshFace& f = mesh.face(id);
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = (f[k] == v ? S2 : S).row(f[k]).transpose();
      const Eigen::Vector3d fn = (p[1] - p[0]).cross(p[2] - p[0]);
      if (!(fn.dot(SN2.row(v).transpose()) > 0)) ok = false;
    }
    if (ok) {
      S.row(v) = S2.row(v);
      SN.row(v) = SN2.row(v);
      moved[v] = 1;
    }
  }
  if (guard) undo_spoiling_moves(mesh, links, V0, N0, moved, border.spoiled_angle_deg * M_PI / 180.0);
}

}  // namespace heatcvt
