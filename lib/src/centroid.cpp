// Heat centroids (paper §5) and the sub-vertex refinement of §7.1 ("Centroids on faces").
#include "heatcvt/centroid.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

// Barycentric coordinates of x in the 2D triangle (a, b, c); false when degenerate.
bool bary2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& x,
            Eigen::Vector3d& out) {
  const Eigen::Vector2d e1 = b - a, e2 = c - a, q = x - a;
  const double det = e1.x() * e2.y() - e1.y() * e2.x();
  if (!(std::abs(det) > 0)) return false;
  const double l1 = (q.x() * e2.y() - q.y() * e2.x()) / det;
  const double l2 = (e1.x() * q.y() - e1.y() * q.x()) / det;
  out = Eigen::Vector3d(1.0 - l1 - l2, l1, l2);
  return out.allFinite();
}

// Closest point of x on the segment a–b: parameter in [0, 1].
double segment_param(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
  const Eigen::Vector2d e = b - a;
  const double l2 = e.squaredNorm();
  if (!(l2 > 0)) return 0.0;
  return std::clamp((x - a).dot(e) / l2, 0.0, 1.0);
}

// Area-weighted normal of the faces around v with their orientations made consistent across the
// shared edges (v, w), like the first face. Returns false (and leaves n untouched) when the faces
// were already consistently oriented: then the caller's vertex normal is right. On a
// non-orientable surface (Klein bottle) the global orientation flips somewhere, and there the
// area-weighted vertex normal of vertex_normals() mixes opposite face normals (it can even vanish
// or lie in the tangent plane), so the tangent frame must come from the locally oriented fan.
bool locally_oriented_normal(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const std::vector<int>& faces,
                             int v, Eigen::Vector3d& n) {
  const size_t m = faces.size();
  std::vector<int> a(m), b(m), sign(m, 0);
  for (size_t i = 0; i < m; ++i) {
    int k = 0;
    while (F(faces[i], k) != v) ++k;
    a[i] = F(faces[i], (k + 1) % 3);
    b[i] = F(faces[i], (k + 2) % 3);
  }
  bool flipped = false;
  std::vector<size_t> stack = {0};
  sign[0] = 1;
  while (!stack.empty()) {
    const size_t i = stack.back();
    stack.pop_back();
    for (size_t j = 0; j < m; ++j) {
      if (sign[j] != 0) continue;
      int s = 0;
      if (a[i] == b[j] || b[i] == a[j]) s = sign[i];        // edge traversed in opposite directions
      else if (a[i] == a[j] || b[i] == b[j]) s = -sign[i];  // same direction: one of them is flipped
      if (s == 0) continue;
      sign[j] = s;
      flipped |= s < 0;
      stack.push_back(j);
    }
  }
  if (!flipped) return false;
  n.setZero();
  for (size_t i = 0; i < m; ++i) {
    const Eigen::Vector3d p0 = V.row(F(faces[i], 0)), p1 = V.row(F(faces[i], 1)), p2 = V.row(F(faces[i], 2));
    n += (sign[i] < 0 ? -1.0 : 1.0) * (p1 - p0).cross(p2 - p0);
  }
  return true;
}

void check_heat_inputs(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatSolver& solver,
                       const char* what) {
  validate_mesh(V, F, std::string(what) + ": mesh");
  if (solver.num_vertices() != V.rows())
    throw InvalidInputError(std::string(what) + ": the solver has " + std::to_string(solver.num_vertices()) +
                            " vertices but the mesh has " + std::to_string(V.rows()));
}

}  // namespace

