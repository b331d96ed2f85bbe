// Compaction of the working mesh into a TriangleMesh.
#include "heatcvt/mesher/compaction.h"

namespace heatcvt {

TriangleMesh compact_mesh(const WorkingMesh& mesh, int* unused) {
  const int ns = mesh.num_vertices();
  std::vector<char> used(ns, 0);
  for (const MeshFace& f : mesh.faces())
    for (int v : f) used[v] = 1;
  std::vector<int> remap(ns, -1);
  int nv = 0;
  for (int s = 0; s < ns; ++s) remap[s] = used[s] ? nv++ : -1;
  if (unused) *unused = ns - nv;
  TriangleMesh out;
  out.V.resize(nv, 3);
  for (int s = 0; s < ns; ++s)
    if (remap[s] >= 0) out.V.row(remap[s]) = mesh.V.row(s);
  out.F.resize(mesh.num_faces(), 3);
  for (int i = 0; i < mesh.num_faces(); ++i)
    for (int k = 0; k < 3; ++k) out.F(i, k) = remap[mesh.face(i)[k]];
  return out;
}

WorkingMesh working_mesh_of(const TriangleMesh& mesh, const SurfaceProjector& surface) {
  const Eigen::Index nv = mesh.V.rows();
  WorkingMesh work(mesh.V, Eigen::MatrixX3d::Zero(nv, 3), std::vector<int>(nv, -1));
  for (int v = 0; v < work.num_vertices(); ++v) {
    Eigen::Vector3d pos, nrm;
    surface.project(work.V.row(v).transpose(), work.anchor[v], pos, nrm);
    work.N.row(v) = nrm.transpose();
  }
  std::vector<MeshFace> faces(mesh.F.rows());
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) faces[f] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
  work.set_faces(std::move(faces));
  return work;
}

}  // namespace heatcvt
