// Tests of the mesher's sizing stage (mesher/isotropic_remesh.h): the vertex count asked for,
// topology and borders kept, shape targets reached, flying faces removed, the border's noise
// cleaned, the same result for any thread count. Shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/isotropic_remesh.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/remesh.h"
#include "heatcvt/shapes.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

// The working mesh of a triangle mesh, its vertices projected onto `surface`.
WorkingMesh working(const TriangleMesh& m, const SurfaceProjector& surface) {
  WorkingMesh w(m.V, Eigen::MatrixX3d::Zero(m.V.rows(), 3), std::vector<int>(m.V.rows(), -1));
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
    Eigen::Vector3d p, n;
    surface.project(m.V.row(v).transpose(), w.anchor[v], p, n);
    w.V.row(v) = p.transpose();
    w.N.row(v) = n.transpose();
  }
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) faces.push_back({m.F(f, 0), m.F(f, 1), m.F(f, 2)});
  w.set_faces(faces);
  return w;
}

ValidationReport validate_open(const TriangleMesh& m) {
  ValidationOptions o;
  o.require_closed = false;
  return validate_triangle_mesh(m.V, m.F, o);
}

// The sized working mesh compacted, checked and returned: valid as an open surface with `loops`
// border loops, the count within 2 % of `target`, φmin ≥ 25°.
TriangleMesh expect_sized_open(const WorkingMesh& w, int target, int loops) {
  const TriangleMesh m = compact_mesh(w);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.boundary_loops, loops);
  EXPECT_NEAR(m.V.rows(), target, 0.02 * target);
  EXPECT_GE(triangle_quality(m.V, m.F).min_angle_deg, 25.0);
  return m;
}

IsotropicRemeshOptions sized_to(int target) {
  IsotropicRemeshOptions o;
  o.target_vertices = target;
  return o;
}

// Grid of n×n quads on [0,1]² with faces of the border cells removed at random, each only where
// the rest stays a manifold with one border loop: a ragged border at the grid spacing.
TriangleMesh ragged_square(int n, unsigned seed) {
  TriangleMesh m = test::grid(n);
  std::mt19937 rng(seed);
  ValidationOptions topology_only;
  topology_only.require_closed = false;
  topology_only.check_self_intersections = false;
  for (Eigen::Index f = m.F.rows() - 1; f >= 0; --f) {
    const Eigen::Vector3d c = (m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))).transpose() / 3.0;
    if (std::min({c.x(), 1 - c.x(), c.y(), 1 - c.y()}) > 1.0 / n || rng() % 3 != 0) continue;
    Eigen::MatrixX3i rest(m.F.rows() - 1, 3);
    rest << m.F.topRows(f), m.F.bottomRows(m.F.rows() - f - 1);
    const ValidationReport v = validate_triangle_mesh(m.V, rest, topology_only);
    if (v.ok() && v.boundary_loops == 1 && v.vertices == m.V.rows()) m.F = rest;
  }
  return m;
}

TEST(IsotropicRemesh, CoarseSphereIsRefinedToTheCountWithTheShapeTargets) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = working(test::icosphere(2), surface);  // 162 vertices
  MesherStats stats;
  ASSERT_TRUE(needs_sizing(w, surface, sized_to(1000)));
  ASSERT_TRUE(size_to_target(w, surface, sized_to(1000), stats));
  const TriangleMesh m = compact_mesh(w);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.genus, 0);
  EXPECT_EQ(v.boundary_loops, 0);
  EXPECT_NEAR(m.V.rows(), 1000, 10);  // within half the 2 % tolerance
  const TriangleQuality q = triangle_quality(m.V, m.F);
  EXPECT_GE(q.min_angle_deg, 25.0);
  EXPECT_GE(q.mean_min_angle_deg, 52.0);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) EXPECT_NEAR(m.V.row(i).norm(), 1.0, 2e-3);  // on icosphere(5)
}

TEST(IsotropicRemesh, TorusIsCoarsenedToTheCountAndKeepsItsHandle) {
  const TriangleMesh torus = test::torus(60, 30);
  const MeshSurfaceProjector surface(torus.V, torus.F);
  WorkingMesh w = working(torus, surface);  // 1,800 vertices
  MesherStats stats;
  ASSERT_TRUE(size_to_target(w, surface, sized_to(500), stats));
  const TriangleMesh m = compact_mesh(w);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.genus, 1);
  EXPECT_EQ(v.components, 1);
  EXPECT_EQ(v.boundary_loops, 0);
  EXPECT_NEAR(m.V.rows(), 500, 5);
  EXPECT_GE(triangle_quality(m.V, m.F).mean_min_angle_deg, 52.0);
}

