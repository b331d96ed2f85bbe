#include "heatcvt/mesh.h"

#include "heatcvt/disjoint_sets.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

#include "heatcvt/errors.h"

namespace heatcvt {

Eigen::Vector3d position(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const SurfacePoint& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) x += p.bary[k] * V.row(F(p.face, k)).transpose();
  return x;
}

double mean_edge_length(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  if (F.rows() == 0) return 0.0;
  double sum = 0;
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (V.row(F(f, (k + 1) % 3)) - V.row(F(f, k))).norm();
  return sum / (3.0 * F.rows());
}

Eigen::VectorXd face_areas(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  Eigen::VectorXd A(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    A[f] = 0.5 * (b - a).cross(c - a).norm();
  }
  return A;
}

double surface_area(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) { return face_areas(V, F).sum(); }

Eigen::MatrixX3d vertex_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(V.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);  // length = 2·area: area weighting
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (int i = 0; i < N.rows(); ++i) {
    double len = N.row(i).norm();
    if (len > 0) N.row(i) /= len;
  }
  return N;
}

std::vector<std::vector<int>> vertex_faces(int num_vertices, const Eigen::MatrixX3i& F) {
  std::vector<std::vector<int>> vf(num_vertices);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) vf[F(f, k)].push_back(f);
  return vf;
}

std::vector<std::vector<int>> vertex_neighbors(int num_vertices, const Eigen::MatrixX3i& F) {
  std::vector<std::vector<int>> nb(num_vertices);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      int a = F(f, k), b = F(f, (k + 1) % 3);
      nb[a].push_back(b);
      nb[b].push_back(a);
    }
  for (auto& n : nb) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return nb;
}

std::vector<std::pair<int, int>> boundary_edges(const Eigen::MatrixX3i& F) {
  // Every face's edges as (smaller, larger) pairs, sorted: an edge of one face occurs once.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<std::size_t>(3 * F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) edges.push_back(std::minmax(F(f, k), F(f, (k + 1) % 3)));
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<int, int>> border;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) border.push_back(edges[i]);
    i = j;
  }
  return border;
}

namespace {

// Loop labels (boundary_loop_labels()) of the border edges `border`; returns the number of loops.
int label_loops(int num_vertices, const std::vector<std::pair<int, int>>& border, Eigen::VectorXi& loop) {
  DisjointSets sets(num_vertices);
  std::vector<char> on(static_cast<std::size_t>(num_vertices), 0);
  for (const auto& [a, b] : border) {
    sets.unite(a, b);
    on[static_cast<std::size_t>(a)] = on[static_cast<std::size_t>(b)] = 1;
  }
  loop.setConstant(num_vertices, -1);
  std::vector<int> id(static_cast<std::size_t>(num_vertices), -1);
  int count = 0;
  for (int v = 0; v < num_vertices; ++v) {
    if (!on[static_cast<std::size_t>(v)]) continue;
    int& r = id[static_cast<std::size_t>(sets.find(v))];
    if (r < 0) r = count++;
    loop[v] = r;
  }
  return count;
}

}  // namespace

int boundary_loop_labels(int num_vertices, const Eigen::MatrixX3i& F, Eigen::VectorXi& loop) {
  return label_loops(num_vertices, boundary_edges(F), loop);
}

int connected_components(int num_vertices, const Eigen::MatrixX3i& F, Eigen::VectorXi& component) {
  DisjointSets sets(num_vertices);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 1; k < 3; ++k) sets.unite(F(f, 0), F(f, k));
  component.resize(num_vertices);
  std::vector<int> id(num_vertices, -1);
  int count = 0;
  for (int v = 0; v < num_vertices; ++v) {
    const int r = sets.find(v);
    if (id[r] < 0) id[r] = count++;
    component[v] = id[r];
  }
  return count;
}

MeshTopology mesh_topology(const Eigen::MatrixX3i& F, int num_vertices) {
  MeshTopology t;
  t.faces = static_cast<int>(F.rows());
  // directed edge counts per undirected edge
  std::unordered_map<uint64_t, std::pair<int, int>> edges;  // key(min,max) -> (#a->b, #b->a)
  edges.reserve(F.rows() * 2);
  std::vector<char> used(num_vertices, 0);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      int a = F(f, k), b = F(f, (k + 1) % 3);
      used[a] = 1;
      uint64_t key = (uint64_t(std::min(a, b)) << 32) | uint32_t(std::max(a, b));
      auto& e = edges[key];
      (a < b ? e.first : e.second)++;
    }
  t.vertices = static_cast<int>(std::count(used.begin(), used.end(), 1));
  t.edges = static_cast<int>(edges.size());
  std::vector<std::pair<int, int>> border;
  for (const auto& [key, e] : edges) {
    int n = e.first + e.second;
    if (n == 1) border.emplace_back(static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu));
    if (n == 1) t.boundary_edges++;
    else if (n > 2) t.nonmanifold_edges++;
    else if (e.first != 1) t.inconsistent_edges++;
  }
  Eigen::VectorXi comp;
  int total = connected_components(num_vertices, F, comp);
  // isolated (unreferenced) vertices form their own components: do not count them
  std::vector<char> seen(total, 0);
  for (int v = 0; v < num_vertices; ++v)
    if (used[v]) seen[comp[v]] = 1;
  t.components = static_cast<int>(std::count(seen.begin(), seen.end(), 1));
  if (!border.empty()) {
    Eigen::VectorXi loop;
    t.boundary_loops = label_loops(num_vertices, border, loop);
  }
  return t;
}

void validate_mesh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const std::string& what) {
  if (V.rows() == 0) throw InvalidInputError(what + ": no vertices");
  if (F.rows() == 0) throw InvalidInputError(what + ": no faces");
  for (int i = 0; i < V.rows(); ++i)
    if (!V.row(i).allFinite())
      throw InvalidInputError(what + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= V.rows())
        throw InvalidInputError(what + ": face " + std::to_string(f) + " references vertex " +
                                std::to_string(F(f, k)) + " but there are only " +
                                std::to_string(V.rows()) + " vertices");
  bool any_area = false;
  for (int f = 0; f < F.rows() && !any_area; ++f) {
    const Eigen::Vector3d e1 = (V.row(F(f, 1)) - V.row(F(f, 0))).transpose(), e2 = (V.row(F(f, 2)) - V.row(F(f, 0))).transpose();
    any_area = e1.cross(e2).squaredNorm() > 0;
  }
  if (!any_area)
    throw InvalidInputError(what + ": every face has zero area (the vertices are coincident or collinear)");
}

}  // namespace heatcvt
