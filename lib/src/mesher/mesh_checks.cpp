// Self-intersections of the working mesh (CGAL box intersection and exact predicates).
#include "heatcvt/mesher/mesh_checks.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>

namespace heatcvt {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int, CGAL::Box_intersection_d::ID_EXPLICIT>;

// Boxes below this many are compared all against all by the box intersection.
constexpr std::ptrdiff_t kBoxCutoff = 2000;

K::Point_3 point(const WorkingMesh& mesh, int v) { return {mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2)}; }

// Whether faces f and g intersect other than along what they share (the rule of
// intersecting_face_pairs()).
bool faces_intersect(const WorkingMesh& mesh, const MeshFace& f, const MeshFace& g) {
  int shared = 0, fi = -1, gj = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (f[i] == g[j]) ++shared, fi = i, gj = j;
  const K::Triangle_3 tf(point(mesh, f[0]), point(mesh, f[1]), point(mesh, f[2]));
  const K::Triangle_3 tg(point(mesh, g[0]), point(mesh, g[1]), point(mesh, g[2]));
  if (shared >= 2) {
    // The corners each face has apart from the common edge.
    int a = -1, b = -1;
    for (int v : f)
      if (v != g[0] && v != g[1] && v != g[2]) a = v;
    for (int v : g)
      if (v != f[0] && v != f[1] && v != f[2]) b = v;
    if (a < 0 || b < 0) return false;  // the same three corners: one face twice
    int u = -1, w = -1;
    for (int v : f)
      if (v != a) (u < 0 ? u : w) = v;
    const K::Point_3 pu = point(mesh, u), pw = point(mesh, w), pa = point(mesh, a), pb = point(mesh, b);
    return CGAL::coplanar(pu, pw, pa, pb) && CGAL::coplanar_orientation(pu, pw, pa, pb) == CGAL::POSITIVE;
  }
  if (shared == 1) {
    const K::Segment_3 sf(point(mesh, f[(fi + 1) % 3]), point(mesh, f[(fi + 2) % 3]));
    const K::Segment_3 sg(point(mesh, g[(gj + 1) % 3]), point(mesh, g[(gj + 2) % 3]));
    return CGAL::do_intersect(tf, sg) || CGAL::do_intersect(tg, sf);
  }
  return CGAL::do_intersect(tf, tg);
}

}  // namespace

std::vector<std::pair<int, int>> intersecting_face_pairs(const WorkingMesh& mesh) {
  std::vector<Box> boxes;
  boxes.reserve(static_cast<std::size_t>(mesh.num_faces()));
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const MeshFace& t = mesh.face(f);
    const K::Point_3 p = point(mesh, t[0]), q = point(mesh, t[1]), r = point(mesh, t[2]);
    if (CGAL::collinear(p, q, r)) continue;
    boxes.emplace_back(p.bbox() + q.bbox() + r.bbox(), f);
  }
  std::vector<std::pair<int, int>> pairs;
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&](const Box& a, const Box& b) {
        const int f = std::min(a.info(), b.info()), g = std::max(a.info(), b.info());
        if (faces_intersect(mesh, mesh.face(f), mesh.face(g))) pairs.emplace_back(f, g);
      },
      kBoxCutoff);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

std::vector<int> self_intersecting_faces(const WorkingMesh& mesh) {
  std::vector<int> out;
  for (const auto& [f, g] : intersecting_face_pairs(mesh)) {
    out.push_back(f);
    out.push_back(g);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

long self_intersecting_pairs(const WorkingMesh& mesh) { return static_cast<long>(intersecting_face_pairs(mesh).size()); }

}  // namespace heatcvt