// Coarsening a sphere with a thin spike: the spike's end (a tip, tips.h) stays a vertex at its
// place (at remesh_cvt()'s threshold); without tips held the collapses and the polish take it (so the test can fail).
TEST(IsotropicRemesh, TheEndOfAThinSpikeSurvivesTheCoarsening) {
  const TriangleMesh spiked = test::spiked_sphere(3, 1.3);  // 642 vertices
  const MeshSurfaceProjector surface(spiked.V, spiked.F);
  const Eigen::Vector3d end = spiked.V.row(0).transpose();
  const auto coarsened = [&](double min_defect_deg) {
    WorkingMesh w = working(spiked, surface);
    IsotropicRemeshOptions o = sized_to(300);
    o.tips.min_defect_deg = min_defect_deg;
    MesherStats stats;
    EXPECT_TRUE(size_to_target(w, surface, o, stats));
    return w;
  };
  const WorkingMesh held = coarsened(kRemeshTipDefectDeg);
  TipOptions on;
  on.min_defect_deg = kRemeshTipDefectDeg;
  ASSERT_EQ(tip_vertices(working(spiked, surface), on)[0], 1);
  EXPECT_GT(held.valence(0), 0);
  EXPECT_LT((held.V.row(0).transpose() - end).norm(), 1e-12);
  const TriangleMesh m = compact_mesh(held);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.genus, 0);
  EXPECT_NEAR(m.V.rows(), 300, 6);  // the 2 % tolerance
  const WorkingMesh free = coarsened(0);
  EXPECT_TRUE(free.valence(0) == 0 || (free.V.row(0).transpose() - end).norm() > 0.05)
      << "without the tips held, the sizing must cut the spike short for this test to mean anything";
}

TEST(IsotropicRemesh, RaggedBorderIsResampledAndKeepsItsLoop) {
  // The surface reaches well beyond the square (as a scan's fitted surface has no border of its
  // own): the border is resampled along its own course.
  const TriangleMesh plane = test::grid(80, -0.5, 1.5, -0.5, 1.5);
  const MeshSurfaceProjector surface(plane.V, plane.F);
  const TriangleMesh ragged = ragged_square(16, 7);
  ASSERT_TRUE(validate_open(ragged).ok());
  ASSERT_EQ(validate_open(ragged).boundary_loops, 1);
  ASSERT_LT(triangle_quality(ragged.V, ragged.F).boundary_min_angle_deg, 46.0);  // right triangles and notches
  WorkingMesh w = working(ragged, surface);
  MesherStats stats;
  ASSERT_TRUE(size_to_target(w, surface, sized_to(400), stats));
  const TriangleMesh m = compact_mesh(w);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.boundary_loops, 1);
  EXPECT_EQ(v.components, 1);
  EXPECT_NEAR(m.V.rows(), 400, 4);
  const TriangleQuality q = triangle_quality(m.V, m.F);
  EXPECT_GE(q.boundary_min_angle_deg, 25.0);
  EXPECT_GE(q.min_angle_deg, 25.0);
  EXPECT_GE(q.mean_min_angle_deg, 52.0);
  // The border stays within one target edge length of the input's border (not drawn in).
  const double spacing = std::sqrt(2.0 / (std::sqrt(3.0) * 400));
  const WorkingMesh input = working(ragged, surface);
  const BorderLinks in_border = border_links(input), out_border = border_links(w);
  for (int i = 0; i < w.num_vertices(); ++i) {
    if (!out_border.on(i)) continue;
    double nearest = 1e9;
    for (int j = 0; j < input.num_vertices(); ++j)
      if (in_border.on(j)) nearest = std::min(nearest, (w.V.row(i) - input.V.row(j)).norm());
    EXPECT_LE(nearest, spacing) << "border vertex " << i;
  }
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) EXPECT_NEAR(m.V(i, 2), 0.0, 1e-12);
}

