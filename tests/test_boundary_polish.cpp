// Tests of the mesher's work on borders and stray pieces: slivers flat along the border trimmed,
// boundary vertices polished along their border, small and stray pieces dropped, and the φmin of
// boundary triangles reported. Shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/orientation.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/sliver_collapse.h"
#include "heatcvt/mesher/working_mesh.h"
#include "test_support.h"

namespace heatcvt {
namespace {

WorkingMesh working(const Eigen::MatrixX3d& V, const std::vector<MeshFace>& faces) {
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(V.rows(), 3);
  N.col(2).setOnes();
  WorkingMesh w(V, N, std::vector<int>(V.rows(), -1));
  w.set_faces(faces);
  return w;
}

Eigen::MatrixX3i face_matrix(const WorkingMesh& w) {
  Eigen::MatrixX3i F(w.num_faces(), 3);
  for (int f = 0; f < w.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = w.face(f)[k];
  return F;
}

int used_vertices(const WorkingMesh& w) {
  std::vector<char> used(w.num_vertices(), 0);
  for (const MeshFace& f : w.faces())
    for (int v : f) used[v] = 1;
  int n = 0;
  for (char u : used) n += u;
  return n;
}

// a = (0,0), b = (1,0) on the border; c just above their midpoint (the apex of a sliver flat along
// the border, 175° at c); d = (0.5, 0.8) above: faces (a,b,c), (a,c,d), (c,b,d).
WorkingMesh flat_sliver(double apex_height) {
  Eigen::MatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, apex_height, 0, 0.5, 0.8, 0;
  return working(V, {{0, 1, 2}, {0, 2, 3}, {2, 1, 3}});
}

TEST(BoundaryTrim, RemovesASliverFlatAlongTheBorderAndKeepsEveryVertex) {
  WorkingMesh w = flat_sliver(0.02);
  const TriangleQuality before = triangle_quality(w.V, face_matrix(w));
  EXPECT_EQ(before.boundary_triangles, 3);
  EXPECT_LT(before.boundary_min_angle_deg, 5);
  EXPECT_EQ(trim_boundary_slivers(w, {}), 1);
  EXPECT_EQ(w.num_faces(), 2);
  EXPECT_EQ(used_vertices(w), 4);
  const TriangleQuality after = triangle_quality(w.V, face_matrix(w));
  EXPECT_GT(after.boundary_min_angle_deg, 25);
  EXPECT_EQ(after.boundary_min_angle_deg, after.min_angle_deg);
}

TEST(BoundaryTrim, KeepsWellShapedTrianglesAndLoneSlivers) {
  const TriangleMesh g = test::grid(3);  // right isosceles triangles: no sliver
  std::vector<MeshFace> grid_faces;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) grid_faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
  WorkingMesh fine = working(g.V, grid_faces);
  EXPECT_EQ(trim_boundary_slivers(fine, {}), 0);
  // A lone sliver: removing it would orphan its corners.
  Eigen::MatrixX3d V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, 0.02, 0;
  WorkingMesh lone = working(V, {{0, 1, 2}});
  EXPECT_EQ(trim_boundary_slivers(lone, {}), 0);
  // The apex threshold and the switch are honoured (the sliver's apex angle is 177.7°).
  WorkingMesh pointed = flat_sliver(0.02);
  BoundaryTrimOptions o;
  o.min_apex_angle_deg = 179;
  EXPECT_EQ(trim_boundary_slivers(pointed, o), 0);
  o.enabled = false;
  o.min_apex_angle_deg = 120;
  EXPECT_EQ(trim_boundary_slivers(pointed, o), 0);
}

// a = (0,0), b = (1,0), d = (0.5, 0.8) above; the ear (a, c, b) below with its lone corner c at
// (0.5, -h): both of its edges at c are on the border.
WorkingMesh ear(double h) {
  Eigen::MatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, -h, 0, 0.5, 0.8, 0;
  return working(V, {{0, 2, 1}, {0, 1, 3}});
}

TEST(BoundaryTrim, CutsSliverEarsAndKeepsAWellShapedOne) {
  // Height 0.02 over an edge of 1: a flat sliver ear (1.3° at a and b); height 3: a spike (18.9°
  // at c). Both are cut: the border moves onto (a, b) and c leaves the mesh.
  for (double h : {0.02, 3.0}) {
    WorkingMesh sliver = ear(h);
    EXPECT_EQ(trim_boundary_slivers(sliver, {}), 1) << h;
    EXPECT_EQ(sliver.num_faces(), 1) << h;
    EXPECT_EQ(used_vertices(sliver), 3) << h;
  }
  // Height 0.3: 31° at a and b, 118° at c, no sliver: kept.
  WorkingMesh fine = ear(0.3);
  EXPECT_EQ(trim_boundary_slivers(fine, {}), 0);
  EXPECT_EQ(fine.num_faces(), 2);
}

// A unit grid with a ribbon one triangle wide (height 0.02 over edges of 1/6: 13.5° at its base
// corners) leaving its right border at the bottom corner: every ribbon triangle has all three
// corners on the border, so no vertex move opens it and no single-apex trim applies.
WorkingMesh grid_with_ribbon(int segments, int* grid_faces) {
  const int n = 6;
  const TriangleMesh g = test::grid(n, 0, 1, 0, 1, true);
  const double step = 1.0 / n, width = 0.02;
  const int b0 = n, q = n + (n + 1);  // bottom-right corner and the vertex above it
  EXPECT_NEAR(g.V(b0, 0), 1.0, 1e-12);
  EXPECT_NEAR(g.V(b0, 1), 0.0, 1e-12);
  EXPECT_NEAR(g.V(q, 1), step, 1e-12);
  Eigen::MatrixX3d V(g.V.rows() + 2 * segments + 1, 3);
  V.topRows(g.V.rows()) = g.V;
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
  *grid_faces = static_cast<int>(faces.size());
  // Bottom vertices B_k = (1 + k step, 0), k = 1..segments (B_0 = b0); top T_k = (1 + (k + 1/2) step, width).
  const auto bottom = [&](int k) { return k == 0 ? b0 : static_cast<int>(g.V.rows()) + k - 1; };
  const auto top = [&](int k) { return static_cast<int>(g.V.rows()) + segments + k; };
  for (int k = 1; k <= segments; ++k) V.row(bottom(k)) << 1 + k * step, 0, 0;
  for (int k = 0; k <= segments; ++k) V.row(top(k)) << 1 + (k + 0.5) * step, width, 0;
  faces.push_back({q, b0, top(0)});
  for (int k = 0; k < segments; ++k) {
    faces.push_back({bottom(k), bottom(k + 1), top(k)});
    faces.push_back({top(k), bottom(k + 1), top(k + 1)});
  }
  return working(V, faces);
}

TEST(BoundaryTrim, CutsARibbonOneTriangleWide) {
  int grid_faces = 0;
  WorkingMesh w = grid_with_ribbon(4, &grid_faces);
  ASSERT_LT(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 15);
  // Without cut_necks only the ear at the ribbon's end goes; its other slivers stay, as their
  // apexes are on the border.
  BoundaryTrimOptions keep;
  keep.cut_necks = false;
  WorkingMesh kept = w;
  EXPECT_LE(trim_boundary_slivers(kept, keep), 1);
  EXPECT_LT(triangle_quality(kept.V, face_matrix(kept)).min_angle_deg, 15);
  // With it the ribbon is cut at its root; what is left of it is a small piece.
  EXPECT_GT(trim_boundary_slivers(w, {}), 0);
  remove_small_pieces(w, 20);
  EXPECT_GE(w.num_faces(), grid_faces) << "the grid is kept";
  EXPECT_LE(w.num_faces(), grid_faces + 1);
  EXPECT_GE(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 25);
  EXPECT_EQ(self_intersecting_pairs(w), 0);
  // Every vertex in faces has a single fan (the mesh is a manifold with boundary).
  const std::vector<std::vector<int>> vf = w.vertex_faces();
  for (int v = 0; v < w.num_vertices(); ++v)
    if (!vf[v].empty()) EXPECT_EQ(vertex_fans(w, v, vf[v]).size(), 1u) << v;
}

// A grid whose bottom border vertex 3 (two faces, both with the interior vertex 10 above it) is
// pulled three rows' height out of the border: a spike with a surface angle of 36.9° there.
TEST(BoundaryTrim, CutsASpikeOfTheBorder) {
  const int n = 6;
  const TriangleMesh g = test::grid(n, 0, 1, 0, 1, true);
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
  WorkingMesh w = working(g.V, faces);
  const int tip = 3, inner = 3 + n + 1;
  ASSERT_EQ(w.vertex_faces()[tip].size(), 2u);
  ASSERT_FALSE(w.boundary_vertices()[inner]);
  w.V(tip, 1) = -3.0 / n;
  ASSERT_LT(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 25);
  // With spike_angle_deg 0 the spike stays: no other trim applies to it.
  BoundaryTrimOptions no_spikes;
  no_spikes.spike_angle_deg = 0;
  WorkingMesh kept = w;
  EXPECT_EQ(trim_boundary_slivers(kept, no_spikes), 0);
  EXPECT_EQ(trim_boundary_slivers(w, {}), 2);
  EXPECT_EQ(used_vertices(w), static_cast<int>(g.V.rows()) - 1);
  EXPECT_TRUE(w.vertex_faces()[tip].empty());
  EXPECT_TRUE(w.boundary_vertices()[inner]) << "the border moves onto the spike's interior vertex";
  EXPECT_GE(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 25);
  const std::vector<std::vector<int>> vf = w.vertex_faces();
  for (int v = 0; v < w.num_vertices(); ++v)
    if (!vf[v].empty()) EXPECT_EQ(vertex_fans(w, v, vf[v]).size(), 1u) << v;
}

// A fan around the border vertex 0 of a grid, with the interior vertex next to it pulled within
// 2 % of an edge of it: its faces are slivers that no move of vertex 0 (on the border) opens.
TEST(SliverCollapse, AnInteriorVertexGoesIntoTheBorderVertexNextToIt) {
  const TriangleMesh g = test::grid(6, 0, 1, 0, 1, true);
  const MeshSurfaceProjector plane(g.V, g.F);
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
  WorkingMesh w = working(g.V, faces);
  const std::vector<char> border = w.boundary_vertices();
  // Vertex 3 of the bottom row is on the border; the one above it (index 3 + 7) is interior.
  const int b = 3, inner = 3 + 7;
  ASSERT_TRUE(border[b]);
  ASSERT_FALSE(border[inner]);
  w.V.row(inner) = w.V.row(b) + Eigen::RowVector3d(0.0, 0.02 / 6, 0.0);
  ASSERT_LT(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 5);
  const Eigen::MatrixX3d before = w.V;
  MesherStats stats;
  EXPECT_GE(collapse_slivers(w, plane, {}, stats), 1);
  EXPECT_EQ(used_vertices(w), static_cast<int>(g.V.rows()) - 1);
  const std::vector<char> after = w.boundary_vertices();
  for (int v = 0; v < w.num_vertices(); ++v)
    if (border[v]) {
      EXPECT_TRUE(after[v]) << v;
      EXPECT_EQ((w.V.row(v) - before.row(v)).norm(), 0.0) << "border vertex " << v << " keeps its place";
    }
  EXPECT_GT(triangle_quality(w.V, face_matrix(w)).min_angle_deg, 25);
}

// The sliver pair (a, b, c), (b, a, d) with a = (0,0), b = (1,0), c = (0.5, 0.1), d = (0.5, -0.1)
// (11.3° at a and b), fanned out to e = (-1, 0) and f = (2, 0) so that a and b have valence 4; on
// the roof z = -lift·|y|, with a, b, e, f on its ridge and the normals of the roof.
WorkingMesh sliver_pair(double lift) {
  Eigen::MatrixX3d V(6, 3), N(6, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, 0.1, -0.1 * lift, 0.5, -0.1, -0.1 * lift, -1, 0, 0, 2, 0, 0;
  N << 0, 0, 1, 0, 0, 1, 0, lift, 1, 0, -lift, 1, 0, 0, 1, 0, 0, 1;
  N.rowwise().normalize();
  WorkingMesh w(V, N, std::vector<int>(6, -1));
  w.set_faces({{0, 1, 2}, {1, 0, 3}, {0, 2, 4}, {0, 4, 3}, {1, 5, 2}, {1, 3, 5}});
  return w;
}

// The roof z = -lift·|y| over [-2, 3] x [-1, 1], finely tessellated, ridge along y = 0.
TriangleMesh roof(double lift) {
  TriangleMesh g = test::grid(40, -2, 3, -1, 1, false);
  for (Eigen::Index v = 0; v < g.V.rows(); ++v) g.V(v, 2) = -lift * std::abs(g.V(v, 1));
  return g;
}

TEST(SliverFlip, FlipsWhereTheNewEdgeLiesOnTheSurfaceOnly) {
  // On a plane the flip to (c, d) lifts the smallest angle from 11.3° to 22.6°.
  const TriangleMesh flat = roof(0.0);
  const MeshSurfaceProjector plane(flat.V, flat.F);
  WorkingMesh w = sliver_pair(0.0);
  EXPECT_EQ(flip_sliver_edges(w, plane, {}, std::vector<char>(6, 0)), 1);
  EXPECT_GT(w.edge_face_count(2, 3), 0);
  EXPECT_EQ(w.edge_face_count(0, 1), 0);
  // Frozen corners are left alone.
  WorkingMesh held = sliver_pair(0.0);
  EXPECT_EQ(flip_sliver_edges(held, plane, {}, std::vector<char>{0, 0, 1, 0, 0, 0}), 0);
  // On a roof (slopes at 45°) the edge (a, b) runs along the ridge; (c, d) would pass 0.07
  // below it (0.35 of its length): refused.
  const TriangleMesh ridge = roof(1.0);
  const MeshSurfaceProjector roof_surface(ridge.V, ridge.F);
  WorkingMesh r = sliver_pair(1.0);
  EXPECT_EQ(flip_sliver_edges(r, roof_surface, {}, std::vector<char>(6, 0)), 0);
  EXPECT_GT(r.edge_face_count(0, 1), 0);
  SliverFlipOptions loose;
  loose.max_offset = 0.5;  // the offset is what refused it
  EXPECT_EQ(flip_sliver_edges(r, roof_surface, loose, std::vector<char>(6, 0)), 1);
}

TEST(BoundaryPolish, ABorderVertexSlidesAlongItsBorder) {
  // A grid whose bottom-border vertex 3 is pushed along the border next to vertex 2.
  const TriangleMesh g = test::grid(6, 0, 1, 0, 1, true);
  const MeshSurfaceProjector plane(g.V, g.F);
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < g.F.rows(); ++f) faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
  for (bool boundary : {false, true}) {
    WorkingMesh w = working(g.V, faces);
    w.V(3, 0) = w.V(2, 0) + 0.15 / 6;
    const double before = triangle_quality(w.V, face_matrix(w)).min_angle_deg;
    AnglePolishOptions o;
    o.boundary = boundary;
    angle_polish(w, plane, 5, std::vector<char>(w.num_vertices(), 0), o, 2);
    const double after = triangle_quality(w.V, face_matrix(w)).min_angle_deg;
    EXPECT_NEAR(w.V(3, 1), 0.0, 1e-12) << "stays on the border";
    if (boundary) EXPECT_GT(after, before + 10);
    else EXPECT_NEAR(w.V(3, 0), w.V(2, 0) + 0.15 / 6, 1e-12) << "interior-only polish leaves it";
  }
}

TEST(SmallPieces, StrayPiecesBelowAFractionOfTheVerticesAreDropped) {
  const TriangleMesh big = test::grid(10);
  Eigen::MatrixX3d V(big.V.rows() + 4, 3);
  V.topRows(big.V.rows()) = big.V;
  V.bottomRows(4) << 5, 5, 0, 6, 5, 0, 5, 6, 0, 6, 6, 0;  // a separate square of two triangles
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < big.F.rows(); ++f) faces.push_back({big.F(f, 0), big.F(f, 1), big.F(f, 2)});
  const int s = static_cast<int>(big.V.rows());
  faces.push_back({s, s + 1, s + 3});
  faces.push_back({s, s + 3, s + 2});
  for (double fraction : {0.0, 0.01, 0.05}) {
    WorkingMesh w = working(V, faces);
    int pieces = 0;
    const int removed = remove_small_pieces(w, 0, fraction, &pieces);
    // 4 of 125 vertices: 3.2 %.
    EXPECT_EQ(pieces, fraction > 0.032 ? 1 : 0) << fraction;
    EXPECT_EQ(removed, fraction > 0.032 ? 2 : 0) << fraction;
  }
  // Never everything: a mesh of small pieces only is kept.
  WorkingMesh w = working(V.bottomRows(4), {{0, 1, 3}, {0, 3, 2}});
  EXPECT_EQ(remove_small_pieces(w, 20, 0.5), 0);
}

}  // namespace
}  // namespace heatcvt
