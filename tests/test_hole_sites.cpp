// Tests of the mesher's recovery of sites the extraction left out: holes closed with the sites
// inside them (hole_sites.h), the shapes of boundary loops, and the sites' own Delaunay stars
// (star_candidates() in dual_candidates.h). Shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/border_growth.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/dual_candidates.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/hole_sites.h"
#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

int used_vertices(const WorkingMesh& w) {
  std::vector<char> used(w.num_vertices(), 0);
  for (const MeshFace& f : w.faces())
    for (int v : f) used[v] = 1;
  return static_cast<int>(std::count(used.begin(), used.end(), 1));
}

// The boundary loops, each followed along its faces' half-edges (the hole on the right).
std::vector<std::vector<int>> boundary_loops(const WorkingMesh& w) {
  std::map<int, int> next;
  for (const MeshFace& f : w.faces())
    for (int k = 0; k < 3; ++k)
      if (!w.has_half_edge(f[(k + 1) % 3], f[k])) next[f[k]] = f[(k + 1) % 3];
  std::vector<std::vector<int>> loops;
  std::map<int, char> seen;
  for (const auto& [start, unused] : next) {
    if (seen[start]) continue;
    std::vector<int> loop;
    for (int v = start; !seen[v]; v = next.at(v)) seen[v] = 1, loop.push_back(v);
    loops.push_back(loop);
  }
  return loops;
}

// Removes the faces with a corner within `radius` of `centre`; returns the vertices left in no face.
int punch(WorkingMesh& w, const Eigen::Vector3d& centre, double radius) {
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); ++f)
    for (int v : w.face(f)) drop[f] |= (w.V.row(v).transpose() - centre).norm() < radius;
  w.remove_faces(drop);
  return w.num_vertices() - used_vertices(w);
}

ValidationReport validate(const WorkingMesh& w, bool closed) {
  const TriangleMesh m = compact_mesh(w);
  ValidationOptions o;
  o.require_closed = closed;
  return validate_triangle_mesh(m.V, m.F, o);
}

TEST(HoleSites, ASphereHoleIsClosedWithTheSitesInsideIt) {
  const TriangleMesh s = test::icosphere(3);
  const MeshSurfaceProjector surface(s.V, s.F);
  for (bool with_sites : {true, false}) {
    WorkingMesh w = test::working_mesh(s);
    const int left_out = punch(w, Eigen::Vector3d(0, 0, 1), 0.45);
    ASSERT_GE(left_out, 5);
    HoleFillingOptions o;
    o.sites.enabled = with_sites;
    int removed = 0;
    EXPECT_EQ(fill_holes(w, surface, o, {}, removed), 1);
    const ValidationReport r = validate(w, true);
    EXPECT_TRUE(r.ok()) << r.summary();
    EXPECT_EQ(r.genus, 0);
    // With the sites every vertex is back in the mesh; without them the hole is closed across them.
    EXPECT_EQ(used_vertices(w), with_sites ? s.V.rows() : s.V.rows() - left_out);
  }
}

TEST(HoleSites, FillOfAPlaneHoleIsTheConstrainedDelaunayTriangulation) {
  const TriangleMesh g = test::grid(12, 0, 1, 0, 1, true);
  WorkingMesh w = test::working_mesh(g);
  const int left_out = punch(w, Eigen::Vector3d(0.5, 0.5, 0), 0.2);
  ASSERT_GE(left_out, 9);
  const std::vector<std::vector<int>> loops = boundary_loops(w);
  ASSERT_EQ(loops.size(), 2u);
  std::vector<int> free_vertices;
  for (int v = 0; v < w.num_vertices(); ++v)
    if (std::none_of(w.faces().begin(), w.faces().end(), [&](const MeshFace& f) { return f[0] == v || f[1] == v || f[2] == v; }))
      free_vertices.push_back(v);
  int holes = 0, borders = 0;
  for (const std::vector<int>& loop : loops) {
    HoleTriangulation t;
    const bool ok = triangulate_hole_with_sites(w, loop, free_vertices, {}, t);
    if (t.shape == LoopShape::outer_border) {
      ++borders;
      EXPECT_FALSE(ok);
      EXPECT_TRUE(t.faces.empty());
      continue;
    }
    ++holes;
    ASSERT_TRUE(ok);
    EXPECT_EQ(t.shape, LoopShape::hole);
    EXPECT_EQ(static_cast<int>(t.interior_sites.size()), left_out);
    // A triangulated polygon of L corners with I points inside has L − 2 + 2I triangles, each
    // facing +z like the grid, and (a grid's points being cocircular) no angle below 45°.
    EXPECT_EQ(static_cast<int>(t.faces.size()), static_cast<int>(loop.size()) - 2 + 2 * left_out);
    for (const MeshFace& f : t.faces) {
      const Eigen::Vector3d a = w.V.row(f[0]), b = w.V.row(f[1]), c = w.V.row(f[2]);
      EXPECT_GT((b - a).cross(c - a).z(), 0);
      EXPECT_GE(face_min_angle(w, f), M_PI / 4 - 1e-9);
    }
    for (const MeshFace& f : t.faces) w.add_face(f);
  }
  EXPECT_EQ(holes, 1);
  EXPECT_EQ(borders, 1);
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(used_vertices(w), w.num_vertices());
}