// An input mesh's border is the output's: a mesh whose border is inset by 1.5 target edge
// lengths from the surface's (the dual of a CVT on an open mesh) gets its border moved onto it.
TEST(IsotropicRemesh, InsetBorderIsMovedOntoTheSurfacesBorder) {
  const TriangleMesh plane = test::grid(40);  // the unit square: its border is known
  const MeshSurfaceProjector surface(plane.V, plane.F);
  ASSERT_TRUE(surface.has_border());
  const int target = 400;
  const double spacing = std::sqrt(2.0 / (std::sqrt(3.0) * target));
  const double inset = 1.5 * spacing;
  WorkingMesh w = working(test::grid(10, inset, 1 - inset, inset, 1 - inset), surface);
  MesherStats stats;
  ASSERT_TRUE(needs_sizing(w, surface, sized_to(target)));
  ASSERT_TRUE(size_to_target(w, surface, sized_to(target), stats));
  const TriangleMesh m = expect_sized_open(w, target, 1);
  EXPECT_GE(triangle_quality(m.V, m.F).mean_min_angle_deg, 52.0);
  // Every border vertex on the square's border; every point of it within one spacing of one.
  const BorderLinks border = border_links(w);
  std::vector<Eigen::Vector3d> on_border;
  for (int i = 0; i < w.num_vertices(); ++i)
    if (border.on(i)) {
      const Eigen::Vector3d x = w.V.row(i);
      EXPECT_NEAR(std::min({x.x(), 1 - x.x(), x.y(), 1 - x.y()}), 0.0, 1e-9) << "border vertex " << i;
      on_border.push_back(x);
    }
  for (int k = 0; k < 400; ++k) {
    const double t = k / 100.0;  // around the square, 100 samples a side
    const int side = k / 100;
    const double u = t - side;
    const Eigen::Vector3d p = side == 0 ? Eigen::Vector3d(u, 0, 0)
                              : side == 1 ? Eigen::Vector3d(1, u, 0)
                              : side == 2 ? Eigen::Vector3d(1 - u, 1, 0)
                                          : Eigen::Vector3d(0, 1 - u, 0);
    double nearest = 1e9;
    for (const Eigen::Vector3d& x : on_border) nearest = std::min(nearest, (x - p).norm());
    EXPECT_LE(nearest, spacing) << "border point " << p.transpose();
  }
}

// The n×n grid on [0,1]² without the faces whose centroid lies in [lo, hi]² (a square hole).
TriangleMesh grid_with_hole(int n, double lo, double hi) {
  const TriangleMesh g = test::grid(n);
  std::vector<Eigen::RowVector3i> kept;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) {
    const Eigen::Vector3d c = (g.V.row(g.F(f, 0)) + g.V.row(g.F(f, 1)) + g.V.row(g.F(f, 2))).transpose() / 3.0;
    if (!(c.x() > lo && c.x() < hi && c.y() > lo && c.y() < hi)) kept.push_back(g.F.row(f));
  }
  TriangleMesh m;
  m.V = g.V;
  m.F.resize(kept.size(), 3);
  for (std::size_t f = 0; f < kept.size(); ++f) m.F.row(f) = kept[f];
  return m;
}

TEST(IsotropicRemesh, ABorderCuttingTheCornersOfAHoleGetsVerticesAtThem) {
  // The surface: the unit square with a square hole [0.4, 0.6]² (its border is known). The start:
  // a 10 × 10 grid with the same hole, but each corner of the hole covered by a triangle, so
  // the hole's border is four chords between the midpoints of its sides, its vertices all on the
  // surface's border (as a coarse dual leaves a hole two spacings wide).
  const TriangleMesh plane = grid_with_hole(40, 0.4, 0.6);
  const MeshSurfaceProjector surface(plane.V, plane.F);
  ASSERT_TRUE(surface.has_border());
  TriangleMesh start = grid_with_hole(10, 0.4, 0.6);
  const auto at = [](int i, int j) { return j * 11 + i; };
  const int corners[4][3] = {{at(4, 4), at(5, 4), at(4, 5)}, {at(6, 4), at(6, 5), at(5, 4)},
                             {at(6, 6), at(5, 6), at(6, 5)}, {at(4, 6), at(4, 5), at(5, 6)}};
  start.F.conservativeResize(start.F.rows() + 4, 3);
  for (int k = 0; k < 4; ++k) start.F.row(start.F.rows() - 4 + k) << corners[k][0], corners[k][1], corners[k][2];
  start = compact_mesh(working(start, surface));  // without the grid's centre, in no face
  ASSERT_TRUE(validate_open(start).ok()) << validate_open(start).summary();
  const int target = static_cast<int>(start.V.rows());
  WorkingMesh w = working(start, surface);
  const SizingFigures before = sizing_figures(w, surface, sized_to(target));
  // Precondition: every border vertex is on the surface's border; the chords are what is off.
  ASSERT_LE(before.border_gap, sized_to(target).border_tolerance);
  ASSERT_GT(before.border_chord_gap, sized_to(target).border_chord_tolerance);
  ASSERT_TRUE(needs_sizing(w, surface, sized_to(target)));
  MesherStats stats;
  ASSERT_TRUE(size_to_target(w, surface, sized_to(target), stats));
  const SizingFigures after = sizing_figures(w, surface, sized_to(target));
  EXPECT_LE(after.border_gap, sized_to(target).border_tolerance);
  EXPECT_LE(after.border_chord_gap, sized_to(target).border_chord_tolerance);
  // A border vertex at each corner of the hole.
  const BorderLinks border = border_links(w);
  for (const Eigen::Vector3d corner : {Eigen::Vector3d(0.4, 0.4, 0), Eigen::Vector3d(0.6, 0.4, 0),
                                       Eigen::Vector3d(0.6, 0.6, 0), Eigen::Vector3d(0.4, 0.6, 0)}) {
    double nearest = 1e9;
    for (int i = 0; i < w.num_vertices(); ++i)
      if (border.on(i)) nearest = std::min(nearest, (w.V.row(i).transpose() - corner).norm());
    EXPECT_LE(nearest, 1e-6) << "hole corner " << corner.transpose();
  }
  expect_sized_open(w, target, 2);
}

