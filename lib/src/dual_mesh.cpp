#include "heatcvt/dual_mesh.h"

#include <algorithm>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_set>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace {

double min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  auto angle = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    const Eigen::Vector3d u = q - p, v = r - p;
    const double nu = u.norm(), nv = v.norm();
    if (!(nu > 0) || !(nv > 0)) return 0.0;
    return std::atan2(u.cross(v).norm(), u.dot(v));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

struct TripleHash {
  size_t operator()(const std::array<int, 3>& t) const {
    return (static_cast<size_t>(t[0]) * 73856093u) ^ (static_cast<size_t>(t[1]) * 19349663u) ^
           (static_cast<size_t>(t[2]) * 83492791u);
  }
};

// The refined faces around refined vertex v (incidence `faces`) in fan order. The walk goes
// through shared link vertices without assuming a consistent orientation (so that non-orientable
// surfaces such as the Klein bottle work): its direction is the orientation of the start face, and
// faces traversed against it are flagged in `backward`. On a consistently oriented fan this is the
// counter-clockwise order: face (v, a, b) is followed by the face (v, b, c). Start: a face whose
// "a" is a free end of the link (boundary), else any face with a free end, else the first one.
// Faces the walk misses (non-manifold spot) are appended so every cell is considered.
struct FanWalk {
  std::vector<int> ring;
  std::vector<char> backward;
  bool closed_cycle = false;  // manifold, no boundary, every face reached
};

FanWalk walk_fan(const VoronoiDiagram& d, int v, const std::vector<int>& faces) {
  std::vector<std::array<int, 3>> fan;  // (face, next vertex after v, previous vertex)
  for (int r : faces) {
    int k = 0;
    while (d.F(r, k) != v) ++k;
    fan.push_back({r, d.F(r, (k + 1) % 3), d.F(r, (k + 2) % 3)});
  }
  bool manifold = true, has_boundary = false;
  int start = 0, start_entry = fan[0][1];
  auto count = [&](int x) {
    int c = 0;
    for (const auto& e : fan) c += (e[1] == x) + (e[2] == x);
    return c;
  };
  int free_b = -1;
  for (size_t i = 0; i < fan.size(); ++i) {
    const int ca = count(fan[i][1]), cb = count(fan[i][2]);
    if (ca > 2 || cb > 2) manifold = false;
    if (ca == 1 && !has_boundary) start = static_cast<int>(i), start_entry = fan[i][1], has_boundary = true;
    if (cb == 1 && free_b < 0) free_b = static_cast<int>(i);
  }
  if (!has_boundary && free_b >= 0) start = free_b, start_entry = fan[free_b][2], has_boundary = true;
  FanWalk w;
  std::vector<char> used(fan.size(), 0);
  int cur = start, entry = start_entry;
  while (cur >= 0 && !used[cur]) {
    used[cur] = 1;
    w.ring.push_back(fan[cur][0]);
    const bool forward = fan[cur][1] == entry;
    w.backward.push_back(forward ? 0 : 1);
    const int exit = forward ? fan[cur][2] : fan[cur][1];
    int next = -1;
    for (size_t j = 0; j < fan.size(); ++j)
      if (!used[j] && (fan[j][1] == exit || fan[j][2] == exit)) {
        next = static_cast<int>(j);
        break;
      }
    cur = next;
    entry = exit;
  }
  w.closed_cycle = manifold && !has_boundary && w.ring.size() == fan.size();
  for (size_t j = 0; j < fan.size(); ++j)
    if (!used[j]) {
      w.ring.push_back(fan[j][0]);
      w.backward.push_back(0);
    }
  return w;
}

// Apex of the fan over the cyclic cells `cyc` that maximises the fan's smallest angle (site
// positions P); the first cell with best_fan off or k = 3.
int fan_apex(const std::vector<int>& cyc, const Eigen::MatrixX3d& P, bool best_fan) {
  const int k = static_cast<int>(cyc.size());
  int apex = 0;
  if (k <= 3 || !best_fan) return apex;
  double best = -1;
  for (int a = 0; a < k; ++a) {
    double worst = std::numeric_limits<double>::infinity();
    for (int i = 1; i + 1 < k; ++i) {
      const int x = cyc[a], y = cyc[(a + i) % k], z = cyc[(a + i + 1) % k];
      worst = std::min(worst, min_angle(P.row(x), P.row(y), P.row(z)));
    }
    if (worst > best) best = worst, apex = a;
  }
  return apex;
}

}  // namespace

