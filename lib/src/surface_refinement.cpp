#include "heatcvt/surface_refinement.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Edge {
  int a, b;
  double length2;
};

int third_corner(const MeshFace& f, int a, int b) {
  for (const int v : f)
    if (v != a && v != b) return v;
  return -1;
}

Eigen::Vector3d face_cross(const Eigen::MatrixX3d& V, int a, int b, int c) {
  const Eigen::Vector3d u = (V.row(b) - V.row(a)).transpose(), w = (V.row(c) - V.row(a)).transpose();
  return u.cross(w);
}

// Whether the faces f1 and f2 (−1: none) on an edge lie in one plane: their normals differ by
// less than the flat angle (cos_flat). A border edge is not flat.
bool flat_pair(const WorkingMesh& m, int f1, int f2, double cos_flat) {
  if (f1 < 0 || f2 < 0) return false;
  const MeshFace &g1 = m.face(f1), &g2 = m.face(f2);
  const Eigen::Vector3d n1 = face_cross(m.V, g1[0], g1[1], g1[2]), n2 = face_cross(m.V, g2[0], g2[1], g2[2]);
  const double l1 = n1.norm(), l2 = n2.norm();
  return l1 > 0 && l2 > 0 && n1.dot(n2) >= cos_flat * l1 * l2;
}

bool flat_edge(const WorkingMesh& m, int a, int b, double cos_flat) {
  return m.edge_face_count(a, b) == 2 && flat_pair(m, m.half_edge_face(a, b), m.half_edge_face(b, a), cos_flat);
}