// The rule that keeps or refuses a sizing result, on figures built by hand (target 1,000).
TEST(IsotropicRemesh, ResultIsKeptOnlyWhenNoWorseOnAnyTargetOrBetterOnMore) {
  const IsotropicRemeshOptions o = sized_to(1000);
  const double deg = M_PI / 180;
  auto figures = [&](int vertices, double min_deg, double mean_deg, double below, double gap) {
    SizingFigures f;
    f.vertices = vertices;
    f.min_angle = min_deg * deg;
    f.mean_angle = mean_deg * deg;
    f.below = below;
    f.border_gap = gap;
    return f;
  };
  const SizingFigures good = figures(1000, 30, 53, 0, 0);
  // Count to within 2 %, shape kept: kept; a count farther off, or φmin / φm lost: refused.
  EXPECT_TRUE(sizing_no_worse(good, figures(950, 30, 53, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(900, 30, 53, 0, 0), figures(950, 30, 53, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 20, 53, 0.01, 0), figures(950, 30, 53, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 30, 50, 0, 0), figures(950, 30, 53, 0, 0), o));
  // Below the φmin target before: a smaller share of faces below it is enough.
  EXPECT_TRUE(sizing_no_worse(figures(1000, 10, 53, 0.01, 0), figures(950, 5, 53, 0.02, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 10, 53, 0.03, 0), figures(950, 5, 53, 0.02, 0), o));
  // A mesh off the count by more than count_first_error (25 %): the count first, φmin may drop.
  EXPECT_TRUE(sizing_no_worse(figures(1000, 5, 45, 0.05, 0), figures(600, 30, 44, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 5, 43, 0.05, 0), figures(600, 30, 44, 0, 0), o));  // φm may not
  EXPECT_FALSE(sizing_no_worse(figures(1000, 5, 45, 0.05, 0), figures(800, 30, 44, 0, 0), o));  // 20 % off only
  // ... and φm may drop by count_first_mean_slack_deg (2°) where φmin stays ≥ traded_min_angle_deg (20°).
  EXPECT_TRUE(sizing_no_worse(figures(1000, 24, 42.6, 0.001, 0), figures(600, 26, 44.5, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 24, 42.4, 0.001, 0), figures(600, 26, 44.5, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 19, 44, 0.001, 0), figures(600, 26, 44.5, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 24, 43, 0.001, 0), figures(800, 26, 44.5, 0, 0), o));  // 20 % off only
  // A border brought onto the surface's own may cost up to 1° of φmin and φm; a border moved off
  // it is refused.
  EXPECT_TRUE(sizing_no_worse(figures(1000, 24.5, 51.5, 0.001, 0), figures(1000, 30, 53, 0, 2.5), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 23.5, 53, 0.001, 0), figures(1000, 30, 53, 0, 2.5), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 30, 53, 0, 0.5), good, o));
  // More of the three targets met (count and φm against φmin alone): kept while φmin stays at
  // least traded_min_angle_deg (20°).
  EXPECT_TRUE(sizing_no_worse(figures(1000, 22, 52.5, 0.002, 0), figures(970, 25.5, 49, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 19, 52.5, 0.002, 0), figures(970, 25.5, 49, 0, 0), o));
  EXPECT_FALSE(sizing_no_worse(figures(1000, 22, 51.5, 0.002, 0), figures(970, 25.5, 49, 0, 0), o));
}

