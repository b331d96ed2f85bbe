// The self-intersection test of the working mesh (mesher/mesh_checks.h): the same face pairs as
// the CGAL check of validate_triangle_mesh(), including faces that share an edge or a vertex.
// Shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "heatcvt/mesh.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/shapes.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

WorkingMesh working(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(V.rows(), 3), std::vector<int>(V.rows(), -1));
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < F.rows(); ++f) faces.push_back({F(f, 0), F(f, 1), F(f, 2)});
  w.set_faces(faces);
  return w;
}

// The intersecting pairs validate_triangle_mesh() lists, sorted.
std::vector<std::pair<int, int>> validated_pairs(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  ValidationOptions o;
  o.require_closed = false;
  o.max_listed = std::numeric_limits<int>::max();
  const ValidationReport r = validate_triangle_mesh(V, F, o);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& c : r.checks)
    if (c.name == "no_self_intersections")
      for (const auto& w : c.where) pairs.emplace_back(std::min(w[0], w[1]), std::max(w[0], w[1]));
  std::sort(pairs.begin(), pairs.end());
  EXPECT_EQ(static_cast<long>(pairs.size()), r.self_intersecting_pairs);
  return pairs;
}

TEST(MeshChecks, IntersectingPairsAreTheValidatorsOnSheetsThatPassThroughEachOther) {
  const TriangleMesh m = interpenetrating_sheets_mesh(12);
  const std::vector<std::pair<int, int>> pairs = intersecting_face_pairs(working(m.V, m.F));
  ASSERT_GT(pairs.size(), 10u);
  EXPECT_EQ(pairs, validated_pairs(m.V, m.F));
  EXPECT_EQ(self_intersecting_pairs(working(m.V, m.F)), static_cast<long>(pairs.size()));
}

TEST(MeshChecks, IntersectingPairsAreTheValidatorsOnACrumpledSphere) {
  // A sphere whose vertices are pushed in and out at random: folds where neighbouring faces
  // overlap, share a vertex across a fold, or pass through each other.
  TriangleMesh m = test::icosphere(3);
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0, 0.06);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v)
    m.V.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  const std::vector<std::pair<int, int>> pairs = intersecting_face_pairs(working(m.V, m.F));
  ASSERT_GT(pairs.size(), 5u);
  EXPECT_EQ(pairs, validated_pairs(m.V, m.F));
}

// The pairs sorted, each as (smaller face, larger face) by their corners: comparable as sets.
std::vector<FacePair> normalised(std::vector<FacePair> pairs) {
  for (FacePair& p : pairs)
    if (p.second < p.first) std::swap(p.first, p.second);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

TEST(MeshChecks, PairsAfterAnEditAreThoseOfAFullCheck) {
  // A crumpled sphere (crossings to start from, asserted); then edits of each kind: a few
  // vertices pushed across their rings (new crossings, asserted), faces removed (the others
  // renumbered), a pushed vertex pulled back. After each, the pairs found from the faces the edit
  // changed must be those of a full check; and where most faces move, it is the full check.
  TriangleMesh m = test::icosphere(3);
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0, 0.05);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) m.V.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  WorkingMesh w = working(m.V, m.F);
  std::vector<FacePair> pairs = crossing_face_pairs(w);
  ASSERT_GT(pairs.size(), 5u);
  auto check = [&](const WorkingMesh::Checkpoint& before, const char* edit) {
    const std::vector<FacePair> after = crossing_face_pairs_after(w, before, pairs);
    const std::vector<FacePair> full = crossing_face_pairs(w);
    EXPECT_EQ(normalised(after), normalised(full)) << edit;
    EXPECT_EQ(faces_in_pairs(w, after), self_intersecting_faces(w)) << edit;
    pairs = after;
    return normalised(full);
  };
  const std::vector<FacePair> crumpled = normalised(pairs);
  WorkingMesh::Checkpoint before = w.checkpoint();
  for (int v : {3, 40, 77}) {  // pushed sideways across their rings: their fans fold over
    const Eigen::Vector3d x = w.V.row(v);
    w.V.row(v) += 0.35 * x.unitOrthogonal().transpose();
  }
  ASSERT_NE(check(before, "pushed"), crumpled);
  before = w.checkpoint();
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); f += 37) drop[f] = 1;
  w.remove_faces(drop);
  check(before, "removed");
  before = w.checkpoint();
  w.V.row(40) = m.V.row(40);
  check(before, "pulled back");
  before = w.checkpoint();
  for (Eigen::Index v = 0; v < w.V.rows(); ++v) w.V.row(v) *= 1.01;  // every face moves: the full check
  check(before, "scaled");
}