// The edges longer than `length2` (squared) that are on the border or between faces not in one
// plane (`flat` false), or flat interior edges (`flat` true), longest first, ties by vertex index.
std::vector<Edge> long_edges(const WorkingMesh& m, double length2, double cos_flat, bool flat) {
  std::vector<Edge> found;
  for (const MeshFace& f : m.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      // Each interior edge once (from its half-edge a→b with a < b), each border edge once.
      if (a > b && m.has_half_edge(b, a)) continue;
      const double l2 = (m.V.row(a) - m.V.row(b)).squaredNorm();
      if (l2 > length2 && flat_edge(m, a, b, cos_flat) == flat) found.push_back({std::min(a, b), std::max(a, b), l2});
    }
  std::sort(found.begin(), found.end(), [](const Edge& x, const Edge& y) {
    return x.length2 != y.length2 ? x.length2 > y.length2 : x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  return found;
}

// New vertices come from a pool of rows added to the mesh in blocks (appending one row at a time
// copies the vertex arrays each time); `used` counts the rows taken, the rest are dropped at the end.
int new_vertex(WorkingMesh& m, int& used, const Eigen::Vector3d& position) {
  if (used == m.num_vertices()) {
    const Eigen::Index block = std::max<Eigen::Index>(1024, used / 2);
    m.add_vertices(Eigen::MatrixX3d::Zero(block, 3), Eigen::MatrixX3d::Zero(block, 3), std::vector<int>(static_cast<std::size_t>(block), -1));
  }
  m.V.row(used) = position.transpose();
  return used++;
}

// Splits the edge {a, b} at its midpoint (the new vertex `v`, already added); the one or two
// faces on it are halved.
void split_edge(WorkingMesh& m, int a, int b, int v) {
  const int f1 = m.half_edge_face(a, b), f2 = m.half_edge_face(b, a);
  if (f1 >= 0) {
    const int c = third_corner(m.face(f1), a, b);
    m.replace_face(f1, {a, v, c});
    m.add_face({v, b, c});
  }
  if (f2 >= 0) {
    const int d = third_corner(m.face(f2), a, b);
    m.replace_face(f2, {b, v, d});
    m.add_face({v, a, d});
  }
}

// Splits the edges of `edges` at their midpoints, in order, until the mesh has `max_vertices`
// vertices. Edges of one list are distinct, and halving a face keeps the other edges of the list
// edges of the mesh. Returns the splits.
int split_edges(WorkingMesh& m, int& used, const std::vector<Edge>& edges, int max_vertices) {
  int splits = 0;
  for (const Edge& e : edges) {
    if (used >= max_vertices) break;
    split_edge(m, e.a, e.b, new_vertex(m, used, 0.5 * (m.V.row(e.a) + m.V.row(e.b)).transpose()));
    ++splits;
  }
  return splits;
}

// Whether flipping the edge a→b of face f1 = (a, b, c), whose other face is f2 = (b, a, d), to
// c–d keeps the surface and improves the pair: the two faces lie in one plane (normals within
// `cos_flat`, before and after), the quad is convex (both new faces turn the way the old ones
// do), c–d is not already an edge, and the new pair's smallest angle is larger than the old
// pair's. In a plane that is Lawson's max-min angle criterion, whose flips end in the Delaunay
// triangulation; it never makes a face narrower than the pair it replaces.
bool flat_delaunay_flip(const WorkingMesh& m, int a, int b, int c, int d, double cos_flat) {
  const Eigen::MatrixX3d& V = m.V;
  const Eigen::Vector3d n1 = face_cross(V, a, b, c), n2 = face_cross(V, b, a, d);
  const double l1 = n1.norm(), l2 = n2.norm();
  if (l1 == 0 || l2 == 0 || n1.dot(n2) < cos_flat * l1 * l2) return false;
  const Eigen::Vector3d n = n1 / l1 + n2 / l2;
  const Eigen::Vector3d n3 = face_cross(V, c, a, d), n4 = face_cross(V, d, b, c);
  if (n3.dot(n) <= 0 || n4.dot(n) <= 0) return false;
  // The new pair lies in one plane too, so that the new edge is flat and no later step takes
  // it for a bend of the surface.
  if (n3.dot(n4) < cos_flat * n3.norm() * n4.norm()) return false;
  if (c == d || m.edge_face_count(c, d) != 0) return false;
  constexpr double kGain = 1e-9;  // radians: ties (cocircular quads) are not flipped
  return std::min(face_min_angle(m, {c, a, d}), face_min_angle(m, {d, b, c})) >
         std::min(face_min_angle(m, {a, b, c}), face_min_angle(m, {b, a, d})) + kGain;
}

// Lawson's flips restricted to flat pairs of faces, from the edges on `stack` (popped from the
// back): the four outer edges of every flipped pair are tested again; the new diagonals are
// appended to `created` where given. Each flip raises the smallest angle of its pair, so the
// loop ends; `budget` only bounds the work. Returns the flips made.
int flip_from(WorkingMesh& m, std::vector<std::pair<int, int>>& stack, double cos_flat, long& budget,
              std::vector<std::pair<int, int>>* created = nullptr) {
  int flips = 0;
  while (!stack.empty() && budget > 0) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const int f1 = m.half_edge_face(a, b), f2 = m.half_edge_face(b, a);
    if (f1 < 0 || f2 < 0 || m.edge_face_count(a, b) != 2) continue;
    const int c = third_corner(m.face(f1), a, b), d = third_corner(m.face(f2), a, b);
    if (!flat_delaunay_flip(m, a, b, c, d, cos_flat)) continue;
    const MeshFace& g = m.face(f1);
    const int k = g[0] == a ? 0 : g[1] == a ? 1 : 2;
    m.flip(f1, k, f2);
    ++flips, --budget;
    if (created) created->emplace_back(c, d);
    for (const auto& [p, q] : {std::make_pair(a, c), std::make_pair(c, b), std::make_pair(b, d), std::make_pair(d, a)})
      stack.emplace_back(p, q);
  }
  return flips;
}

// flip_from() every edge of the mesh, in face order.
int flip_flat_edges(WorkingMesh& m, double cos_flat, long& budget) {
  std::vector<std::pair<int, int>> stack;
  for (const MeshFace& f : m.faces())
    for (int k = 0; k < 3; ++k)
      if (f[k] < f[(k + 1) % 3] || !m.has_half_edge(f[(k + 1) % 3], f[k])) stack.emplace_back(f[k], f[(k + 1) % 3]);
  std::reverse(stack.begin(), stack.end());
  return flip_from(m, stack, cos_flat, budget);
}

// Delaunay refinement of the flat regions by edge midpoints: the longest flat interior edge
// longer than `length2` (squared) is split and the flips restore the Delaunay property around
// its midpoint, until none is left. Splitting the longest edge of a Delaunay triangulation
// inserts points where the region is emptiest, so the points spread evenly over the region
// instead of lining up along the input's long edges. Stops at `max_vertices` vertices. Returns
// the splits.
int refine_flat_regions(WorkingMesh& m, int& used, int max_vertices, double length2, double cos_flat, long& budget,
                        int& flips) {
  using Entry = std::pair<double, std::pair<int, int>>;  // length², then the edge's ends
  auto longer = [](const Entry& x, const Entry& y) {
    return x.first != y.first ? x.first < y.first : x.second > y.second;
  };
  std::vector<Entry> heap;
  for (const Edge& e : long_edges(m, length2, cos_flat, true)) heap.push_back({e.length2, {e.a, e.b}});
  std::make_heap(heap.begin(), heap.end(), longer);
  auto push = [&](int p, int q) {
    const double l2 = (m.V.row(p) - m.V.row(q)).squaredNorm();
    if (l2 > length2 && flat_edge(m, p, q, cos_flat))
      heap.push_back({l2, {std::min(p, q), std::max(p, q)}}), std::push_heap(heap.begin(), heap.end(), longer);
  };
  int splits = 0;
  std::vector<std::pair<int, int>> stack, created;
  while (!heap.empty() && used < max_vertices) {
    std::pop_heap(heap.begin(), heap.end(), longer);
    const auto [a, b] = heap.back().second;
    heap.pop_back();
    if (!flat_edge(m, a, b, cos_flat)) continue;  // flipped away since
    const int v = new_vertex(m, used, 0.5 * (m.V.row(a) + m.V.row(b)).transpose());
    const int c = third_corner(m.face(m.half_edge_face(a, b)), a, b), d = third_corner(m.face(m.half_edge_face(b, a)), a, b);
    split_edge(m, a, b, v);
    ++splits;
    stack = {{a, c}, {c, b}, {b, d}, {d, a}};
    created.clear();
    flips += flip_from(m, stack, cos_flat, budget, &created);
    for (const int w : {a, b, c, d}) push(v, w);
    for (const auto& [p, q] : created) push(p, q);
  }
  return splits;
}

}  // namespace