// The bridge of FlyingFacesAcrossADepthJumpAreRemoved with the upper sheet shifted by `shift` in x.
void expect_bridge_removed(double shift) {
  const TriangleMesh lower = test::grid(10, 0, 1, 0, 1), upper = test::grid(10, 1 + shift, 2 + shift, 0, 1);
  TriangleMesh both;
  both.V.resize(lower.V.rows() + upper.V.rows(), 3);
  both.V << lower.V, upper.V;
  both.V.bottomRows(upper.V.rows()).col(2).setConstant(0.5);
  const int off = static_cast<int>(lower.V.rows());
  std::vector<Eigen::Vector3i> faces;
  for (Eigen::Index f = 0; f < lower.F.rows(); ++f) faces.push_back(lower.F.row(f).transpose());
  for (Eigen::Index f = 0; f < upper.F.rows(); ++f) faces.push_back(upper.F.row(f).transpose() + Eigen::Vector3i::Constant(off));
  const TriangleMesh surface_mesh = [&] {
    TriangleMesh s;
    s.V = both.V;
    s.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
    for (size_t f = 0; f < faces.size(); ++f) s.F.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
    return s;
  }();
  // Bridge: the lower grid's column x = 1 (vertex 11 j + 10) to the upper grid's x = 1 (11 j).
  for (int j = 0; j < 10; ++j) {
    const int a = 11 * j + 10, b = 11 * (j + 1) + 10, c = off + 11 * j, d = off + 11 * (j + 1);
    faces.push_back({a, c, b});
    faces.push_back({b, c, d});
  }
  both.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) both.F.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
  const MeshSurfaceProjector surface(surface_mesh.V, surface_mesh.F);
  WorkingMesh w = working(both, surface);
  MesherStats stats;
  EXPECT_EQ(remove_flying_faces(w, surface, sized_to(242)), 20);
  ASSERT_TRUE(size_to_target(w, surface, sized_to(242), stats));
  for (const MeshFace& f : w.faces()) {
    const double zmin = std::min({w.V(f[0], 2), w.V(f[1], 2), w.V(f[2], 2)});
    const double zmax = std::max({w.V(f[0], 2), w.V(f[1], 2), w.V(f[2], 2)});
    EXPECT_LT(zmax - zmin, 1e-9) << "a face still spans the jump";
  }
  const TriangleMesh m = compact_mesh(w);
  EXPECT_EQ(validate_open(m).components, 2);
  EXPECT_NEAR(m.V.rows(), 242, 3);
}

TEST(IsotropicRemesh, FlyingFacesAcrossADepthJumpAreRemoved) {
  // Two parallel sheets (z = 0 and z = 0.5) as the surface; the mesh is both grids plus a strip
  // of faces bridging their facing edges (what a hole fill across a depth jump makes): upright
  // (the upper sheet starts at x = 1) and tilted 65° (it starts at x = 1 + 0.5 / tan 65°).
  for (const double shift : {0.0, 0.5 / std::tan(65 * M_PI / 180)}) {
    SCOPED_TRACE(shift);
    expect_bridge_removed(shift);
  }
}


// Smallest angle over the faces of `mesh` whose vertices are all in [first, last).
double smallest_angle_of(const WorkingMesh& mesh, int first, int last) {
  double m = 180;
  for (const MeshFace& f : mesh.faces())
    if (f[0] >= first && f[0] < last) m = std::min(m, face_min_angle(mesh, f) * 180 / M_PI);
  return m;
}

