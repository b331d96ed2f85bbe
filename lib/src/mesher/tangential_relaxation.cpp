// Tangential relaxation of the working mesh.
#include "heatcvt/mesher/tangential_relaxation.h"

#include <Eigen/Geometry>

#include "heatcvt/parallel.h"

namespace heatcvt {

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
  const BorderLinks links = border.slide ? border_links(mesh) : BorderLinks{};
  const double corner = border.corner_turn_deg * M_PI / 180.0;
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (int v = 0; v < ns; ++v) {
    if (!(W[v] > 0) || (fixed && (*fixed)[v])) continue;
    const Eigen::Vector3d x = S.row(v), nv = SN.row(v);
    Eigen::Vector3d d = C.row(v).transpose() / W[v] - x;
    d -= d.dot(nv) * nv;
    if (border.slide && links.on(v)) {
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
    }
  }
}

}  // namespace heatcvt