TEST(MeshChecks, FacesSharingAnEdgeOrAVertexIntersectOnlyWhenTheyOverlap) {
  // Two faces on the edge (0, 1): side by side (no intersection), then folded flat onto each
  // other (the same side of the edge, coplanar: they overlap).
  Eigen::MatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0;
  Eigen::MatrixX3i F(2, 3);
  F << 0, 1, 2, 1, 0, 3;
  EXPECT_EQ(self_intersecting_pairs(working(V, F)), 0);
  V.row(3) << 0.4, 0.8, 0;
  EXPECT_EQ(self_intersecting_pairs(working(V, F)), 1);
  EXPECT_EQ(intersecting_face_pairs(working(V, F)), validated_pairs(V, F));
  // Two faces on vertex 0 only: apart, then the second one's far edge through the first. (Two
  // faces meeting at one vertex are no polygon mesh for CGAL: validate_triangle_mesh() does not
  // run its self-intersection check on them; the crumpled sphere above has such pairs inside a
  // valid mesh.)
  Eigen::MatrixX3d U(5, 3);
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0.5, 0, -1, 0.5;
  Eigen::MatrixX3i G(2, 3);
  G << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(self_intersecting_pairs(working(U, G)), 0);
  U.row(3) << 0.3, 0.3, -0.5;
  U.row(4) << 0.3, 0.3, 0.5;
  EXPECT_EQ(intersecting_face_pairs(working(U, G)), (std::vector<std::pair<int, int>>{{0, 1}}));
}

TEST(MeshChecks, FacesThatOnlyJustMissCountAsIntersecting) {
  // A slit whose two sides end in distinct vertices 2 and 5 (a border pinched shut): faces
  // (0, 1, 2) and (3, 4, 5) share no corner. With 5 a rounding step off 2, exact predicates say
  // the faces miss; scaled back to a scan's frame the two corners can round to the same point,
  // and CGAL's check of the written mesh fails. Within the contact tolerance (1e-9 of the
  // diagonal) they count; a micrometre apart on a unit mesh they do not.
  Eigen::MatrixX3d V(6, 3);
  V << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 1, 2, 0, 0, 2, 0, 0.5, 1, 0;
  Eigen::MatrixX3i F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  for (const double gap : {1e-15, 1e-12, 1e-10}) {
    V.row(5) << 0.5, 1 + gap, 0;
    EXPECT_EQ(intersecting_face_pairs(working(V, F)), (std::vector<std::pair<int, int>>{{0, 1}})) << gap;
  }
  V.row(5) << 0.5, 1 + 1e-6, 0;
  EXPECT_EQ(self_intersecting_pairs(working(V, F)), 0);
  // Faces on a common vertex 0: the far corner of the second a rounding step above the first's
  // plane, over its interior (its far edge only just misses the first face).
  Eigen::MatrixX3d U(5, 3);
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, 1e-13, -1, -1, 1;
  Eigen::MatrixX3i G(2, 3);
  G << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(intersecting_face_pairs(working(U, G)), (std::vector<std::pair<int, int>>{{0, 1}}));
  U.row(3) << 0.3, 0.3, 1e-6;
  EXPECT_EQ(self_intersecting_pairs(working(U, G)), 0);
}

TEST(MeshChecks, LostLoopsAreThoseClosedOrJoined) {
  // A 6 × 6 grid without the quads (1, 2) and (3, 2): two holes one quad apart, and the outer
  // border: three loops.
  const TriangleMesh g = test::grid(6);
  auto without = [&](std::vector<int> quads) {
    std::vector<MeshFace> faces;
    for (int q = 0; q < 36; ++q)
      if (std::find(quads.begin(), quads.end(), q) == quads.end())
        for (int f : {2 * q, 2 * q + 1}) faces.push_back({g.F(f, 0), g.F(f, 1), g.F(f, 2)});
    WorkingMesh w(g.V, Eigen::MatrixX3d::Zero(g.V.rows(), 3), std::vector<int>(g.V.rows(), -1));
    w.set_faces(faces);
    return w;
  };
  const int left = 2 * 6 + 1, middle = 2 * 6 + 2, right = 2 * 6 + 3;
  std::vector<int> before;
  ASSERT_EQ(boundary_loop_labels(without({left, right}), before), 3);
  // The same mesh: nothing lost.
  EXPECT_TRUE(lost_loop_vertices(without({left, right}), before).empty());
  // The quad between them removed: the two holes are one loop; the corners of both are lost.
  std::vector<int> joined = lost_loop_vertices(without({left, middle, right}), before);
  EXPECT_EQ(joined.size(), 8u);
  // The right hole closed: its four corners are lost, the left hole's are not.
  std::vector<int> closed = lost_loop_vertices(without({left}), before);
  std::vector<int> right_corners;
  for (int v = 0; v < static_cast<int>(before.size()); ++v)
    if (before[v] >= 0 && before[v] == before[2 * 7 + 4]) right_corners.push_back(v);
  EXPECT_EQ(closed, right_corners);
  EXPECT_EQ(right_corners.size(), 4u);
  // A new hole elsewhere loses nothing.
  EXPECT_TRUE(lost_loop_vertices(without({left, right, 4 * 6 + 4}), before).empty());
}

}  // namespace
}  // namespace heatcvt