TEST(IsotropicRemesh, SliversOfOpenPiecesAreCutAndClosedPiecesKeepEveryFace) {
  // An open sheet (a 10 × 10 grid) and a closed sphere far from it, each with one vertex pushed
  // almost onto an edge of its ring: slivers in both pieces.
  TriangleMesh sheet = test::grid(10, 0, 1, 0, 1), ball = test::icosphere(2);
  sheet.V.row(11 * 5 + 5) += Eigen::RowVector3d(0.095, 0.0, 0.0);
  ball.V.row(ball.F(0, 0)) = 0.2 * ball.V.row(ball.F(0, 0)) + 0.8 * ball.V.row(ball.F(0, 1));
  ball.V.rowwise() += Eigen::RowVector3d(5, 0, 0);
  const int ns = static_cast<int>(sheet.V.rows()), nb = static_cast<int>(ball.V.rows());
  Eigen::MatrixX3d V(ns + nb, 3);
  V << sheet.V, ball.V;
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(ns + nb, 3), std::vector<int>(ns + nb, -1));
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < sheet.F.rows(); ++f) faces.push_back({sheet.F(f, 0), sheet.F(f, 1), sheet.F(f, 2)});
  for (Eigen::Index f = 0; f < ball.F.rows(); ++f) faces.push_back({ball.F(f, 0) + ns, ball.F(f, 1) + ns, ball.F(f, 2) + ns});
  w.set_faces(faces);
  const IsotropicRemeshOptions o;
  ASSERT_LT(smallest_angle_of(w, 0, ns), o.min_angle_deg);        // precondition: slivers in the sheet
  ASSERT_LT(smallest_angle_of(w, ns, ns + nb), o.min_angle_deg);  // ... and in the ball
  int ball_faces = 0;
  for (const MeshFace& f : w.faces()) ball_faces += f[0] >= ns;

  const int cut = cut_unrepairable_slivers(w, o);
  EXPECT_GT(cut, 0);
  EXPECT_GE(smallest_angle_of(w, 0, ns), o.min_angle_deg);
  int ball_left = 0;
  for (const MeshFace& f : w.faces()) ball_left += f[0] >= ns;
  EXPECT_EQ(ball_left, ball_faces);
  EXPECT_EQ(w.num_faces() + cut, static_cast<int>(faces.size()));
  const TriangleMesh m = compact_mesh(w);
  const ValidationReport v = validate_open(m);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.components, 2);
}

TEST(IsotropicRemesh, MeshesMeetingTheTargetsAreLeftAlone) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = working(test::icosphere(3), surface);  // 642 vertices, φmin 50°+
  const WorkingMesh::Checkpoint before = w.checkpoint();
  MesherStats stats;
  EXPECT_FALSE(needs_sizing(w, surface, sized_to(645)));
  EXPECT_FALSE(size_to_target(w, surface, sized_to(645), stats));
  EXPECT_EQ(w.V, before.V);
  EXPECT_EQ(w.faces(), before.faces);
  IsotropicRemeshOptions off;  // target 0: the stage is off
  EXPECT_FALSE(size_to_target(w, surface, off, stats));
}

TEST(IsotropicRemesh, FacesCrossingAtTheStartAreLeftAloneAndNoCrossingIsAdded) {
  // Two sheets through each other (coarse, so that the sizing refines them): their crossing is
  // frozen, every step that would make another crossing is redone around it.
  const TriangleMesh sheets = interpenetrating_sheets_mesh(8);
  const TriangleMesh fine = interpenetrating_sheets_mesh(40);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = working(sheets, surface);
  const long crossing_before = self_intersecting_pairs(w);
  ASSERT_GT(crossing_before, 0) << "precondition: the sheets cross";
  const int target = 3 * static_cast<int>(sheets.V.rows());
  MesherStats stats;
  ASSERT_TRUE(size_to_target(w, surface, sized_to(target), stats));
  EXPECT_LE(self_intersecting_pairs(w), crossing_before);
  const TriangleMesh m = compact_mesh(w);
  ValidationOptions topology_only;
  topology_only.require_closed = false;
  topology_only.check_self_intersections = false;
  const ValidationReport v = validate_triangle_mesh(m.V, m.F, topology_only);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.components, 2);
  EXPECT_EQ(v.boundary_loops, 2);
  EXPECT_NEAR(m.V.rows(), target, 0.01 * target);
}

TEST(IsotropicRemesh, SameResultForAnyThreadCount) {
  const TriangleMesh plane = test::grid(40);
  const MeshSurfaceProjector surface(plane.V, plane.F);
  const TriangleMesh ragged = ragged_square(12, 3);
  std::vector<WorkingMesh> results;
  for (int threads : test::kThreadCounts) {
    WorkingMesh w = working(ragged, surface);
    IsotropicRemeshOptions o = sized_to(300);
    o.threads = threads;
    MesherStats stats;
    ASSERT_TRUE(size_to_target(w, surface, o, stats));
    results.push_back(w);
  }
  for (size_t i = 1; i < results.size(); ++i) {
    EXPECT_EQ(results[i].V, results[0].V);
    EXPECT_EQ(results[i].faces(), results[0].faces());
  }
}

}  // namespace
}  // namespace heatcvt