SurfaceRefinement refine_surface(const TriangleMesh& mesh, const SurfaceRefinementOptions& options) {
  if (!(options.split_ratio >= 1) || !(options.length_step > 0 && options.length_step < 1) ||
      !(options.flat_angle_deg >= 0 && options.flat_angle_deg < 90) || !(options.target_vertices >= 0) ||
      !(options.max_vertex_factor >= 1))
    throw InvalidInputError("refine_surface: split_ratio >= 1, 0 < length_step < 1, 0 <= flat_angle_deg < 90, "
                            "target_vertices >= 0 and max_vertex_factor >= 1 are required");
  const MeshTopology topology = mesh_topology(mesh.F, static_cast<int>(mesh.V.rows()));
  if (topology.nonmanifold_edges > 0 || topology.inconsistent_edges > 0)
    throw InvalidInputError("refine_surface: the mesh has an edge with more than two faces or is not consistently oriented");
  WorkingMesh m(mesh.V, Eigen::MatrixX3d::Zero(mesh.V.rows(), 3), std::vector<int>(static_cast<std::size_t>(mesh.V.rows()), -1));
  std::vector<MeshFace> faces(static_cast<std::size_t>(mesh.F.rows()));
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) faces[static_cast<std::size_t>(f)] = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
  m.set_faces(std::move(faces));
  const double cos_flat = std::cos(options.flat_angle_deg * kPi / 180);

  SurfaceRefinement out;
  int used = m.num_vertices();
  long budget = 20L * m.num_faces() + 1000;  // flips; grows with the splits below
  out.flips = flip_flat_edges(m, cos_flat, budget);
  if (options.target_vertices > 0) {
    // An equilateral mesh of N vertices (2N faces) on area A has edges of length √(2A / (√3 N)).
    const double area = surface_area(mesh.V, mesh.F);
    double length = std::sqrt(2 * area / (std::sqrt(3.0) * options.target_vertices));
    const int max_vertices = static_cast<int>(
        std::min(2e9, m.num_vertices() + std::ceil(options.max_vertex_factor * options.target_vertices)));
    constexpr int kMaxSteps = 200;  // the length shrinks by length_step each step: far below any need
    for (int step = 0; step < kMaxSteps && length > 0; ++step) {
      const double split2 = options.split_ratio * options.split_ratio * length * length;
      // The edges that carry the shape (border, creases, the bends of a faceted curve) first:
      // no flip can shorten them. Then the flat regions, which they now bound finely. A flip
      // within the flat angle can leave a pair bent by a little more, so both run until neither
      // finds a long edge, at most kPasses times.
      constexpr int kPasses = 4;
      for (int added = 1, pass = 0; added > 0 && pass < kPasses && used < max_vertices; ++pass) {
        added = 0;
        for (std::vector<Edge> edges = long_edges(m, split2, cos_flat, false); !edges.empty() && used < max_vertices;
             edges = long_edges(m, split2, cos_flat, false)) {
          const int split = split_edges(m, used, edges, max_vertices);
          added += split;
          budget += 20L * split;
          out.flips += flip_flat_edges(m, cos_flat, budget);
        }
        budget += 20L * m.num_faces();
        added += refine_flat_regions(m, used, max_vertices, split2, cos_flat, budget, out.flips);
        out.splits += added;
      }
      out.target_edge_length = length;
      if (used >= options.target_vertices || used >= max_vertices) break;
      length *= options.length_step;
    }
  }
  out.mesh.V = m.V.topRows(used);
  out.mesh.F.resize(m.num_faces(), 3);
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) out.mesh.F(f, k) = m.face(f)[k];
  return out;
}

}  // namespace heatcvt
