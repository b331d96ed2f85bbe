// Self-intersections of the working mesh (CGAL box intersection and exact predicates).
#include "heatcvt/mesher/mesh_checks.h"

#include "heatcvt/grid_cell.h"
#include "heatcvt/mesh.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

namespace heatcvt {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int, CGAL::Box_intersection_d::ID_EXPLICIT>;

// Boxes below this many are compared all against all by the box intersection.
constexpr std::ptrdiff_t kBoxCutoff = 2000;

// Faces closer than this fraction of the mesh's bounding-box diagonal (where they share no
// corner, or apart from the corner they share) count as intersecting. Exact predicates decide a
// pair in the coordinates at hand; a pair that only just misses (two border vertices moved onto
// the same point, a corner a rounding step off a face) can touch once the mesh is scaled back to
// the input's frame or written out, so the mesher keeps a margin far above rounding and far below
// any edge length.
constexpr double kContactTolerance = 1e-9;

K::Point_3 point(const WorkingMesh& mesh, int v) { return {mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2)}; }

// Whether the points p[0..n) all lie more than eps to the same side of the plane of triangle s
// (then they, and what they span, are farther than eps from s).
bool apart_by_plane(const K::Triangle_3& s, const K::Point_3* p, int n, double eps) {
  const K::Vector_3 normal = CGAL::cross_product(s[1] - s[0], s[2] - s[0]);
  const double len = std::sqrt(normal.squared_length());
  if (!(len > 0)) return false;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < n; ++i) {
    const double d = (p[i] - s[0]) * normal / len;
    lo = std::min(lo, d), hi = std::max(hi, d);
  }
  return lo > eps || hi < -eps;
}

bool apart_by_plane(const K::Triangle_3& s, const K::Triangle_3& t, double eps) {
  const K::Point_3 p[3] = {t[0], t[1], t[2]};
  return apart_by_plane(s, p, 3, eps);
}

// Whether the segment and the triangle come within eps of each other.
bool segment_near(const K::Segment_3& s, const K::Triangle_3& t, double eps) {
  const K::Point_3 ends[2] = {s.source(), s.target()};
  if (apart_by_plane(t, ends, 2, eps)) return false;
  const double eps2 = eps * eps;
  if (CGAL::squared_distance(s.source(), t) < eps2 || CGAL::squared_distance(s.target(), t) < eps2) return true;
  for (int i = 0; i < 3; ++i)
    if (CGAL::squared_distance(s, K::Segment_3(t[i], t[(i + 1) % 3])) < eps2) return true;
  return false;
}

// Whether two triangles with no common corner come within eps of each other.
bool triangles_near(const K::Triangle_3& a, const K::Triangle_3& b, double eps) {
  if (apart_by_plane(a, b, eps) || apart_by_plane(b, a, eps)) return false;
  for (int i = 0; i < 3; ++i)
    if (segment_near(K::Segment_3(a[i], a[(i + 1) % 3]), b, eps)) return true;
  for (int i = 0; i < 3; ++i)
    if (CGAL::squared_distance(b[i], a) < eps * eps) return true;
  return false;
}

// Whether faces f and g intersect other than along what they share (the rule of
// intersecting_face_pairs()), or come within eps of each other where they share nothing.
bool faces_intersect(const WorkingMesh& mesh, const MeshFace& f, const MeshFace& g, double eps) {
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
    // Each far side of one face beyond eps from the plane of the other: neither test below can
    // hold (segment_near() starts with the same test), so the exact predicates are skipped.
    const K::Point_3 ends_f[2] = {sf.source(), sf.target()}, ends_g[2] = {sg.source(), sg.target()};
    if (apart_by_plane(tf, ends_g, 2, eps) && apart_by_plane(tg, ends_f, 2, eps)) return false;
    return CGAL::do_intersect(tf, sg) || CGAL::do_intersect(tg, sf) || segment_near(sg, tf, eps) ||
           segment_near(sf, tg, eps);
  }
  return CGAL::do_intersect(tf, tg) || triangles_near(tf, tg, eps);
}

// The contact tolerance of intersecting_face_pairs() for the mesh: kContactTolerance times the
// diagonal of the bounding box of its faces.
double contact_tolerance(const WorkingMesh& mesh) {
  CGAL::Bbox_3 all;
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f)) all += point(mesh, v).bbox();
  return kContactTolerance * std::sqrt(CGAL::square(all.xmax() - all.xmin()) + CGAL::square(all.ymax() - all.ymin()) +
                                       CGAL::square(all.zmax() - all.zmin()));
}

