// Closing a hole with the sites inside it: constrained Delaunay triangulation in the loop's plane.
#include "heatcvt/mesher/hole_sites.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>

namespace heatcvt {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = Kernel::Point_2;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using FaceInfoBase = CGAL::Triangulation_face_base_with_info_2<char, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceInfoBase>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Whether the closed segments pq and rs share a point.
bool segments_meet(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r, const Eigen::Vector2d& s) {
  const double d1 = cross2(q - p, r - p), d2 = cross2(q - p, s - p);
  const double d3 = cross2(s - r, p - r), d4 = cross2(s - r, q - r);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  auto on = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& x, double d) {
    return d == 0 && std::min(a.x(), b.x()) <= x.x() && x.x() <= std::max(a.x(), b.x()) &&
           std::min(a.y(), b.y()) <= x.y() && x.y() <= std::max(a.y(), b.y());
  };
  return on(p, q, r, d1) || on(p, q, s, d2) || on(r, s, p, d3) || on(r, s, q, d4);
}

bool is_simple(const std::vector<Eigen::Vector2d>& poly) {
  const size_t L = poly.size();
  for (size_t i = 0; i < L; ++i)
    for (size_t j = i + 1; j < L; ++j) {
      if (j == i + 1 || (i == 0 && j == L - 1)) continue;  // neighbouring edges share a corner
      if (segments_meet(poly[i], poly[(i + 1) % L], poly[j], poly[(j + 1) % L])) return false;
    }
  return true;
}

double signed_area(const std::vector<Eigen::Vector2d>& poly) {
  double a = 0;
  for (size_t i = 0; i < poly.size(); ++i) a += cross2(poly[i], poly[(i + 1) % poly.size()]);
  return 0.5 * a;
}

bool inside(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& x) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > x.y()) != (poly[j].y() > x.y()) &&
        x.x() < (poly[j].x() - poly[i].x()) * (x.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) + poly[i].x())
      in = !in;
  return in;
}

double segment_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
  const Eigen::Vector2d e = b - a;
  const double t = e.squaredNorm() > 0 ? std::clamp((x - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * e - x).norm();
}

// Faces of the CDT inside the constrained polygon: those not reachable from the infinite face
// without crossing a constraint.
std::vector<Cdt::Face_handle> inside_faces(Cdt& cdt) {
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = 1;
  std::deque<Cdt::Face_handle> queue = {cdt.infinite_face()};
  cdt.infinite_face()->info() = 0;
  while (!queue.empty()) {
    const Cdt::Face_handle f = queue.front();
    queue.pop_front();
    for (int k = 0; k < 3; ++k) {
      const Cdt::Face_handle g = f->neighbor(k);
      if (g->info() == 0 || cdt.is_constrained({f, k})) continue;
      g->info() = 0;
      queue.push_back(g);
    }
  }
  std::vector<Cdt::Face_handle> out;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    if (f->info()) out.push_back(f);
  return out;
}

}  // namespace