SurfacePoint refine_hottest_vertex(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                   const std::vector<std::vector<int>>& vertex_faces,
                                   const Eigen::MatrixX3d& vertex_normals, const Eigen::VectorXd& heat,
                                   int hottest_vertex) {
  const int v = hottest_vertex;
  if (v < 0 || v >= V.rows() || v >= static_cast<int>(vertex_faces.size()))
    throw InvalidInputError("refine_hottest_vertex: vertex " + std::to_string(v) + " out of range");
  if (heat.size() != V.rows())
    throw InvalidInputError("refine_hottest_vertex: heat has " + std::to_string(heat.size()) +
                            " entries but the mesh has " + std::to_string(V.rows()) + " vertices");
  const std::vector<int>& faces = vertex_faces[v];
  if (faces.empty()) throw InvalidInputError("refine_hottest_vertex: vertex " + std::to_string(v) + " has no faces");
  const SurfacePoint fallback = vertex_point(F, vertex_faces, v);

  // tangent frame of the area-weighted normal (of the locally oriented fan on non-orientable surfaces)
  Eigen::Vector3d n = vertex_normals.row(v).transpose();
  locally_oriented_normal(V, F, faces, v, n);
  if (!(n.norm() > 0) || !n.allFinite()) return fallback;
  n.normalize();
  // first tangent axis from a coordinate axis not nearly parallel to n (any such axis works)
  Eigen::Vector3d e1 = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (e1 - e1.dot(n) * n).normalized();
  const Eigen::Vector3d e2 = n.cross(e1);
  const Eigen::Vector3d o = V.row(v).transpose();

  // the one-ring (vertices of the incident faces, v included)
  std::vector<int> ring;
  for (int f : faces)
    for (int k = 0; k < 3; ++k) ring.push_back(F(f, k));
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  if (ring.size() < 6) return fallback;
  double scale = 0;
  for (int w : ring) scale = std::max(scale, (V.row(w).transpose() - o).norm());
  if (!(scale > 0)) return fallback;

  auto project = [&](int w) {
    const Eigen::Vector3d q = (V.row(w).transpose() - o) / scale;
    return Eigen::Vector2d(q.dot(e1), q.dot(e2));
  };
  Eigen::MatrixXd A(ring.size(), 6);
  Eigen::VectorXd b(ring.size());
  for (size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d x = project(ring[i]);
    A.row(i) << 1, x.x(), x.y(), x.x() * x.x(), x.x() * x.y(), x.y() * x.y();
    b[i] = heat[ring[i]];
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < 6) return fallback;
  const Eigen::VectorXd c = qr.solve(b);
  if (!c.allFinite()) return fallback;
  // h = c0 + c1 x + c2 y + c3 x² + c4 xy + c5 y²; Hessian [[2c3, c4], [c4, 2c5]]
  Eigen::Matrix2d H;
  H << 2 * c[3], c[4], c[4], 2 * c[5];
  if (!(H(0, 0) < 0) || !(H.determinant() > 0)) return fallback;
  const Eigen::Vector2d z = H.ldlt().solve(-Eigen::Vector2d(c[1], c[2]));
  if (!z.allFinite()) return fallback;

  // locate z in the projected incident faces, else take the closest point on them
  double best_d = std::numeric_limits<double>::infinity();
  SurfacePoint best = fallback;
  for (int f : faces) {
    const Eigen::Vector2d p0 = project(F(f, 0)), p1 = project(F(f, 1)), p2 = project(F(f, 2));
    Eigen::Vector3d l;
    if (bary2d(p0, p1, p2, z, l) && l.minCoeff() >= 0) {
      SurfacePoint p;
      p.face = f;
      p.bary = l / l.sum();
      return p;
    }
    // closest point on the triangle's boundary
    const Eigen::Vector2d P[3] = {p0, p1, p2};
    for (int k = 0; k < 3; ++k) {
      const double s = segment_param(P[k], P[(k + 1) % 3], z);
      const Eigen::Vector2d q = (1 - s) * P[k] + s * P[(k + 1) % 3];
      const double dist = (q - z).norm();
      if (dist < best_d) {
        best_d = dist;
        best.face = f;
        best.bary = Eigen::Vector3d::Zero();
        best.bary[k] = 1 - s;
        best.bary[(k + 1) % 3] = s;
      }
    }
  }
  return best;
}

