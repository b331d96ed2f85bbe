#include "heatcvt/subdivision.h"

#include <cmath>
#include <unordered_map>
#include <vector>

namespace heatcvt {

TriangleMesh loop_subdivide(const TriangleMesh& mesh) {
  const int nv = static_cast<int>(mesh.V.rows());
  const int nf = static_cast<int>(mesh.F.rows());
  // Edge table: key (min,max) -> (new vertex index, opposite vertices, face count)
  struct EdgeInfo {
    int index = -1;
    int opposite[2] = {-1, -1};
    int faces = 0;
  };
  std::unordered_map<uint64_t, EdgeInfo> edges;
  edges.reserve(nf * 2);
  auto key = [](int a, int b) { return (uint64_t(std::min(a, b)) << 32) | uint32_t(std::max(a, b)); };
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      EdgeInfo& e = edges[key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))];
      if (e.faces < 2) e.opposite[e.faces] = mesh.F(f, (k + 2) % 3);
      e.faces++;
    }
  // Deterministic numbering of new vertices: in order of first appearance in F.
  int next = nv;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      EdgeInfo& e = edges[key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))];
      if (e.index < 0) e.index = next++;
    }
  TriangleMesh out;
  out.V.resize(next, 3);
  // Neighbours and boundary neighbours of old vertices.
  std::vector<Eigen::Vector3d> ring_sum(nv, Eigen::Vector3d::Zero()), boundary_sum(nv, Eigen::Vector3d::Zero());
  std::vector<int> valence(nv, 0), boundary_count(nv, 0);
  for (const auto& [k, e] : edges) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    ring_sum[a] += mesh.V.row(b).transpose();
    ring_sum[b] += mesh.V.row(a).transpose();
    valence[a]++;
    valence[b]++;
    if (e.faces == 1) {
      boundary_sum[a] += mesh.V.row(b).transpose();
      boundary_sum[b] += mesh.V.row(a).transpose();
      boundary_count[a]++;
      boundary_count[b]++;
    }
    Eigen::Vector3d p;
    if (e.faces == 2)
      p = 0.375 * (mesh.V.row(a) + mesh.V.row(b)).transpose() +
          0.125 * (mesh.V.row(e.opposite[0]) + mesh.V.row(e.opposite[1])).transpose();
    else
      p = 0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose();
    out.V.row(e.index) = p.transpose();
  }
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d x = mesh.V.row(v).transpose();
    if (boundary_count[v] == 2) {
      out.V.row(v) = (0.75 * x + 0.125 * boundary_sum[v]).transpose();
    } else if (boundary_count[v] > 0 || valence[v] == 0) {
      out.V.row(v) = x.transpose();  // non-manifold boundary corner or isolated: keep
    } else {
      const int n = valence[v];
      const double beta = n == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * n);
      out.V.row(v) = ((1 - n * beta) * x + beta * ring_sum[v]).transpose();
    }
  }
  out.F.resize(4 * nf, 3);
  for (int f = 0; f < nf; ++f) {
    const int a = mesh.F(f, 0), b = mesh.F(f, 1), c = mesh.F(f, 2);
    const int ab = edges[key(a, b)].index, bc = edges[key(b, c)].index, ca = edges[key(c, a)].index;
    out.F.row(4 * f + 0) << a, ab, ca;
    out.F.row(4 * f + 1) << b, bc, ab;
    out.F.row(4 * f + 2) << c, ca, bc;
    out.F.row(4 * f + 3) << ab, bc, ca;
  }
  return out;
}

TriangleMesh loop_subdivide_to(const TriangleMesh& mesh, int min_vertices) {
  TriangleMesh m = mesh;
  while (m.V.rows() < min_vertices) m = loop_subdivide(m);
  return m;
}

}  // namespace heatcvt