// The bounding box of face f grown by eps, or false where its corners are collinear (such faces
// are skipped).
bool face_box(const WorkingMesh& mesh, int f, double eps, CGAL::Bbox_3& box) {
  const MeshFace& t = mesh.face(f);
  const K::Point_3 p = point(mesh, t[0]), q = point(mesh, t[1]), r = point(mesh, t[2]);
  if (CGAL::collinear(p, q, r)) return false;
  const CGAL::Bbox_3 b = p.bbox() + q.bbox() + r.bbox();
  box = CGAL::Bbox_3(b.xmin() - eps, b.ymin() - eps, b.zmin() - eps, b.xmax() + eps, b.ymax() + eps, b.zmax() + eps);
  return true;
}

// The pairs (f, g), f < g, ascending, of intersecting faces of which at least one is marked in
// `changed`: the boxes of the marked faces go into a grid of cells as wide as the widest of them,
// and every face's box looks up the cells it overlaps.
std::vector<std::pair<int, int>> intersecting_pairs_at(const WorkingMesh& mesh, const std::vector<char>& changed) {
  const double eps = contact_tolerance(mesh);
  std::vector<std::pair<int, CGAL::Bbox_3>> marked;
  double cell = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    CGAL::Bbox_3 b;
    if (!changed[f] || !face_box(mesh, f, eps, b)) continue;
    marked.emplace_back(f, b);
    cell = std::max({cell, b.xmax() - b.xmin(), b.ymax() - b.ymin(), b.zmax() - b.zmin()});
  }
  std::vector<std::pair<int, int>> pairs;
  if (marked.empty() || !(cell > 0)) return pairs;
  auto lo = [&](const CGAL::Bbox_3& b) { return grid_cell({b.xmin(), b.ymin(), b.zmin()}, cell); };
  auto hi = [&](const CGAL::Bbox_3& b) { return grid_cell({b.xmax(), b.ymax(), b.zmax()}, cell); };
  std::unordered_map<GridCell, std::vector<int>, GridCellHash> grid;
  for (int i = 0; i < static_cast<int>(marked.size()); ++i) {
    const CGAL::Bbox_3& b = marked[static_cast<std::size_t>(i)].second;
    const GridCell c0 = lo(b), c1 = hi(b);
    for (auto x = c0[0]; x <= c1[0]; ++x)
      for (auto y = c0[1]; y <= c1[1]; ++y)
        for (auto z = c0[2]; z <= c1[2]; ++z) grid[{x, y, z}].push_back(i);
  }
  std::vector<int> seen(marked.size(), -1);
  for (int g = 0; g < mesh.num_faces(); ++g) {
    CGAL::Bbox_3 b;
    if (!face_box(mesh, g, eps, b)) continue;
    // A face wider than many cells is compared with every marked face instead.
    const GridCell c0 = lo(b), c1 = hi(b);
    const auto cells = (c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1) * (c1[2] - c0[2] + 1);
    auto consider = [&](int i) {
      if (seen[static_cast<std::size_t>(i)] == g) return;
      seen[static_cast<std::size_t>(i)] = g;
      const int f = marked[static_cast<std::size_t>(i)].first;
      if (f == g || (changed[g] && g < f) || !CGAL::do_overlap(b, marked[static_cast<std::size_t>(i)].second)) return;
      const int a = std::min(f, g), c = std::max(f, g);
      if (faces_intersect(mesh, mesh.face(a), mesh.face(c), eps)) pairs.emplace_back(a, c);
    };
    if (cells > static_cast<std::int64_t>(marked.size())) {
      for (int i = 0; i < static_cast<int>(marked.size()); ++i) consider(i);
      continue;
    }
    for (auto x = c0[0]; x <= c1[0]; ++x)
      for (auto y = c0[1]; y <= c1[1]; ++y)
        for (auto z = c0[2]; z <= c1[2]; ++z) {
          const auto it = grid.find({x, y, z});
          if (it != grid.end())
            for (int i : it->second) consider(i);
        }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

std::vector<FacePair> by_corners(const WorkingMesh& mesh, const std::vector<std::pair<int, int>>& pairs) {
  std::vector<FacePair> out;
  out.reserve(pairs.size());
  for (const auto& [f, g] : pairs) out.emplace_back(mesh.face(f), mesh.face(g));
  return out;
}

}  // namespace

std::vector<std::pair<int, int>> intersecting_face_pairs(const WorkingMesh& mesh) {
  std::vector<Box> boxes;
  boxes.reserve(static_cast<std::size_t>(mesh.num_faces()));
  const double eps = contact_tolerance(mesh);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    CGAL::Bbox_3 b;
    if (face_box(mesh, f, eps, b)) boxes.emplace_back(b, f);
  }
  // The box scan lists the overlapping pairs; the exact tests, most of the work, then run on
  // every core. The sort makes the result independent of the thread count.
  std::vector<std::pair<int, int>> overlapping;
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&](const Box& a, const Box& b) {
        overlapping.emplace_back(std::min(a.info(), b.info()), std::max(a.info(), b.info()));
      },
      kBoxCutoff);
  std::vector<char> hit(overlapping.size(), 0);
  const auto count = static_cast<std::ptrdiff_t>(overlapping.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (std::ptrdiff_t i = 0; i < count; ++i) {
    const auto& [f, g] = overlapping[static_cast<std::size_t>(i)];
    hit[static_cast<std::size_t>(i)] = faces_intersect(mesh, mesh.face(f), mesh.face(g), eps);
  }
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < overlapping.size(); ++i)
    if (hit[i]) pairs.push_back(overlapping[i]);
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

