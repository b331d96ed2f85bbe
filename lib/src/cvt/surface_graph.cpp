// Edge graph and surface walks shared by the CVT steps. See cvt/surface_graph.h.
#include "heatcvt/cvt/surface_graph.h"

#include <limits>
#include <queue>
#include <utility>

#include "heatcvt/closest_point.h"

namespace heatcvt {

EdgeGraph edge_graph(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  const int n = static_cast<int>(V.rows());
  std::vector<std::vector<int>> adj = vertex_neighbors(n, F);
  EdgeGraph g;
  g.off.assign(n + 1, 0);
  for (int v = 0; v < n; ++v) g.off[v + 1] = g.off[v] + static_cast<int>(adj[v].size());
  g.nbr.resize(g.off[n]);
  g.len.resize(g.off[n]);
  for (int v = 0; v < n; ++v)
    for (size_t k = 0; k < adj[v].size(); ++k) {
      g.nbr[g.off[v] + k] = adj[v][k];
      g.len[g.off[v] + k] = (V.row(v) - V.row(adj[v][k])).norm();
    }
  return g;
}

std::vector<int> graph_voronoi(const EdgeGraph& g, const std::vector<int>& sources) {
  const int n = g.num_vertices();
  std::vector<int> label(n, -1);
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::pair<int, int>>;  // (distance, (source, vertex)): deterministic order
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
  for (size_t s = 0; s < sources.size(); ++s) q.push({0.0, {static_cast<int>(s), sources[s]}});
  while (!q.empty()) {
    const auto [d, sv] = q.top();
    q.pop();
    const int s = sv.first, v = sv.second;
    if (label[v] >= 0) continue;
    label[v] = s;
    dist[v] = d;
    for (int k = g.off[v]; k < g.off[v + 1]; ++k) {
      const int w = g.nbr[k];
      const double nd = d + g.len[k];
      if (label[w] < 0 && nd < dist[w]) {
        dist[w] = nd;
        q.push({nd, {s, w}});
      }
    }
  }
  return label;
}

int nearest_corner(const Eigen::MatrixX3i& F, const SurfacePoint& p) {
  int k = 0;
  p.bary.maxCoeff(&k);
  return F(p.face, k);
}

SurfacePoint vertex_point(const Eigen::MatrixX3i& F, const std::vector<std::vector<int>>& vfaces, int v) {
  SurfacePoint p;
  p.face = vfaces[v].front();
  int k = 0;
  while (F(p.face, k) != v) ++k;
  p.bary = Eigen::Vector3d::Unit(k);
  return p;
}

Eigen::VectorXd lumped_vertex_areas(const Eigen::MatrixX3i& F, const Eigen::VectorXd& face_area, int num_vertices) {
  Eigen::VectorXd vertex_area = Eigen::VectorXd::Zero(num_vertices);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) vertex_area[F(f, k)] += face_area[f] / 3.0;
  return vertex_area;
}

SurfacePoint project_local(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                           const std::vector<std::vector<int>>& vfaces, const SurfacePoint& start,
                           const Eigen::Vector3d& p, int max_steps, double min_gain) {
  auto eval = [&](int f, Eigen::Vector3d& bary) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    bary = closest_point_barycentric(p, a, b, c);
    return (bary[0] * a + bary[1] * b + bary[2] * c - p).squaredNorm();
  };
  SurfacePoint cur = start;
  double best = eval(cur.face, cur.bary);
  for (int step = 0; step < max_steps; ++step) {
    int best_face = -1;
    Eigen::Vector3d best_bary, bary;
    for (int k = 0; k < 3; ++k)
      for (int f : vfaces[F(cur.face, k)]) {
        if (f == cur.face) continue;
        const double d = eval(f, bary);
        if (d < best * (1 - min_gain) && (best_face < 0 || d < eval(best_face, best_bary))) {
          best_face = f;
          best_bary = bary;
        }
      }
    if (best_face < 0) break;
    cur.face = best_face;
    best = eval(best_face, cur.bary);
  }
  return cur;
}

CvtSurface::CvtSurface(const Eigen::MatrixX3d& V_, const Eigen::MatrixX3i& F_, const Eigen::VectorXd& density)
    : V(V_), F(F_), graph(edge_graph(V_, F_)), vfaces(vertex_faces(static_cast<int>(V_.rows()), F_)),
      face_area(face_areas(V_, F_)), vertex_area(lumped_vertex_areas(F_, face_area, static_cast<int>(V_.rows()))),
      face_mass(face_area), vertex_density(density) {
  if (density.size() == 0) return;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    face_mass[f] *= (density[F(f, 0)] + density[F(f, 1)] + density[F(f, 2)]) / 3.0;
}

}  // namespace heatcvt