TEST(HoleSites, ALoopWhoseProjectionCrossesItselfIsNotTriangulated) {
  // A bow-tie: four corners on the plane z = 0, visited so that edges 0-1 and 2-3 cross.
  WorkingMesh w(Eigen::MatrixX3d(4, 3), Eigen::MatrixX3d(4, 3), std::vector<int>(4, -1));
  w.V << 0, 0, 0, 1, 1, 0, 1, 0, 0, 0, 1, 0;
  w.N.setZero();
  w.N.col(2).setOnes();
  HoleTriangulation t;
  EXPECT_FALSE(triangulate_hole_with_sites(w, {0, 1, 2, 3}, {}, {}, t));
  EXPECT_EQ(t.shape, LoopShape::not_simple);
  // Normals that cancel out leave no plane to look from.
  w.N.row(0) << 0, 0, -1;
  w.N.row(1) << 0, 0, -1;
  EXPECT_FALSE(triangulate_hole_with_sites(w, {0, 2, 1, 3}, {}, {}, t));
  EXPECT_EQ(t.shape, LoopShape::unknown);
}

TEST(HoleSites, TheBorderOfAFragmentIsNotClosedIntoAPillow) {
  // An open sheet of many fragments (an open surface): a lone strip's border would be closed
  // into its own back side. The strip stays open.
  const TriangleMesh g = test::grid(10, 0, 1, 0, 1, true);
  WorkingMesh w = test::working_mesh(g);
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : w.face(f)) c += w.V.row(v).transpose() / 3.0;
    drop[f] = !(c.y() > 0.2 && c.y() < 0.4 && c.x() > 0.1 && c.x() < 0.9);  // keep one strip
  }
  w.remove_faces(drop);
  const int faces = w.num_faces();
  ASSERT_GE(faces, 20);
  const MeshSurfaceProjector surface(g.V, g.F);
  HoleFillingOptions o;
  o.policy = HolePolicy::fill;
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, o, {}, removed), 0);
  EXPECT_EQ(w.num_faces(), faces);
}

// A finger: a cylinder of radius 0.1 over 0 <= z <= 1 with a hemispherical base and a cone of
// height 0.05 on top (the tip), `around` vertices on each ring and rings about 2π·0.1/around
// apart. Outward oriented; the open ring at z = 1 is vertex ring `top_ring`.
TriangleMesh finger(int around, int* top_ring = nullptr) {
  const double r = 0.1, spacing = 2 * M_PI * r / around;
  std::vector<std::pair<double, double>> rings;  // (radius, z), bottom to top, poles excluded
  const int base = std::max(2, static_cast<int>(0.5 * M_PI * r / spacing));
  for (int i = 1; i <= base; ++i) {
    const double a = 0.5 * M_PI * i / base;
    rings.push_back({r * std::sin(a), -r * std::cos(a)});
  }
  const int side = static_cast<int>(1.0 / spacing);
  for (int i = 1; i <= side; ++i) rings.push_back({r, static_cast<double>(i) / side});
  if (top_ring) *top_ring = static_cast<int>(rings.size()) - 1;
  const int cone = std::max(1, static_cast<int>(0.05 / spacing));
  for (int i = 1; i < cone; ++i) rings.push_back({r * (1.0 - static_cast<double>(i) / cone), 1.0 + 0.05 * i / cone});
  const int nr = static_cast<int>(rings.size());
  TriangleMesh m;
  m.V.resize(nr * around + 2, 3);
  for (int k = 0; k < nr; ++k)
    for (int j = 0; j < around; ++j) {
      const double t = 2 * M_PI * j / around;
      m.V.row(k * around + j) << rings[k].first * std::cos(t), rings[k].first * std::sin(t), rings[k].second;
    }
  const int bottom = nr * around, top = bottom + 1;
  m.V.row(bottom) << 0, 0, -r;
  m.V.row(top) << 0, 0, 1.05;
  std::vector<Eigen::Vector3i> F;
  for (int j = 0; j < around; ++j) {
    const int j1 = (j + 1) % around;
    F.push_back({bottom, j1, j});
    F.push_back({top, (nr - 1) * around + j, (nr - 1) * around + j1});
    for (int k = 0; k + 1 < nr; ++k) {
      const int a = k * around + j, b = k * around + j1, c = a + around, d = b + around;
      F.push_back({a, b, d});
      F.push_back({a, d, c});
    }
  }
  m.F.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t f = 0; f < F.size(); ++f) m.F.row(static_cast<Eigen::Index>(f)) = F[f].transpose();
  return m;
}

