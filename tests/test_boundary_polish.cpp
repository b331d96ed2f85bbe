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
