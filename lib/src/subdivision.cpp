#include "heatcvt/subdivision.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace heatcvt {

namespace {

// One edge of the mesh being subdivided: its new vertex, the corners opposite to it in (up to
// two of) its faces, and the number of faces.
struct EdgeInfo {
  int index = -1;
  int opposite[2] = {-1, -1};
  int faces = 0;
};

struct EdgeTable {
  std::unordered_map<std::uint64_t, EdgeInfo> edges;
  int num_vertices = 0;  // old vertices + one per edge
  static std::uint64_t key(int a, int b) {
    return (std::uint64_t(std::min(a, b)) << 32) | std::uint32_t(std::max(a, b));
  }
  const EdgeInfo& at(int a, int b) const { return edges.at(key(a, b)); }
};

// Edges of the mesh with their new vertices numbered after the old ones, in order of first
// appearance in F (deterministic).
EdgeTable edge_table(const TriangleMesh& mesh) {
  EdgeTable t;
  const int nf = static_cast<int>(mesh.F.rows());
  t.edges.reserve(static_cast<std::size_t>(nf) * 2);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      EdgeInfo& e = t.edges[EdgeTable::key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))];
      if (e.faces < 2) e.opposite[e.faces] = mesh.F(f, (k + 2) % 3);
      e.faces++;
    }
  t.num_vertices = static_cast<int>(mesh.V.rows());
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      EdgeInfo& e = t.edges[EdgeTable::key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))];
      if (e.index < 0) e.index = t.num_vertices++;
    }
  return t;
}

// The four children of every face, numbered as documented in subdivision.h.
Eigen::MatrixX3i split_faces(const Eigen::MatrixX3i& F, const EdgeTable& t) {
  const Eigen::Index nf = F.rows();
  Eigen::MatrixX3i out(4 * nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    const int ab = t.at(a, b).index, bc = t.at(b, c).index, ca = t.at(c, a).index;
    out.row(4 * f + 0) << a, ab, ca;
    out.row(4 * f + 1) << b, bc, ab;
    out.row(4 * f + 2) << c, ca, bc;
    out.row(4 * f + 3) << ab, bc, ca;
  }
  return out;
}

}  // namespace

TriangleMesh loop_subdivide(const TriangleMesh& mesh) {
  const int nv = static_cast<int>(mesh.V.rows());
  const EdgeTable table = edge_table(mesh);
  const auto& edges = table.edges;
  TriangleMesh out;
  out.V.resize(table.num_vertices, 3);
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
  out.F = split_faces(mesh.F, table);
  return out;
}

TriangleMesh loop_subdivide_to(const TriangleMesh& mesh, int min_vertices) {
  TriangleMesh m = mesh;
  while (m.V.rows() < min_vertices) m = loop_subdivide(m);
  return m;
}

TriangleMesh midpoint_subdivide(const TriangleMesh& mesh) {
  const EdgeTable table = edge_table(mesh);
  TriangleMesh out;
  out.V.resize(table.num_vertices, 3);
  out.V.topRows(mesh.V.rows()) = mesh.V;
  for (const auto& [k, e] : table.edges) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    out.V.row(e.index) = 0.5 * (mesh.V.row(a) + mesh.V.row(b));
  }
  out.F = split_faces(mesh.F, table);
  return out;
}

SurfacePoint subdivision_parent(const SurfacePoint& p) {
  // Barycentric coordinates (in the parent face a, b, c) of the corners of child face k.
  static const double corners[4][3][3] = {
      {{1, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}},   // (a, ab, ca)
      {{0, 1, 0}, {0, 0.5, 0.5}, {0.5, 0.5, 0}},   // (b, bc, ab)
      {{0, 0, 1}, {0.5, 0, 0.5}, {0, 0.5, 0.5}},   // (c, ca, bc)
      {{0.5, 0.5, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5}}};  // (ab, bc, ca)
  SurfacePoint out;
  out.face = p.face / 4;
  const int child = p.face % 4;
  out.bary.setZero();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j) out.bary[j] += p.bary[k] * corners[child][k][j];
  return out;
}

}  // namespace heatcvt