TEST(HoleFilling, TheOpenEndOfASampledTipIsCappedAndAnUnsampledOneStaysOpen) {
  // The finger's mesh without the faces above its top ring: a loop around the thin part whose
  // sites' normals cancel out (no plane to see the hole from), with the blunt tip too far above
  // the loop's edges for the surrounded-hole test. The cloud is a finer finger: with the tip (the
  // extraction lost the cells of a sampled tip) or ending at the loop (the open end of a
  // scanned tube).
  int top_ring = 0;
  const TriangleMesh coarse = finger(24, &top_ring), fine = finger(96);
  double volume = 0;
  for (Eigen::Index f = 0; f < coarse.F.rows(); ++f)
    volume += coarse.V.row(coarse.F(f, 0)).dot(coarse.V.row(coarse.F(f, 1)).cross(coarse.V.row(coarse.F(f, 2)))) / 6;
  ASSERT_GT(volume, 0) << "outward";
  const Eigen::MatrixX3d fine_normals = vertex_normals(fine.V, fine.F);
  const HoleFillingOptions o;
  for (bool tip_sampled : {true, false}) {
    WorkingMesh w = test::working_mesh(coarse);
    std::vector<char> drop(w.num_faces(), 0);
    for (int f = 0; f < w.num_faces(); ++f)
      for (int v : w.face(f)) drop[f] |= w.V(v, 2) > 1.0;
    w.remove_faces(drop);
    const std::vector<std::vector<int>> loops = boundary_loops(w);
    ASSERT_EQ(loops.size(), 1u);
    const int L = static_cast<int>(loops[0].size());
    ASSERT_GT(L, o.max_hole_edges);
    ASSERT_LE(L, o.surrounded_hole_factor * o.max_hole_edges);
    // The loop's sites have the normals of the cylinder they were fitted on: radial, cancelling out.
    for (int v : loops[0]) w.N.row(v) = Eigen::RowVector3d(w.V(v, 0), w.V(v, 1), 0).normalized();
    std::vector<int> kept;
    for (int i = 0; i < fine.V.rows(); ++i)
      if (tip_sampled || fine.V(i, 2) <= 1.0) kept.push_back(i);
    const CloudSurfaceProjector surface(fine.V(kept, Eigen::all), fine_normals(kept, Eigen::all));
    int removed = 0;
    EXPECT_EQ(fill_holes(w, surface, o, {}, removed), tip_sampled ? 1 : 0) << "tip sampled " << tip_sampled;
    const ValidationReport r = validate(w, tip_sampled);
    EXPECT_TRUE(r.ok()) << r.summary();
    EXPECT_EQ(r.boundary_loops, tip_sampled ? 0 : 1);
    EXPECT_EQ(r.components, 1);
  }
}