DualMesh dual_mesh(const VoronoiDiagram& d, const Eigen::MatrixX3d& sites, const DualMeshOptions& options) {
  const int nc = d.num_cells();
  if (sites.rows() < nc)
    throw InvalidInputError("dual_mesh: " + std::to_string(sites.rows()) + " site positions for " +
                            std::to_string(nc) + " cells");
  const int nrv = static_cast<int>(d.V.rows());
  DualMesh out;
  out.V = sites.topRows(nc);

  std::vector<int> off, inc;
  refined_vertex_faces(d, off, inc);

  std::vector<std::array<int, 3>> tris;
  std::vector<int> source;
  std::unordered_set<std::array<int, 3>, TripleHash> seen;
  std::vector<int> cyc, distinct, faces;
  for (int v = 0; v < nrv; ++v) {
    const int deg = off[v + 1] - off[v];
    if (deg < 3) continue;
    distinct.clear();
    for (int i = off[v]; i < off[v + 1]; ++i)
      if (d.face_cell[inc[i]] >= 0) distinct.push_back(d.face_cell[inc[i]]);
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
    if (distinct.size() < 3) continue;
    ++out.voronoi_vertices;

    faces.assign(inc.begin() + off[v], inc.begin() + off[v + 1]);
    const FanWalk w = walk_fan(d, v, faces);
    if (!w.closed_cycle) ++out.open_fans;
    const std::vector<int>& ring = w.ring;
    const std::vector<char>& backward_face = w.backward;
    const bool closed_cycle = w.closed_cycle;
    // cyclic sequence of cells, consecutive repeats collapsed, unreached faces skipped
    cyc.clear();
    for (int r : ring) {
      const int c = d.face_cell[r];
      if (c < 0) continue;
      if (cyc.empty() || cyc.back() != c) cyc.push_back(c);
    }
    if (closed_cycle)
      while (cyc.size() > 1 && cyc.front() == cyc.back()) cyc.pop_back();
    if (cyc.size() != distinct.size()) ++out.repeated_cell_vertices;
    if (cyc.size() < 3) continue;
    const int k = static_cast<int>(cyc.size());
    if (k > 3) ++out.split_vertices;
    const int apex = fan_apex(cyc, out.V, options.best_fan);
    // reference normal: the refined faces around v, oriented like the walk (= like the input on
    // an oriented surface)
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < ring.size(); ++i) {
      const int r = ring[i];
      const Eigen::Vector3d p0 = d.V.row(d.F(r, 0)), p1 = d.V.row(d.F(r, 1)), p2 = d.V.row(d.F(r, 2));
      normal += (backward_face[i] ? -1.0 : 1.0) * (p1 - p0).cross(p2 - p0);
    }
    for (int i = 1; i + 1 < k; ++i) {
      std::array<int, 3> t = {cyc[apex], cyc[(apex + i) % k], cyc[(apex + i + 1) % k]};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
      // canonical rotation (smallest first) keeps orientation; identical triples are emitted once
      std::array<int, 3> key = t;
      std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
      if (!seen.insert(key).second) {
        ++out.duplicate_triangles;
        continue;
      }
      const Eigen::Vector3d a = out.V.row(t[0]), b = out.V.row(t[1]), c = out.V.row(t[2]);
      if ((b - a).cross(c - a).dot(normal) < 0) ++out.flipped_against_input;
      tris.push_back(t);
      source.push_back(v);
    }
  }
  out.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  out.face_source.resize(static_cast<Eigen::Index>(tris.size()));
  std::vector<char> used_site(nc, 0);
  for (size_t i = 0; i < tris.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      out.F(static_cast<Eigen::Index>(i), k) = tris[i][k];
      used_site[tris[i][k]] = 1;
    }
    out.face_source[static_cast<Eigen::Index>(i)] = source[i];
  }
  for (int s = 0; s < nc; ++s)
    if (!used_site[s]) out.unused_sites.push_back(s);
  return out;
}

Eigen::VectorXd smallest_angles(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  Eigen::VectorXd a(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) a[f] = min_angle(V.row(F(f, 0)), V.row(F(f, 1)), V.row(F(f, 2)));
  return a;
}

TriangleQuality triangle_quality(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  TriangleQuality q;
  q.triangles = static_cast<int>(F.rows());
  if (F.rows() == 0) return q;
  const Eigen::VectorXd a = smallest_angles(V, F) * (180.0 / M_PI);
  q.min_angle_deg = a.minCoeff();
  q.mean_min_angle_deg = a.mean();
  q.below_30_fraction = static_cast<double>((a.array() < 30.0).count()) / static_cast<double>(a.size());
  std::vector<std::array<int, 2>> edges;
  edges.reserve(3 * F.rows());
  auto edge = [&](Eigen::Index f, int k) {
    const int u = F(f, k), v = F(f, (k + 1) % 3);
    return std::array<int, 2>{std::min(u, v), std::max(u, v)};
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) edges.push_back(edge(f, k));
  std::sort(edges.begin(), edges.end());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto range = std::equal_range(edges.begin(), edges.end(), edge(f, k));
      if (range.second - range.first != 1) continue;
      q.boundary_min_angle_deg = std::min(q.boundary_min_angle_deg, a[f]);
      ++q.boundary_triangles;
      break;
    }
  return q;
}

}  // namespace heatcvt