bool triangulate_hole_with_sites(const WorkingMesh& mesh, const std::vector<int>& loop, const std::vector<int>& candidates,
                                 const HoleSiteOptions& options, HoleTriangulation& out) {
  out = {};
  const int L = static_cast<int>(loop.size());
  if (L < 3) return false;
  // The plane: the loop's mean site normal through its centroid.
  Eigen::Vector3d n = Eigen::Vector3d::Zero(), g = Eigen::Vector3d::Zero();
  double h = 0;
  for (int i = 0; i < L; ++i) {
    n += mesh.N.row(loop[i]).transpose();
    g += mesh.V.row(loop[i]).transpose();
    h += (mesh.V.row(loop[i]) - mesh.V.row(loop[(i + 1) % L])).norm();
  }
  g /= L;
  h /= L;
  if (!(n.norm() >= options.min_mean_normal * L) || !(h > 0)) return false;
  n.normalize();
  const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
  auto plane = [&](int v) {
    const Eigen::Vector3d d = mesh.V.row(v).transpose() - g;
    return Eigen::Vector2d(d.dot(u), d.dot(w));
  };
  std::vector<Eigen::Vector2d> poly(L);
  double radius = 0;
  for (int i = 0; i < L; ++i) {
    poly[i] = plane(loop[i]);
    radius = std::max(radius, (mesh.V.row(loop[i]).transpose() - g).norm());
  }
  // The hole is on the right of the loop: seen from n its projection runs clockwise.
  const double area = -signed_area(poly);
  if (!is_simple(poly)) {
    out.shape = LoopShape::not_simple;
    return false;
  }
  out.shape = area > 0 ? LoopShape::hole : LoopShape::outer_border;
  if (!(area > 0)) return false;
  out.expected_sites = area / (0.5 * std::sqrt(3.0) * h * h);

  // Inside sites, in the candidates' order, each clear of the loop and of those taken before.
  std::vector<Eigen::Vector2d> taken;
  for (int v : candidates) {
    if (mesh.N.row(v).dot(n) < options.min_normal_dot) continue;
    if (std::abs((mesh.V.row(v).transpose() - g).dot(n)) > options.max_height * radius) continue;
    const Eigen::Vector2d x = plane(v);
    if (!inside(poly, x)) continue;
    bool clear = true;
    for (int i = 0; i < L && clear; ++i) clear = segment_distance(poly[i], poly[(i + 1) % L], x) >= options.min_clearance * h;
    for (size_t t = 0; t < taken.size() && clear; ++t) clear = (taken[t] - x).norm() >= options.min_clearance * h;
    if (!clear) continue;
    taken.push_back(x);
    out.interior_sites.push_back(v);
  }

  Cdt cdt;
  std::vector<Cdt::Vertex_handle> corner(L);
  for (int i = 0; i < L; ++i) {
    corner[i] = cdt.insert(Point2(poly[i].x(), poly[i].y()));
    corner[i]->info() = loop[i];
  }
  for (size_t t = 0; t < taken.size(); ++t)
    cdt.insert(Point2(taken[t].x(), taken[t].y()))->info() = out.interior_sites[t];
  auto fail = [&] {
    out.interior_sites.clear();
    return false;
  };
  if (static_cast<int>(cdt.number_of_vertices()) != L + static_cast<int>(taken.size())) return fail();
  for (int i = 0; i < L; ++i) cdt.insert_constraint(corner[i], corner[(i + 1) % L]);
  // A constraint through another vertex or crossing another one would add a vertex or split it.
  if (static_cast<int>(cdt.number_of_vertices()) != L + static_cast<int>(taken.size())) return fail();
  const std::vector<Cdt::Face_handle> faces = inside_faces(cdt);
  if (static_cast<int>(faces.size()) != L - 2 + 2 * static_cast<int>(taken.size())) return fail();
  std::vector<int> position(mesh.num_vertices(), -1);
  for (int i = 0; i < L; ++i) position[loop[i]] = i;
  for (const Cdt::Face_handle& f : faces) {
    const MeshFace t = {f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};  // counter-clockwise
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const bool loop_edge = position[a] >= 0 && position[b] >= 0 &&
                             ((position[a] + 1) % L == position[b] || (position[b] + 1) % L == position[a]);
      if (!loop_edge && mesh.edge_face_count(a, b) > 0) {
        out.faces.clear();
        out.interior_sites.clear();
        return false;
      }
    }
    out.faces.push_back(t);
  }
  // Lifted back onto the sites, every triangle must still face the way its corners do (a plane
  // across a depth jump or a fold would give steep slivers).
  for (const MeshFace& t : out.faces) {
    const Eigen::Vector3d a = mesh.V.row(t[0]), b = mesh.V.row(t[1]), c = mesh.V.row(t[2]);
    const Eigen::Vector3d fn = (b - a).cross(c - a);
    bool agrees = fn.norm() > 0;
    for (int k = 0; k < 3 && agrees; ++k) agrees = fn.normalized().dot(mesh.N.row(t[k]).transpose()) > options.min_triangle_dot;
    if (!agrees) {
      out.faces.clear();
      out.interior_sites.clear();
      return false;
    }
  }
  return true;
}

}  // namespace heatcvt