TEST(StarCandidates, JitteredPlanarSitesGiveAConsistentTriangulation) {
  // Sites of a jittered 20 x 20 grid on z = 0 with normals +z: every interior triangle of their
  // Delaunay triangulation is in the stars of its three corners, and the stars alone give a
  // manifold disk through every site.
  const int n = 20;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  Eigen::MatrixX3d V(n * n, 3), N(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      V.row(j * n + i) << i + jitter(rng), j + jitter(rng), 0;
      N.row(j * n + i) << 0, 0, 1;
    }
  WorkingMesh w(V, N, std::vector<int>(n * n, -1));
  const std::vector<DualCandidate> stars = star_candidates(w, {}, {}, 2);
  ASSERT_FALSE(stars.empty());
  int three = 0;
  for (const DualCandidate& c : stars) {
    EXPECT_GE(c.witnesses, 1);
    EXPECT_LE(c.witnesses, 3);
    three += c.witnesses == 3;
    const Eigen::Vector3d a = V.row(c.f[0]), b = V.row(c.f[1]), d = V.row(c.f[2]);
    EXPECT_GT((b - a).cross(d - a).z(), 0) << "oriented by the site normals";
  }
  // Triangles in some star but not in all three are confined to the grid's rim.
  EXPECT_GE(three, static_cast<int>(stars.size()) - 4 * n);
  const int rejected = extract_manifold(w, stars);
  EXPECT_EQ(rejected, static_cast<int>(stars.size()) - w.num_faces());
  EXPECT_LE(rejected, 4 * n) << "only along the rim do stars disagree";
  make_vertices_manifold(w, {});
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(used_vertices(w), n * n);
  // The same for any thread count.
  EXPECT_EQ(star_candidates(w, {}, {}, 1).size(), stars.size());
}

// Sites of a 20 x 12 grid on z = 0 (normals +z) with the triangles of columns 0-7 and 12-19
// only: two pieces with a strip of 3 columns of sites in no triangle between them. `rise` lifts
// the right piece and the strip's right half above the left (a depth jump).
WorkingMesh two_pieces(double rise) {
  const int nx = 20, ny = 12;
  Eigen::MatrixX3d V(nx * ny, 3), N = Eigen::MatrixX3d::Zero(nx * ny, 3);
  N.col(2).setOnes();
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) V.row(j * nx + i) << i, j, i >= 10 ? rise : 0.0;
  std::vector<MeshFace> faces;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      if (i >= 7 && i < 12) continue;
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  WorkingMesh w(V, N, std::vector<int>(nx * ny, -1));
  w.set_faces(faces);
  return w;
}

// (Fronts that meet do not zip: joining two pieces takes a triangle that first touches the other
// piece at a single vertex, which the one-fan rule refuses. The pieces stay two.)
TEST(BorderGrowth, PiecesGrowOverTheSitesBetweenThem) {
  WorkingMesh w = two_pieces(0.0);
  ASSERT_LT(used_vertices(w), w.num_vertices());
  const int before = w.num_faces();
  const int added = grow_borders(w, {});
  EXPECT_EQ(w.num_faces(), before + added);
  EXPECT_EQ(used_vertices(w), w.num_vertices());
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.boundary_loops, 2);
  Eigen::MatrixX3i F(w.num_faces(), 3);
  for (int f = 0; f < w.num_faces(); ++f) F.row(f) << w.face(f)[0], w.face(f)[1], w.face(f)[2];
  EXPECT_GE(triangle_quality(w.V, F).min_angle_deg, 20.0);
}

TEST(BorderGrowth, NoTriangleStandsAcrossADepthJump) {
  // The two halves 5 spacings apart in depth: triangles across the jump stand on edge.
  WorkingMesh w = two_pieces(5.0);
  grow_borders(w, {});
  for (const MeshFace& f : w.faces()) {
    const double zmin = std::min({w.V(f[0], 2), w.V(f[1], 2), w.V(f[2], 2)});
    const double zmax = std::max({w.V(f[0], 2), w.V(f[1], 2), w.V(f[2], 2)});
    EXPECT_EQ(zmin, zmax) << "a triangle spans the jump";
  }
  EXPECT_EQ(validate(w, false).components, 2);
}

TEST(BorderGrowth, ANearlyClosedSurfaceIsLeftToTheHoleFilling) {
  const TriangleMesh s = test::icosphere(3);
  WorkingMesh w = test::working_mesh(s);
  punch(w, Eigen::Vector3d(0, 0, 1), 0.3);
  const int faces = w.num_faces();
  EXPECT_EQ(grow_borders(w, {}), 0);
  EXPECT_EQ(w.num_faces(), faces);
}

}  // namespace
}  // namespace heatcvt