std::vector<FacePair> crossing_face_pairs(const WorkingMesh& mesh) { return by_corners(mesh, intersecting_face_pairs(mesh)); }

std::vector<FacePair> crossing_face_pairs_after(const WorkingMesh& mesh, const WorkingMesh::Checkpoint& before,
                                                const std::vector<FacePair>& pairs_before, double max_changed_fraction) {
  const MeshChanges changes = changes_since(before, mesh);
  const std::vector<char>& moved = changes.moved;
  std::vector<char> changed(mesh.num_faces(), 0);
  long count = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const MeshFace& t = mesh.face(f);
    changed[f] = moved[t[0]] || moved[t[1]] || moved[t[2]] || changes.new_face[f];
    count += changed[f];
  }
  if (count > max_changed_fraction * mesh.num_faces()) return crossing_face_pairs(mesh);
  // Pairs of two faces left alone: both still there, no corner moved.
  std::unordered_set<MeshFace, MeshFaceHash> now(mesh.faces().begin(), mesh.faces().end());
  auto kept = [&](const MeshFace& t) {
    return now.count(t) && !moved[t[0]] && !moved[t[1]] && !moved[t[2]];
  };
  std::vector<FacePair> out;
  for (const FacePair& p : pairs_before)
    if (kept(p.first) && kept(p.second)) out.push_back(p);
  const std::vector<FacePair> fresh = by_corners(mesh, intersecting_pairs_at(mesh, changed));
  out.insert(out.end(), fresh.begin(), fresh.end());
  return out;
}

std::vector<int> faces_in_pairs(const WorkingMesh& mesh, const std::vector<FacePair>& pairs) {
  std::unordered_set<MeshFace, MeshFaceHash> named;
  for (const FacePair& p : pairs) named.insert(p.first), named.insert(p.second);
  std::vector<int> out;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (named.count(mesh.face(f))) out.push_back(f);
  return out;
}

namespace {

Eigen::MatrixX3i face_matrix(const WorkingMesh& mesh) {
  const std::vector<MeshFace>& faces = mesh.faces();
  Eigen::MatrixX3i F(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) F.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  return F;
}

}  // namespace

TopologyTarget topology_of(const WorkingMesh& mesh) {
  const MeshTopology t = mesh_topology(face_matrix(mesh), mesh.num_vertices());
  return {t.components, t.boundary_loops, t.euler_characteristic()};
}

bool breaks_topology(const TopologyTarget& target, const TopologyTarget& before, const TopologyTarget& after) {
  if (!target.enabled()) return false;
  return (before == target && !(after == target)) ||
         after.boundary_loops < std::min(before.boundary_loops, target.boundary_loops);
}

int boundary_loop_labels(const WorkingMesh& mesh, std::vector<int>& loop) {
  Eigen::VectorXi labels;
  const int count = boundary_loop_labels(mesh.num_vertices(), face_matrix(mesh), labels);
  loop.assign(labels.data(), labels.data() + labels.size());
  return count;
}

std::vector<int> lost_loop_vertices(const WorkingMesh& mesh, const std::vector<int>& before) {
  std::vector<int> now;
  boundary_loop_labels(mesh, now);
  const int loops = before.empty() ? 0 : *std::max_element(before.begin(), before.end()) + 1;
  // For each loop of before, the loop its vertices are on now (−1: none on the border; −2: several).
  std::vector<int> became(static_cast<std::size_t>(loops), -1);
  for (std::size_t v = 0; v < before.size(); ++v) {
    const int l = before[v], n = v < now.size() ? now[v] : -1;
    if (l < 0 || n < 0) continue;
    int& b = became[static_cast<std::size_t>(l)];
    b = b == -1 || b == n ? n : -2;
  }
  std::vector<int> sharing(now.empty() ? 0 : static_cast<std::size_t>(*std::max_element(now.begin(), now.end()) + 1), 0);
  for (int b : became)
    if (b >= 0) ++sharing[static_cast<std::size_t>(b)];
  std::vector<int> lost;
  for (std::size_t v = 0; v < before.size(); ++v) {
    const int l = before[v];
    if (l < 0) continue;
    const int b = became[static_cast<std::size_t>(l)];
    if (b == -1 || (b >= 0 && sharing[static_cast<std::size_t>(b)] > 1)) lost.push_back(static_cast<int>(v));
  }
  return lost;
}

}  // namespace heatcvt