std::vector<SurfacePoint> heat_centroids(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                         const HeatSolver& solver, const VoronoiDiagram& diagram,
                                         const CentroidOptions& options) {
  check_heat_inputs(V, F, solver, "heat_centroids");
  if (options.steps < 1) throw InvalidInputError("heat_centroids: steps must be >= 1");
  if (diagram.face_parent.size() != diagram.F.rows() || diagram.face_cell.size() != diagram.F.rows())
    throw InvalidInputError("heat_centroids: inconsistent diagram");
  if (diagram.F.rows() > 0 && diagram.face_parent.maxCoeff() >= F.rows())
    throw InvalidInputError("heat_centroids: the diagram does not belong to this mesh (parent face out of range)");
  const int nv = static_cast<int>(V.rows()), nc = diagram.num_cells();
  const auto loads = cell_load_vectors(diagram, F);
  // candidate vertices: vertices of the cells' parent faces
  std::vector<std::vector<int>> cand(nc);
  for (int r = 0; r < diagram.F.rows(); ++r) {
    const int c = diagram.face_cell[r];
    if (c < 0 || c >= nc) continue;
    for (int k = 0; k < 3; ++k) cand[c].push_back(F(diagram.face_parent[r], k));
  }
  for (auto& cv : cand) {
    std::sort(cv.begin(), cv.end());
    cv.erase(std::unique(cv.begin(), cv.end()), cv.end());
  }
  const auto vf = vertex_faces(nv, F);
  const Eigen::MatrixX3d N = vertex_normals(V, F);
  std::vector<SurfacePoint> out(nc);  // face −1 for empty cells
  const int block = std::max(1, options.solve_block);
  const int threads = resolve_threads(options.threads);
  for (int c0 = 0; c0 < nc; c0 += block) {
    const int nb = std::min(block, nc - c0);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nv, nb);
    for (int j = 0; j < nb; ++j)
      for (const auto& [vtx, w] : loads[c0 + j]) rhs(vtx, j) += w;
    Eigen::MatrixXd U = solver.solve(rhs);
    for (int s = 1; s < options.steps; ++s) U = solver.solve(Eigen::MatrixXd(solver.mass().asDiagonal() * U));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int j = 0; j < nb; ++j) {
      const int c = c0 + j;
      if (cand[c].empty()) continue;
      int hot = cand[c][0];
      for (int w : cand[c])
        if (U(w, j) > U(hot, j)) hot = w;
      const Eigen::VectorXd h = U.col(j);
      out[c] = options.quadratic_refinement ? refine_hottest_vertex(V, F, vf, N, h, hot) : vertex_point(F, vf, hot);
    }
  }
  return out;
}

SurfacePoint heat_centroid_of_faces(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatSolver& solver,
                                    const std::vector<int>& faces, const CentroidOptions& options) {
  check_heat_inputs(V, F, solver, "heat_centroid_of_faces");
  if (options.steps < 1) throw InvalidInputError("heat_centroid_of_faces: steps must be >= 1");
  if (faces.empty()) throw InvalidInputError("heat_centroid_of_faces: no faces given");
  const Eigen::VectorXd area = face_areas(V, F);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(V.rows());
  for (int f : faces) {
    if (f < 0 || f >= F.rows())
      throw InvalidInputError("heat_centroid_of_faces: face index " + std::to_string(f) + " out of range [0, " +
                              std::to_string(F.rows()) + ")");
    for (int k = 0; k < 3; ++k) rhs[F(f, k)] += area[f] / 3.0;  // eq. 10–11
  }
  const Eigen::VectorXd u = solver.diffuse_steps(rhs, options.steps);
  int hot = 0;
  u.maxCoeff(&hot);
  const auto vf = vertex_faces(static_cast<int>(V.rows()), F);
  if (vf[hot].empty()) throw InvalidInputError("heat_centroid_of_faces: the hottest vertex has no faces");
  if (!options.quadratic_refinement) return vertex_point(F, vf, hot);
  return refine_hottest_vertex(V, F, vf, vertex_normals(V, F), u, hot);
}

}  // namespace heatcvt
