// Tests of the surface mesher's stages (lib/include/heatcvt/mesher/), each on shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/coverage_repair.h"
#include "heatcvt/mesher/dual_candidates.h"
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/edge_split.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/orientation.h"
#include "heatcvt/mesher/polish.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/sliver_collapse.h"
#include "heatcvt/mesher/sliver_repair.h"
#include "heatcvt/mesher/surface_mesher.h"
#include "heatcvt/mesher/tangential_relaxation.h"
#include "heatcvt/mesher/tips.h"
#include "heatcvt/mesher/untangle.h"
#include "heatcvt/mesher/valence3_removal.h"
#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/remesh.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/errors.h"
#include "heatcvt/shapes.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<MeshFace> faces_of(const Eigen::MatrixX3i& F) {
  std::vector<MeshFace> out;
  for (Eigen::Index f = 0; f < F.rows(); ++f) out.push_back({F(f, 0), F(f, 1), F(f, 2)});
  return out;
}


Eigen::MatrixX3i face_matrix(const WorkingMesh& w) {
  Eigen::MatrixX3i F(w.num_faces(), 3);
  for (int f = 0; f < w.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = w.face(f)[k];
  return F;
}

ValidationReport validate(const WorkingMesh& w, bool closed) {
  const TriangleMesh m = compact_mesh(w);
  ValidationOptions o;
  o.require_closed = closed;
  return validate_triangle_mesh(m.V, m.F, o);
}

// The index of `w` equals that of a mesh built from its faces in one go.
void expect_index_fresh(const WorkingMesh& w) {
  WorkingMesh fresh(w.V, w.N, w.anchor);
  fresh.set_faces(w.faces());
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_EQ(w.valence(v), fresh.valence(v)) << "vertex " << v;
  for (const MeshFace& f : w.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      EXPECT_EQ(w.half_edge_face(a, b), fresh.half_edge_face(a, b));
      EXPECT_EQ(w.half_edge_face(b, a), fresh.half_edge_face(b, a));
      EXPECT_EQ(w.edge_face_count(a, b), fresh.edge_face_count(a, b));
    }
}

double ring_min_angle(const WorkingMesh& w) {
  double m = M_PI;
  for (const MeshFace& f : w.faces()) m = std::min(m, face_min_angle(w, f));
  return m;
}

int slivers(const WorkingMesh& w, double deg) {
  int n = 0;
  for (const MeshFace& f : w.faces()) n += face_min_angle(w, f) < deg * kDeg;
  return n;
}

// Removes the faces whose centroid has z above `z` (a cap of a sphere).
void cut_cap(WorkingMesh& w, double z) {
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); ++f) {
    double cz = 0;
    for (int v : w.face(f)) cz += w.V(v, 2) / 3.0;
    drop[f] = cz > z;
  }
  ASSERT_GT(w.remove_faces(drop), 0);
}

// ---------------------------------------------------------------------------------------------

TEST(WorkingMesh, EdgeIndexFollowsEveryOperation) {
  const TriangleMesh s = test::icosphere(2);
  WorkingMesh w = test::working_mesh(s);
  EXPECT_EQ(w.num_faces(), s.F.rows());
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_GE(w.valence(v), 5);
  // Flip the first edge, remove every third face, add one back, replace another.
  const int f2 = w.half_edge_face(w.face(0)[1], w.face(0)[0]);
  ASSERT_GE(f2, 0);
  w.flip(0, 0, f2);
  expect_index_fresh(w);
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); f += 3) drop[f] = 1;
  const MeshFace removed = w.face(3);
  EXPECT_EQ(w.remove_faces(drop), (w.num_faces() + 2) / 3);
  expect_index_fresh(w);
  w.add_face(removed);
  expect_index_fresh(w);
  const MeshFace g = w.face(5);
  w.replace_face(5, {g[1], g[2], g[0]});
  expect_index_fresh(w);
  w.pop_face();
  expect_index_fresh(w);
  // A vertex split into a face and taken back: faces popped, the vertex popped.
  const MeshFace h = w.face(0);
  const int m = w.add_vertex(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1), -1);
  w.replace_face(0, {h[0], h[1], m});
  w.add_face({h[1], h[2], m});
  w.add_face({h[2], h[0], m});
  expect_index_fresh(w);
  w.pop_face();
  w.pop_face();
  w.replace_face(0, h);
  w.pop_vertex();
  EXPECT_EQ(w.num_vertices(), s.V.rows());
  EXPECT_EQ(static_cast<Eigen::Index>(w.anchor.size()), s.V.rows());
  expect_index_fresh(w);
  EXPECT_EQ(w.add_vertex(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1), -1), m);
  EXPECT_EQ(w.valence(m), 0);
}

TEST(WorkingMesh, FlipTurnsTheSharedEdge) {
  // Quad a(0,0) b(1,0) c(1,1) d(0,1) as (a, b, c), (c, d, a): flipping edge c-a gives b-d.
  Eigen::MatrixX3d V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(4, 3), {});
  w.add_face({0, 1, 2});
  w.add_face({2, 3, 0});
  w.flip(0, 2, 1);  // edge (c, a) of face 0
  EXPECT_EQ(w.edge_face_count(0, 2), 0);
  EXPECT_EQ(w.edge_face_count(1, 3), 2);
  EXPECT_GE(w.half_edge_face(1, 3), 0);
  EXPECT_GE(w.half_edge_face(3, 1), 0);
  expect_index_fresh(w);
}

TEST(WorkingMesh, RollbackRestoresExactly) {
  const TriangleMesh s = test::icosphere(2);
  WorkingMesh w = test::working_mesh(s);
  for (int v = 0; v < w.num_vertices(); ++v) w.anchor[v] = v;
  const WorkingMesh::Checkpoint c = w.checkpoint();
  const std::vector<MeshFace> faces = w.faces();
  const Eigen::MatrixX3d V = w.V, N = w.N;
  const int m = w.add_vertex(Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(0, 0, 1), 7);
  w.replace_face(0, {w.face(0)[0], w.face(0)[1], m});
  w.V.row(3) *= 1.5;
  w.anchor[2] = 99;
  std::vector<char> drop(w.num_faces(), 0);
  drop[10] = 1;
  w.remove_faces(drop);
  w.rollback(c);
  EXPECT_EQ(w.num_vertices(), s.V.rows());
  EXPECT_TRUE(w.faces() == faces);
  EXPECT_EQ((w.V - V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((w.N - N).cwiseAbs().maxCoeff(), 0.0);
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_EQ(w.anchor[v], v);
  expect_index_fresh(w);
}

TEST(WorkingMesh, ComponentsByVertexAndByEdge) {
  // Two icospheres, and a triangle touching the first one at a vertex only.
  const TriangleMesh s = test::icosphere(1);
  const int n = static_cast<int>(s.V.rows());
  Eigen::MatrixX3d V(2 * n + 2, 3);
  V << s.V, s.V.rowwise() + Eigen::RowVector3d(3, 0, 0), Eigen::RowVector3d(0, 0, 2), Eigen::RowVector3d(0, 0.5, 2);
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(V.rows(), 3), {});
  for (const MeshFace& f : faces_of(s.F)) w.add_face(f);
  for (const MeshFace& f : faces_of(s.F)) w.add_face({f[0] + n, f[1] + n, f[2] + n});
  int top = 0;
  for (int v = 0; v < n; ++v)
    if (s.V(v, 2) > s.V(top, 2)) top = v;
  w.add_face({top, 2 * n, 2 * n + 1});
  const FaceComponents by_edge = face_components(w, false);
  const FaceComponents by_vertex = face_components(w, true);
  ASSERT_EQ(by_edge.size.size(), 3u);
  EXPECT_EQ(by_edge.size[0], s.F.rows());
  EXPECT_EQ(by_edge.size[1], s.F.rows());
  EXPECT_EQ(by_edge.size[2], 1);
  ASSERT_EQ(by_vertex.size.size(), 2u);
  EXPECT_EQ(by_vertex.size[0], s.F.rows() + 1);
}

// ---------------------------------------------------------------------------------------------

TEST(Projector, MeshProjectorGivesTheClosestPointAndNormal) {
  const TriangleMesh s = test::icosphere(4);
  const MeshSurfaceProjector proj(s.V, s.F);
  int hint = -1;
  Eigen::Vector3d pos, nrm;
  const Eigen::Vector3d x(0.3, -1.7, 0.9);
  proj.project(x, hint, pos, nrm);
  EXPECT_GE(hint, 0);
  EXPECT_NEAR(pos.norm(), 1.0, 2e-3);
  EXPECT_GT(pos.normalized().dot(x.normalized()), 0.999);
  EXPECT_GT(nrm.dot(pos.normalized()), 0.999);
  EXPECT_NEAR(proj.distance_to_samples(x), x.norm() - 1.0, 2e-3);
}

// A thin plate (1 × 1 × 0.02): a point that moved off its top face to just below the plate's
// mid-plane is nearest the bottom face, but with the top face as its hint it stays on the top.
TEST(Projector, MeshProjectorStaysOnTheSheetOfItsHintAcrossAThinPart) {
  TriangleMesh plate;
  plate.V.resize(8, 3);
  for (int i = 0; i < 8; ++i) plate.V.row(i) << (i & 1), ((i >> 1) & 1), 0.02 * ((i >> 2) & 1);
  plate.F.resize(12, 3);
  plate.F << 0, 2, 1, 1, 2, 3,  // bottom (z = 0, facing −z)
      4, 5, 6, 5, 7, 6,         // top (z = 0.02, facing +z)
      0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5;
  ASSERT_EQ(mesh_topology(plate.F, 8).inconsistent_edges, 0);
  const MeshSurfaceProjector proj(plate.V, plate.F);
  const Eigen::Vector3d x(0.4, 0.55, 0.008);
  Eigen::Vector3d pos, nrm;
  int hint = -1;  // precondition: the closest point is on the bottom face
  proj.project(x, hint, pos, nrm);
  ASSERT_NEAR(pos.z(), 0.0, 1e-12);
  hint = 2;  // a top face
  proj.project(x, hint, pos, nrm);
  EXPECT_NEAR(pos.z(), 0.02, 1e-12);
  EXPECT_NEAR(pos.x(), 0.4, 1e-12);
  EXPECT_NEAR(pos.y(), 0.55, 1e-12);
  EXPECT_GT(nrm.z(), 0.5);
  EXPECT_GE(plate.F(hint, 0), 4);  // the hint is a top face again
}

TEST(Projector, CloudFitProjectsOntoTheSampledSphere) {
  const TriangleMesh s = test::icosphere(4);  // 2562 points on the unit sphere
  const Eigen::MatrixX3d P = s.V;
  Eigen::MatrixX3d N = P;  // outward normals
  CloudFitOptions o;
  o.fit_neighbors = 20;
  o.walk_neighbors = 20;
  const CloudSurfaceProjector proj(P, N, o);
  for (const Eigen::Vector3d x : {Eigen::Vector3d(0.6, 0.7, 0.55), Eigen::Vector3d(-0.1, 0.2, -1.1)}) {
    int hint = 0;  // the walk starts far away
    Eigen::Vector3d pos, nrm;
    proj.project(x, hint, pos, nrm);
    EXPECT_NEAR(pos.norm(), 1.0, 1e-3);
    EXPECT_GT(nrm.dot(pos.normalized()), 0.999);
    EXPECT_LT((P.row(hint).transpose() - x.normalized()).norm(), 0.1);  // walked to the nearest points
  }
  EXPECT_NEAR(proj.distance_to_samples(Eigen::Vector3d(0, 0, 3)), 2.0, 1e-9);  // (0,0,1) is a vertex
}

// ---------------------------------------------------------------------------------------------

TEST(DualCandidates, FacesOfADualAreOrientedByTheSiteNormals) {
  const TriangleMesh s = test::icosphere(2);
  WorkingMesh w(s.V, s.V, {});  // outward normals
  Eigen::MatrixX3i F = s.F;
  for (Eigen::Index f = 0; f < F.rows(); f += 2) std::swap(F(f, 1), F(f, 2));  // half of them inside out
  Eigen::MatrixX3i twice(2 * F.rows(), 3);
  twice << F, F.topRows(F.rows());
  const DualCandidates c = dual_candidates_from_faces(twice, w);
  EXPECT_EQ(c.coherent.size(), static_cast<size_t>(s.F.rows()));
  EXPECT_TRUE(c.loose.empty());
  for (const DualCandidate& d : c.coherent) {
    EXPECT_EQ(d.witnesses, 2);
    const Eigen::Vector3d a = s.V.row(d.f[0]), b = s.V.row(d.f[1]), cc = s.V.row(d.f[2]);
    EXPECT_GT((b - a).cross(cc - a).dot(a + b + cc), 0);  // outward
  }
  for (size_t i = 1; i < c.coherent.size(); ++i) EXPECT_GE(c.coherent[i - 1].quality, c.coherent[i].quality);
}

// ---------------------------------------------------------------------------------------------

TEST(ManifoldExtraction, FinOfAThirdFaceOnAnEdgeIsRejected) {
  const TriangleMesh s = test::icosphere(1);
  const int n = static_cast<int>(s.V.rows());
  Eigen::MatrixX3d V(n + 1, 3);
  V << s.V, Eigen::RowVector3d(0, 0, 3);
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(n + 1, 3), {});
  std::vector<DualCandidate> cands;
  for (const MeshFace& f : faces_of(s.F)) cands.push_back({f, 2, 0, 1.0});
  const MeshFace e = cands[0].f;
  // The fin on edge (e0, e1), witnessed less than the sphere's faces (so ordered after them).
  cands.push_back(DualCandidate{{e[1], e[0], n}, 1, 0, 1.0});
  EXPECT_EQ(extract_manifold(w, cands), 1);
  EXPECT_EQ(w.num_faces(), s.F.rows());
  EXPECT_EQ(w.edge_face_count(e[0], e[1]), 2);
  EXPECT_TRUE(validate(w, true).ok());
}

TEST(ManifoldExtraction, NonManifoldVertexKeepsItsLargestFan) {
  // A sphere and a pair of triangles touching it at one vertex (the pair's own piece is small).
  const TriangleMesh s = test::icosphere(1);
  const int n = static_cast<int>(s.V.rows());
  int top = 0;
  for (int v = 0; v < n; ++v)
    if (s.V(v, 2) > s.V(top, 2)) top = v;
  Eigen::MatrixX3d V(n + 3, 3);
  V << s.V, Eigen::RowVector3d(0.5, 0, 1.5), Eigen::RowVector3d(0, 0.5, 1.5), Eigen::RowVector3d(0.5, 0.5, 1.8);
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(n + 3, 3), {});
  for (const MeshFace& f : faces_of(s.F)) w.add_face(f);
  w.add_face({top, n, n + 1});
  w.add_face({n + 1, n, n + 2});
  ManifoldOptions o;
  o.max_dropped_piece_faces = 0;  // only the fan rule
  EXPECT_EQ(make_vertices_manifold(w, o), 1);  // the fan {top, n, n+1} at `top`
  EXPECT_EQ(w.num_faces(), s.F.rows() + 1);
  // The remaining lone triangle is a piece of one face: dropped by the piece rule.
  EXPECT_EQ(make_vertices_manifold(w), 1);
  EXPECT_EQ(w.num_faces(), s.F.rows());
  EXPECT_TRUE(validate(w, true).ok());
}

TEST(ManifoldExtraction, SecondPassAddsOnlyWhatKeepsVerticesManifold) {
  // The sphere without the five faces at its top vertex; the second pass gets them back in an
  // order where the third one would make the top vertex non-manifold (two fans) when tried.
  const TriangleMesh s = test::icosphere(1);
  int top = 0;
  for (int v = 0; v < s.V.rows(); ++v)
    if (s.V(v, 2) > s.V(top, 2)) top = v;
  WorkingMesh w(s.V, s.V, {});
  std::vector<DualCandidate> cap;
  for (const MeshFace& f : faces_of(s.F)) {
    if (f[0] == top || f[1] == top || f[2] == top) cap.push_back({f, 1, 0, 1.0});
    else w.add_face(f);
  }
  ASSERT_GE(cap.size(), 5u);
  // Ring order of the cap faces: each next one shares an edge at `top` with the previous one.
  std::vector<DualCandidate> ring = {cap[0]};
  while (ring.size() < cap.size())
    for (const DualCandidate& c : cap) {
      int k = 0;
      while (ring.back().f[k] != top) ++k;
      const int after = ring.back().f[(k + 2) % 3];  // (top, x, after): the next face has (top, after, y)
      int j = 0;
      while (c.f[j] != top) ++j;
      if (c.f[(j + 1) % 3] == after) {
        ring.push_back(c);
        break;
      }
    }
  // First list: faces 0, 2, 1 of the ring (2 is not adjacent to 0 at `top`: rejected then);
  // second call: 2 and the rest.
  const int k = static_cast<int>(ring.size());
  EXPECT_EQ(add_compatible_candidates(w, {ring[0], ring[2], ring[1]}, {}), 2);
  EXPECT_EQ(w.num_faces(), s.F.rows() - (k - 2));
  EXPECT_EQ(add_compatible_candidates(w, {ring[2]}, std::vector<DualCandidate>(ring.begin() + 3, ring.end())), k - 2);
  EXPECT_EQ(w.num_faces(), s.F.rows());
  EXPECT_TRUE(validate(w, true).ok());
}

// ---------------------------------------------------------------------------------------------

TEST(HoleFilling, ClosesASphereWithACutOutCap) {
  const TriangleMesh s = test::icosphere(3);
  const MeshSurfaceProjector surface(s.V, s.F);
  WorkingMesh w = test::working_mesh(s);
  cut_cap(w, 0.93);
  ASSERT_FALSE(validate(w, true).ok());
  HoleFillingOptions o;  // a loop of 15 edges: filled as a hole in sampled surface
  o.fill_short_loops = false;
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, o, {}, removed), 1);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
}

TEST(HoleFilling, KeepsTheGenusOfATorus) {
  const TriangleMesh t = test::torus(48, 24);
  const MeshSurfaceProjector surface(t.V, t.F);
  WorkingMesh w = test::working_mesh(t);
  // Cut out the faces around one vertex on the outer equator (a hole of 6 edges... and its ring).
  std::vector<char> drop(w.num_faces(), 0);
  const Eigen::Vector3d centre(1.4, 0, 0);
  for (int f = 0; f < w.num_faces(); ++f) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int v : w.face(f)) g += w.V.row(v).transpose() / 3.0;
    drop[f] = (g - centre).norm() < 0.2;
  }
  ASSERT_GT(w.remove_faces(drop), 6);
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, {}, {}, removed), 1);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 1);
}

TEST(HoleFilling, KeepsTheBorderOfAnOpenSheet) {
  const TriangleMesh g = test::grid(7);  // boundary loop of 28 edges, nothing sampled beyond it
  const MeshSurfaceProjector surface(g.V, g.F);
  WorkingMesh w = test::working_mesh(g);
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, {}, {}, removed), 0);
  EXPECT_EQ(w.num_faces(), g.F.rows());
}

// The projector of an input mesh knows its border: a loop away from it is a hole inside the
// surface, filled under every policy; the border itself stays.
TEST(HoleFilling, HolesInsideAnInputMeshAreFilledAndItsBorderKept) {
  const TriangleMesh g = test::grid(8);
  const MeshSurfaceProjector surface(g.V, g.F);
  ASSERT_TRUE(surface.has_border());
  auto with_hole = [&] {
    WorkingMesh w = test::working_mesh(g);
    std::vector<char> drop(w.num_faces(), 0);  // the two triangles of the cell [3/8, 4/8]²
    for (int f = 0; f < w.num_faces(); ++f) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : w.face(f)) c += w.V.row(v).transpose() / 3.0;
      drop[f] = c.x() > 3.0 / 8 && c.x() < 4.0 / 8 && c.y() > 3.0 / 8 && c.y() < 4.0 / 8;
    }
    EXPECT_EQ(w.remove_faces(drop), 2);
    return w;
  };
  HoleFillingOptions o;
  o.policy = HolePolicy::keep;
  o.clearance = 10;  // the sampled-hole test never selects a loop
  WorkingMesh w = with_hole();
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, o, {}, removed), 1);
  EXPECT_EQ(w.num_faces(), g.F.rows());
  EXPECT_EQ(validate(w, false).boundary_loops, 1);
  // The hole's corners are 3 cells (h) from the border: with a clearance of 4h it is not inside.
  o.interior_hole_clearance = 4;
  WorkingMesh near = with_hole();
  EXPECT_EQ(fill_holes(near, surface, o, {}, removed), 0);
  EXPECT_EQ(validate(near, false).boundary_loops, 2);
}

// A loop of the mesh around a hole of the input mesh (one grid cell, in the middle of a 5 × 5
// block of cells the mesh lacks) stays open under keep, though every vertex of the loop is
// farther than interior_hole_clearance · h from the input's border; fill closes it.
TEST(HoleFilling, ALoopAroundAHoleOfTheInputMeshStaysOpen) {
  const TriangleMesh g = test::grid(10);
  const auto without = [&](double lo, double hi) {
    WorkingMesh w = test::working_mesh(g);
    std::vector<char> drop(w.num_faces(), 0);
    for (int f = 0; f < w.num_faces(); ++f) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : w.face(f)) c += w.V.row(v).transpose() / 3.0;
      drop[f] = c.x() > lo && c.x() < hi && c.y() > lo && c.y() < hi;
    }
    w.remove_faces(drop);
    return w;
  };
  const TriangleMesh input = compact_mesh(without(0.4, 0.5));
  const MeshSurfaceProjector surface(input.V, input.F);
  ASSERT_TRUE(surface.has_border());
  HoleFillingOptions o;
  o.policy = HolePolicy::keep;
  int removed = 0;
  WorkingMesh kept = without(0.2, 0.7);
  ASSERT_EQ(validate(kept, false).boundary_loops, 2);
  EXPECT_EQ(fill_holes(kept, surface, o, {}, removed), 0);
  EXPECT_EQ(validate(kept, false).boundary_loops, 2);
  o.policy = HolePolicy::fill;
  WorkingMesh filled = without(0.2, 0.7);
  EXPECT_EQ(fill_holes(filled, surface, o, {}, removed), 1);
  EXPECT_EQ(validate(filled, false).boundary_loops, 1);
}

// The projector of a closed input mesh knows it has no border: every loop is a hole inside it.
TEST(HoleFilling, EveryHoleOfAClosedInputMeshIsFilled) {
  const TriangleMesh s = test::icosphere(3);
  const MeshSurfaceProjector surface(s.V, s.F);
  ASSERT_TRUE(surface.border_known());
  ASSERT_FALSE(surface.has_border());
  WorkingMesh w = test::working_mesh(s);
  cut_cap(w, 0.8);
  HoleFillingOptions o;
  o.policy = HolePolicy::keep;
  o.clearance = 10;  // the sampled-hole test never selects a loop
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, o, {}, removed), 1);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
}

TEST(HoleFilling, ShortLoopsOfTheSurfaceItselfAreKeptOnRequest) {
  // An annulus (radii 1 and 2, 8 vertices per ring) as both the mesh and the surface: two
  // boundary loops of 8 edges with no surface across them.
  Eigen::MatrixX3d V(16, 3);
  for (int k = 0; k < 8; ++k) {
    V.row(k) << std::cos(k * M_PI / 4), std::sin(k * M_PI / 4), 0;
    V.row(8 + k) = 2 * V.row(k);
  }
  Eigen::MatrixX3i F(16, 3);
  for (int k = 0; k < 8; ++k) {
    const int j = (k + 1) % 8;
    F.row(2 * k) << k, 8 + k, 8 + j;
    F.row(2 * k + 1) << k, 8 + j, j;
  }
  const MeshSurfaceProjector surface(V, F);
  TriangleMesh annulus;
  annulus.V = V;
  annulus.F = F;
  HoleFillingOptions keep;
  keep.fill_short_loops = false;
  WorkingMesh w = test::working_mesh(annulus);
  int removed = 0;
  EXPECT_EQ(fill_holes(w, surface, keep, {}, removed), 0);
  EXPECT_EQ(w.num_faces(), 16);
  EXPECT_EQ(fill_holes(w, surface, {}, {}, removed), 2);  // the default fills loops of <= 8 edges
  const std::vector<char> boundary = w.boundary_vertices();
  EXPECT_EQ(std::count(boundary.begin(), boundary.end(), 1), 0);
}

TEST(HoleFilling, LoopTriangulationMaximisesTheSmallestAngle) {
  // A regular hexagon: the best triangulation has smallest angle 30 degrees.
  Eigen::MatrixX3d V(6, 3);
  for (int i = 0; i < 6; ++i) V.row(i) << std::cos(i * M_PI / 3), std::sin(i * M_PI / 3), 0;
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(6, 3), {});
  std::vector<MeshFace> tris;
  ASSERT_TRUE(triangulate_loop(w, {0, 1, 2, 3, 4, 5}, tris));
  ASSERT_EQ(tris.size(), 4u);
  for (const MeshFace& f : tris) {
    EXPECT_NEAR(face_min_angle(w, f), 30 * kDeg, 1e-9);
    const Eigen::Vector3d n = (V.row(f[1]) - V.row(f[0])).cross(V.row(f[2]) - V.row(f[0])).transpose();
    EXPECT_LT(n.z(), 0);  // against the loop's counter-clockwise direction
  }
}

// ---------------------------------------------------------------------------------------------

TEST(Untangle, RemovesASpikeThroughTheSphereAndRefillsTheHoles) {
  // The top vertex of a sphere pulled through the bottom: its fan crosses the bottom faces.
  const TriangleMesh s = test::icosphere(3);
  const MeshSurfaceProjector surface(s.V, s.F);
  WorkingMesh w = test::working_mesh(s);
  int top = 0;
  for (int v = 0; v < w.num_vertices(); ++v)
    if (w.V(v, 2) > w.V(top, 2)) top = v;
  w.V.row(top) << 0.01, 0.02, -1.3;
  ASSERT_GT(self_intersecting_pairs(w), 0);
  MesherStats stats;
  untangle(w, surface, {}, {}, {}, stats);
  EXPECT_EQ(self_intersecting_pairs(w), 0);
  EXPECT_GT(stats.removed_triangles, 0);
  EXPECT_GT(stats.holes_filled, 1);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(w.valence(top), 0);
}

// ---------------------------------------------------------------------------------------------

TEST(Valence3Removal, RemovesAVertexInsertedInAFace) {
  const TriangleMesh s = test::icosphere(2);
  WorkingMesh w = test::working_mesh(s);
  const MeshFace f = w.face(7);
  const Eigen::Vector3d c = (w.V.row(f[0]) + w.V.row(f[1]) + w.V.row(f[2])).transpose() / 3.0;
  const int m = w.add_vertex(c.normalized(), c.normalized(), -1);
  w.replace_face(7, {f[0], f[1], m});
  w.add_face({f[1], f[2], m});
  w.add_face({f[2], f[0], m});
  ASSERT_EQ(w.valence(m), 3);
  EXPECT_EQ(remove_valence3(w), 1);
  EXPECT_EQ(w.valence(m), 0);
  EXPECT_EQ(w.num_faces(), s.F.rows());
  EXPECT_EQ(w.edge_face_count(f[0], f[1]), 2);
  EXPECT_TRUE(validate(w, true).ok());
  EXPECT_EQ(remove_valence3(w), 0);  // an icosphere has none
}

// ---------------------------------------------------------------------------------------------

TEST(TipVertices, TheEndOfASpikeIsATipAndASmoothSphereHasNone) {
  const auto count = [](const std::vector<char>& t) { return std::count(t.begin(), t.end(), 1); };
  TipOptions on;
  on.min_defect_deg = kRemeshTipDefectDeg;
  EXPECT_EQ(count(tip_vertices(test::working_mesh(test::icosphere(3)), on)), 0);
  const WorkingMesh spiked = test::working_mesh(test::spiked_sphere(2, 2.5));
  const std::vector<char> spike = tip_vertices(spiked, on);
  EXPECT_EQ(count(spike), 1);
  EXPECT_EQ(spike[0], 1);
  EXPECT_EQ(count(tip_vertices(spiked)), 0);  // off by default
  // A tetrahedron: each corner has three 60° angles, a defect of 180°.
  Eigen::MatrixX3d V(4, 3);
  V << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
  WorkingMesh tet(V, V.rowwise().normalized(), {});
  for (const MeshFace& f : std::vector<MeshFace>{{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}) tet.add_face(f);
  EXPECT_EQ(count(tip_vertices(tet, on)), 4);
  TipOptions higher;
  higher.min_defect_deg = 185;
  EXPECT_EQ(count(tip_vertices(tet, higher)), 0);
  // Border vertices are no tips, however sharp the border turns.
  EXPECT_EQ(count(tip_vertices(test::working_mesh(test::grid(3)), on)), 0);
}

// The polish stages on a sphere with a thin spike whose end has valence 3 (a vertex above the
// middle of a face), the spiked sphere itself the surface: the end stays where it is with the
// tips held, and valence-3 removal takes it without (so the test can fail).
TEST(Polish, AValence3TipIsNotRemoved) {
  TriangleMesh spiked = test::icosphere(2);
  const Eigen::Vector3i f = spiked.F.row(0);
  const Eigen::Vector3d c = (spiked.V.row(f[0]) + spiked.V.row(f[1]) + spiked.V.row(f[2])).transpose() / 3.0;
  const int tip = static_cast<int>(spiked.V.rows());
  spiked.V.conservativeResize(tip + 1, 3);
  spiked.V.row(tip) = 2.5 * c.normalized().transpose();
  spiked.F.conservativeResize(spiked.F.rows() + 2, 3);
  spiked.F.row(0) << f[0], f[1], tip;
  spiked.F.row(spiked.F.rows() - 2) << f[1], f[2], tip;
  spiked.F.row(spiked.F.rows() - 1) << f[2], f[0], tip;
  const MeshSurfaceProjector surface(spiked.V, spiked.F);
  const auto polished = [&](double min_defect_deg) {
    WorkingMesh w = test::working_mesh(spiked);
    PolishOptions o;
    o.tips.min_defect_deg = min_defect_deg;
    MesherStats stats;
    relaxation_polish(w, surface, o, {}, {}, {}, stats);
    angle_polish_stage(w, surface, o, stats);
    return w;
  };
  const Eigen::Vector3d end = spiked.V.row(tip).transpose();
  const WorkingMesh held = polished(kRemeshTipDefectDeg);
  EXPECT_EQ(held.valence(tip), 3);
  EXPECT_EQ((held.V.row(tip).transpose() - end).norm(), 0.0);
  EXPECT_TRUE(validate(held, true).ok());
  EXPECT_EQ(polished(0).valence(tip), 0) << "without the tips held, valence-3 removal takes the end";
}

// ---------------------------------------------------------------------------------------------

TEST(EdgeFlips, MaxMinAngleFlipsMakeDelaunayPairs) {
  // A sheared grid whose diagonals all go the wrong way (every pair fails the Delaunay test).
  TriangleMesh g = test::grid(6, 0, 1, 0, 1, false);
  g.V.col(0) += 0.7 * g.V.col(1);
  WorkingMesh w = test::working_mesh(g);
  auto delaunay = [&](int a, int b) {  // opposite angles of the pair on edge (a, b) sum to <= pi
    const int f1 = w.half_edge_face(a, b), f2 = w.half_edge_face(b, a);
    double sum = 0;
    for (int f : {f1, f2}) {
      int o = -1;
      for (int v : w.face(f))
        if (v != a && v != b) o = v;
      const Eigen::Vector3d p = w.V.row(o), x = w.V.row(a), y = w.V.row(b);
      sum += std::acos((x - p).normalized().dot((y - p).normalized()));
    }
    return sum <= M_PI + 1e-9;
  };
  const std::vector<char> boundary = w.boundary_vertices();
  auto interior_pairs_delaunay = [&]() {
    int bad = 0;
    for (const MeshFace& f : w.faces())
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if (!boundary[a] && !boundary[b] && !delaunay(a, b)) ++bad;
      }
    return bad;
  };
  ASSERT_GT(interior_pairs_delaunay(), 0);
  const double before = ring_min_angle(w);
  FlipOptions o;
  o.max_passes = 50;
  EXPECT_GT(flip_edges(w, o), 0);
  EXPECT_EQ(interior_pairs_delaunay(), 0);
  EXPECT_GE(ring_min_angle(w), before);
  expect_index_fresh(w);
  EXPECT_TRUE(validate(w, false).ok());
}

TEST(EdgeFlips, ValenceFlipsBringValencesTowardsSix) {
  // Grid with all diagonals one way: interior valences 6; flip nothing. Alternating diagonals:
  // valences 4 and 8; valence flips equalise them on the flat sheet.
  WorkingMesh w = test::working_mesh(test::grid(8, 0, 1, 0, 1, true));
  const std::vector<char> boundary = w.boundary_vertices();
  auto deviation = [&]() {
    long d = 0;
    for (int v = 0; v < w.num_vertices(); ++v)
      if (!boundary[v]) d += (w.valence(v) - 6) * (w.valence(v) - 6);
    return d;
  };
  const long before = deviation();
  ASSERT_GT(before, 0);
  FlipOptions o;
  o.valence_mode = true;
  o.max_normal_deviation_deg = 30;
  EXPECT_GT(flip_edges(w, o), 0);
  EXPECT_LT(deviation(), before);
  EXPECT_TRUE(validate(w, false).ok());
}

// ---------------------------------------------------------------------------------------------

// A coarse sphere with its vertices moved tangentially (seeded), on a fine sphere as surface.
WorkingMesh jittered_sphere(const TriangleMesh& coarse, double amount) {
  WorkingMesh w = test::working_mesh(coarse);
  for (int v = 0; v < w.num_vertices(); ++v) {
    const Eigen::Vector3d x = w.V.row(v);
    const Eigen::Vector3d t = x.unitOrthogonal(), u = x.cross(t);
    const double a = std::sin(12.9898 * v) * amount, b = std::cos(78.233 * v) * amount;
    w.V.row(v) = (x + a * t + b * u).normalized().transpose();
    w.N.row(v) = w.V.row(v);
  }
  return w;
}

TEST(EdgeFlips, PassesAfterTheFirstFlipWhatFullScansFlip) {
  // flip_edges() re-examines only edges next to a flip after its first pass. Each call's first
  // pass is a full scan, so one call of P passes must flip exactly what P one-pass calls flip.
  // Inputs where later passes still flip (asserted): max-min-angle flips on a strongly sheared
  // grid, valence flips on a jittered grid of valences 4 and 8.
  TriangleMesh sheared = test::grid(16, 0, 1, 0, 1, true), jittered = sheared;
  sheared.V.col(0) += 2.5 * sheared.V.col(1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (Eigen::Index v = 0; v < jittered.V.rows(); ++v) jittered.V.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), 0);
  for (const bool valence_mode : {false, true}) {
    const WorkingMesh start = test::working_mesh(valence_mode ? jittered : sheared);
    FlipOptions o;
    o.valence_mode = valence_mode;
    o.max_passes = 1;
    WorkingMesh single = start;
    const int first_pass = flip_edges(single, o);
    int single_flips = first_pass;
    for (int pass = 1; pass < 12; ++pass) single_flips += flip_edges(single, o);
    ASSERT_GT(single_flips, first_pass) << "valence_mode " << valence_mode;  // later passes flip
    WorkingMesh many = start;
    o.max_passes = 12;
    EXPECT_EQ(flip_edges(many, o), single_flips) << "valence_mode " << valence_mode;
    EXPECT_EQ(many.faces(), single.faces()) << "valence_mode " << valence_mode;
  }
}

TEST(EdgeFlips, AContinuedCallWithDirtyMarksFlipsWhatAFullScanFlips) {
  // After a converged call, some vertices move (a smoothing step); a call told which vertices
  // moved (moved_vertex_rings()) must flip exactly what a full scan flips. Both flip rules, on a
  // jittered grid where a second jitter of a patch makes new flips (asserted).
  TriangleMesh grid = test::grid(20, 0, 1, 0, 1, true);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.015, 0.015);
  for (Eigen::Index v = 0; v < grid.V.rows(); ++v) grid.V.row(v) += Eigen::RowVector3d(jitter(rng), jitter(rng), 0);
  for (const bool valence_mode : {false, true}) {
    FlipOptions o;
    o.valence_mode = valence_mode;
    o.max_passes = 50;
    WorkingMesh start = test::working_mesh(grid);
    bool converged = false;
    flip_edges(start, o, nullptr, nullptr, nullptr, &converged);
    ASSERT_TRUE(converged);
    const WorkingMesh::Checkpoint unmoved = start.checkpoint();
    for (int v = 0; v < start.num_vertices(); ++v)
      if (start.V(v, 0) > 0.3 && start.V(v, 0) < 0.6 && start.V(v, 1) > 0.2 && start.V(v, 1) < 0.5)
        start.V.row(v) += Eigen::RowVector3d(2 * jitter(rng), 2 * jitter(rng), 0);
    const std::vector<char> dirty = moved_vertex_rings(start, unmoved);
    ASSERT_GT(std::count(dirty.begin(), dirty.end(), 1), 0);
    ASSERT_LT(std::count(dirty.begin(), dirty.end(), 1), start.num_vertices() / 2);
    WorkingMesh full = start, continued = start;
    const int full_flips = flip_edges(full, o);
    ASSERT_GT(full_flips, 0) << "valence_mode " << valence_mode;
    EXPECT_EQ(flip_edges(continued, o, nullptr, nullptr, &dirty), full_flips) << "valence_mode " << valence_mode;
    EXPECT_EQ(continued.faces(), full.faces()) << "valence_mode " << valence_mode;
  }
}

TEST(EdgeFlips, AListOfTheFacesAtTheOnlyAtVerticesFlipsWhatAFullScanFlips) {
  // With `only_at`, visiting only the faces at the marked vertices must give the same flips as a
  // scan of every face. A sheared grid (many flips, asserted) with a patch of marked vertices.
  TriangleMesh grid = test::grid(16, 0, 1, 0, 1, true);
  grid.V.col(0) += 1.5 * grid.V.col(1);
  const WorkingMesh start = test::working_mesh(grid);
  std::vector<char> marked(static_cast<std::size_t>(start.num_vertices()), 0);
  for (int v = 0; v < start.num_vertices(); ++v)
    marked[v] = start.V(v, 1) > 0.3 && start.V(v, 1) < 0.6 && start.V(v, 0) - 1.5 * start.V(v, 1) > 0.2 &&
                start.V(v, 0) - 1.5 * start.V(v, 1) < 0.5;
  ASSERT_GT(std::count(marked.begin(), marked.end(), 1), 4);
  const std::vector<std::vector<int>> vf = start.vertex_faces();
  std::vector<int> listed;
  for (int v = 0; v < start.num_vertices(); ++v)
    if (marked[v]) listed.insert(listed.end(), vf[v].begin(), vf[v].end());
  for (const int passes : {1, 5, 50}) {
    FlipOptions o;
    o.max_passes = passes;
    WorkingMesh full = start, local = start, unmarked = start;
    const int full_flips = flip_edges(full, o, &marked);
    ASSERT_GT(full_flips, 0);
    ASSERT_LT(full_flips, flip_edges(unmarked, o));  // the marks limit the flips
    EXPECT_EQ(flip_edges(local, o, &marked, nullptr, nullptr, nullptr, &listed), full_flips) << passes;
    EXPECT_EQ(local.faces(), full.faces()) << passes;
    expect_index_fresh(local);
  }
}

TEST(Polish, TangentialRelaxationEvensOutAndStaysOnTheSurface) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = jittered_sphere(test::icosphere(2), 0.06);
  const double before = ring_min_angle(w);
  for (int i = 0; i < 5; ++i) tangential_relaxation(w, surface, 2);
  EXPECT_GT(ring_min_angle(w), before);
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_NEAR(w.V.row(v).norm(), 1.0, 1e-3);
  EXPECT_TRUE(validate(w, true).ok());
}

// A vertex's ring is checked against the positions its neighbours had or were just given, for
// orientation only. On a square of two triangles alone in its component the corners on the
// diagonal move to its middle and the other two to their triangles' centroids, which narrows a
// triangle from 45° to 18°, though no triangle turns over. Every corner of the square is on its
// border: the step undoes such moves and keeps every move that spoils no face.
TEST(Polish, TangentialRelaxationUndoesMovesThatNarrowAFace) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  TriangleMesh coarse = test::icosphere(2);
  const int nv = static_cast<int>(coarse.V.rows()), nf = static_cast<int>(coarse.F.rows());
  coarse.V.conservativeResize(nv + 4, 3);
  coarse.V.bottomRows(4) << -0.05, -0.05, 1, 0.05, -0.05, 1, 0.05, 0.05, 1, -0.05, 0.05, 1;
  coarse.V.bottomRows(4).rowwise().normalize();
  coarse.F.conservativeResize(nf + 2, 3);
  coarse.F.bottomRows(2) << nv, nv + 1, nv + 2, nv, nv + 2, nv + 3;
  WorkingMesh start = jittered_sphere(coarse, 0.01);
  start.V.bottomRows(4) = coarse.V.bottomRows(4);  // the square as built
  start.N.bottomRows(4) = coarse.V.bottomRows(4);
  const double floor = 20 * M_PI / 180;
  auto step = [&](double spoiled_deg, int threads) {
    WorkingMesh w = start;
    RelaxationBorder border;
    border.spoiled_angle_deg = spoiled_deg;
    tangential_relaxation(w, surface, threads, border);
    return w;
  };
  auto spoiled = [&](const WorkingMesh& w, int f) {
    return face_min_angle(w, w.face(f)) < std::min(face_min_angle(start, start.face(f)), floor);
  };
  // Precondition: without the check a face of the square is spoiled, and no face of the sphere.
  const WorkingMesh unchecked = step(0, 2);
  ASSERT_TRUE(spoiled(unchecked, nf) || spoiled(unchecked, nf + 1));
  for (int f = 0; f < nf; ++f) ASSERT_FALSE(spoiled(unchecked, f)) << "face " << f;
  const WorkingMesh checked = step(20, 2);
  for (int f = 0; f < nf + 2; ++f) EXPECT_FALSE(spoiled(checked, f)) << "face " << f;
  EXPECT_EQ(checked.V.topRows(nv), unchecked.V.topRows(nv));
  EXPECT_EQ(step(20, 1).V, checked.V);
}

TEST(Polish, AnglePolishRaisesTheSmallestAngleAndHonoursFrozenVertices) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = jittered_sphere(test::icosphere(2), 0.06);
  std::vector<char> frozen(w.num_vertices(), 0);
  frozen[0] = 1;
  const Eigen::Vector3d x0 = w.V.row(0);
  const double before = ring_min_angle(w);
  EXPECT_GT(angle_polish(w, surface, 10, frozen, {}, 2), 0);
  EXPECT_GT(ring_min_angle(w), before);
  EXPECT_EQ((w.V.row(0).transpose() - x0).norm(), 0.0);
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_NEAR(w.V.row(v).norm(), 1.0, 1e-3);
  EXPECT_TRUE(validate(w, true).ok());
}

TEST(Polish, AnglePolishDoesNotDependOnTheThreadCount) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh a = jittered_sphere(test::icosphere(2), 0.06), b = a;
  const std::vector<char> frozen(a.num_vertices(), 0);
  angle_polish(a, surface, 4, frozen, {}, 1);
  angle_polish(b, surface, 4, frozen, {}, 2);
  EXPECT_EQ((a.V - b.V).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Polish, AnglePolishPassesOverSettledVerticesWithoutChangingTheResult) {
  // A vertex whose last search kept no move is searched again only once a vertex of its ring
  // moved (angle_polish()). Searching every vertex in every round must give the same mesh:
  // R one-round calls (each searches every vertex) against one call of R rounds, and polish
  // cycles with flips in between, marks carried across them or not.
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  const WorkingMesh start = jittered_sphere(test::icosphere(3), 0.04);
  const std::vector<char> frozen(start.num_vertices(), 0);
  WorkingMesh every = start, skipping = start;
  const std::vector<std::vector<int>> vf = start.vertex_faces();
  int passed_over = 0;  // vertices that no vertex of their ring moved in a round (skipped in the next)
  const int rounds = 20;
  for (int r = 0; r < rounds; ++r) {
    const Eigen::MatrixX3d before = every.V;
    angle_polish(every, surface, 1, frozen, {}, 2);
    if (r == rounds - 1) break;
    for (int v = 0; v < start.num_vertices(); ++v) {
      bool still = true;
      for (int id : vf[v])
        for (int w : start.face(id)) still = still && every.V.row(w) == before.row(w);
      passed_over += still;
    }
  }
  ASSERT_GT(passed_over, 0);  // precondition: the skipping run passes over some searches
  angle_polish(skipping, surface, rounds, frozen, {}, 2);
  EXPECT_EQ((every.V - skipping.V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(every.anchor, skipping.anchor);

  FlipOptions flips;
  flips.valence_mode = false;
  WorkingMesh fresh = start, carried = start;
  std::vector<char> settled;
  int flipped = 0;
  for (int cycle = 0; cycle < 4; ++cycle) {
    angle_polish(fresh, surface, 2, frozen, {}, 2);
    flipped += flip_edges(fresh, flips);
    angle_polish(carried, surface, 2, frozen, {}, 2, &settled);
    const std::vector<MeshFace> unflipped = carried.faces();
    flip_edges(carried, flips);
    unsettle_changed_faces(unflipped, carried, settled);
  }
  ASSERT_GT(flipped, 0);  // precondition: the flips changed rings between the calls
  EXPECT_EQ(fresh.faces(), carried.faces());
  EXPECT_EQ((fresh.V - carried.V).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Polish, MarksClearedWhereTheMeshChangedGiveTheSamePolishAsSearchingEveryVertex) {
  // A polish to convergence, then edits between two polishes: a few vertices moved along the
  // surface, three edges flipped (faces made and removed). The marks of the
  // first polish, cleared by unsettle_changes_since(), must give the same second polish as fresh
  // marks; and they must pass over most vertices (asserted), or the test would show nothing.
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = jittered_sphere(test::icosphere(3), 0.04);
  const std::vector<char> frozen(w.num_vertices(), 0);
  std::vector<char> settled;
  angle_polish(w, surface, 50, frozen, {}, 2, &settled);
  const WorkingMesh::Checkpoint polished = w.checkpoint();
  for (int v : {5, 60, 200}) {
    const Eigen::Vector3d x = w.V.row(v);
    const Eigen::Vector3d moved = (x + 0.03 * x.unitOrthogonal()).normalized();
    w.V.row(v) = moved.transpose();
    w.N.row(v) = moved.transpose();
  }
  for (int f1 : {10, 300, 900}) {  // one edge of each of these faces flipped
    const int a = w.face(f1)[0], b = w.face(f1)[1];
    const int f2 = w.half_edge_face(b, a);
    ASSERT_GE(f2, 0);
    w.flip(f1, 0, f2);
  }
  const std::vector<char> all_frozen(w.num_vertices(), 0);
  unsettle_changes_since(polished, w, settled);
  ASSERT_EQ(static_cast<int>(settled.size()), w.num_vertices());
  ASSERT_GT(std::count(settled.begin(), settled.end(), 1), w.num_vertices() / 2);
  WorkingMesh fresh = w, carried = w;
  const int fresh_moves = angle_polish(fresh, surface, 50, all_frozen, {}, 2);
  ASSERT_GT(fresh_moves, 0);
  EXPECT_EQ(angle_polish(carried, surface, 50, all_frozen, {}, 2, &settled), fresh_moves);
  EXPECT_EQ((fresh.V - carried.V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(fresh.anchor, carried.anchor);
}

// ---------------------------------------------------------------------------------------------

TEST(SliverCollapse, CollapsesTheShortEdgeOfSlivers) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = test::working_mesh(test::icosphere(2));
  // Move vertex 0 most of the way to a neighbour: its short edge makes slivers.
  const MeshFace f = w.face(w.vertex_faces()[0][0]);
  const int nb = f[0] == 0 ? f[1] : f[0];
  w.V.row(0) = (0.9 * w.V.row(nb) + 0.1 * w.V.row(0)).normalized();
  ASSERT_GT(slivers(w, 25), 0);
  MesherStats stats;
  EXPECT_GT(collapse_slivers(w, surface, {}, stats), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.vertices, test::icosphere(2).V.rows() - 1);
}

// ---------------------------------------------------------------------------------------------

// repair_slivers() with no vertex frozen and every vertex kept (only flips and moves).
int repair_keeping_every_vertex(WorkingMesh& w, const SurfaceProjector& surface, const SliverRepairOptions& o = {}) {
  return repair_slivers(w, surface, o, std::vector<char>(w.num_vertices(), 0), w.num_vertices());
}

TEST(SliverRepair, RemovesTheSliversOfAJitteredSphereWithoutLosingAVertex) {
  const TriangleMesh fine = test::icosphere(5);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = jittered_sphere(test::icosphere(2), 0.12);
  const int vertices = w.num_vertices();
  ASSERT_GT(slivers(w, 25), 3);
  const double before = ring_min_angle(w);
  EXPECT_GT(repair_keeping_every_vertex(w, surface), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  EXPECT_GT(ring_min_angle(w), before);
  EXPECT_EQ(vertices_in_faces(w), vertices);  // the floor: only flips and moves
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_NEAR(w.V.row(v).norm(), 1.0, 1e-3);
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
  expect_index_fresh(w);
}

TEST(SliverRepair, MovesAVertexBackIntoItsRingAndHonoursFrozenVertices) {
  // Vertex 17 of a 6 × 6 grid, (0.5, 1/3), moved most of the way to its neighbour 18: slivers.
  const TriangleMesh sheet = test::grid(6);
  const MeshSurfaceProjector surface(sheet.V, sheet.F);
  WorkingMesh w = test::working_mesh(sheet);
  w.V(17, 0) = 0.62;
  ASSERT_GT(slivers(w, 25), 0);
  WorkingMesh held = w;
  EXPECT_EQ(repair_slivers(held, surface, {}, std::vector<char>(w.num_vertices(), 1), 0), 0);
  EXPECT_EQ((held.V - w.V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(held.faces(), w.faces());
  EXPECT_GT(repair_keeping_every_vertex(w, surface), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  EXPECT_LT(w.V(17, 0), 0.62);
  EXPECT_NEAR(w.V(17, 2), 0.0, 1e-12);  // on the plane
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(r.vertices, 49);
}

TEST(SliverRepair, AFlatEarOnTheBorderGoes) {
  // A 4 × 4 grid with a flat ear (9° at its base) hung on the border edge 1–2.
  const TriangleMesh plane = test::grid(4, -0.5, 1.5, -0.5, 1.5);
  const MeshSurfaceProjector surface(plane.V, plane.F);
  WorkingMesh w = test::working_mesh(test::grid(4));
  const int ear = w.add_vertex(Eigen::Vector3d(0.375, -0.02, 0), Eigen::Vector3d::UnitZ(), -1);
  ASSERT_TRUE(w.has_half_edge(1, 2));
  w.add_face({2, 1, ear});
  ASSERT_EQ(slivers(w, 25), 1);
  EXPECT_GT(repair_slivers(w, surface, {}, std::vector<char>(w.num_vertices(), 0), 0), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  EXPECT_EQ(vertices_in_faces(w), 25);
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
}

TEST(SliverRepair, SlidesABorderVertexAlongItsBorder) {
  // Vertex 3 of a 6 × 6 grid, (0.5, 0) on the border y = 0, slid most of the way to its border
  // neighbour 4: slivers that no interior move, flip or collapse (the floor keeps every vertex)
  // can mend as well as sliding it back.
  const TriangleMesh sheet = test::grid(6);
  const MeshSurfaceProjector surface(sheet.V, sheet.F);
  WorkingMesh w = test::working_mesh(sheet);
  w.V(3, 0) = 0.62;
  ASSERT_GT(slivers(w, 25), 0);
  WorkingMesh held = w;
  SliverRepairOptions fixed_border;
  fixed_border.move_border = false;
  repair_keeping_every_vertex(held, surface, fixed_border);
  ASSERT_GT(slivers(held, 25), 0) << "precondition: only a border move mends it";
  EXPECT_GT(repair_keeping_every_vertex(w, surface), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  EXPECT_LT(w.V(3, 0), 0.62);
  EXPECT_NEAR(w.V(3, 1), 0.0, 1e-12);  // still on the border line
  EXPECT_NEAR(w.V(3, 2), 0.0, 1e-12);
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(r.vertices, 49);
}

// A grid on [-1, 1]² mapped onto the unit disk (x √(1 − y²/2), y √(1 − x²/2)): its border
// vertices lie on the unit circle.
TriangleMesh disk(int n) {
  TriangleMesh m = test::grid(n, -1, 1, -1, 1);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
    const double x = m.V(v, 0), y = m.V(v, 1);
    m.V(v, 0) = x * std::sqrt(1 - 0.5 * y * y), m.V(v, 1) = y * std::sqrt(1 - 0.5 * x * x);
  }
  return m;
}

TEST(SliverRepair, ABorderVertexOnTheInputMeshsBoundaryStaysOnIt) {
  // Vertex 3 of a coarse disk, (0, −1), moved along the circle most of the way to its border
  // neighbour 4. Sliding it back along the chord would cut inside the input's round boundary;
  // the repair keeps it on that boundary.
  const TriangleMesh fine = disk(40);
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = test::working_mesh(disk(6));
  const double a3 = std::atan2(w.V(3, 1), w.V(3, 0)), a4 = std::atan2(w.V(4, 1), w.V(4, 0));
  const double a = 0.2 * a3 + 0.8 * a4;
  Eigen::Vector3d on, n;
  ASSERT_TRUE(surface.project_to_border(Eigen::Vector3d(std::cos(a), std::sin(a), 0), on, n));
  w.V.row(3) = on.transpose();
  ASSERT_GT(slivers(w, 25), 0);
  EXPECT_GT(repair_keeping_every_vertex(w, surface), 0);
  const Eigen::Vector3d moved = w.V.row(3).transpose();
  EXPECT_LT(std::atan2(moved.y(), moved.x()), a);  // slid back towards where it was
  ASSERT_TRUE(surface.project_to_border(moved, on, n));
  EXPECT_LT((on - moved).norm(), 1e-12);  // on the input's boundary
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.vertices, 49);
}

TEST(SliverRepair, MendsAPatchWhoseNormalsAreFlipped) {
  // The sliver of MovesAVertexBackIntoItsRing on a sheet whose stored normals all point against
  // its faces (a patch whose scan normals were oriented the other way): every face faces against
  // its corners before and after, and the repair still mends it without folding a face.
  const TriangleMesh sheet = test::grid(6);
  const MeshSurfaceProjector surface(sheet.V, sheet.F);
  WorkingMesh w = test::working_mesh(sheet);
  w.N.rowwise() = -Eigen::RowVector3d::UnitZ();
  w.V(17, 0) = 0.62;
  ASSERT_GT(slivers(w, 25), 0);
  EXPECT_GT(repair_keeping_every_vertex(w, surface), 0);
  EXPECT_EQ(slivers(w, 25), 0);
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_EQ(w.N(v, 2), -1.0);  // moved vertices keep theirs
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.vertices, 49);
}

// ---------------------------------------------------------------------------------------------

// `sphere` pushed out radially into a spike around the unit direction d: radius 1 + h (x·d)^k
// for x·d > 0 (a tip of height h whose width shrinks as k grows).
TriangleMesh spiked(TriangleMesh sphere, const Eigen::Vector3d& d, double h, int k) {
  for (Eigen::Index v = 0; v < sphere.V.rows(); ++v) {
    const Eigen::Vector3d x = sphere.V.row(v).normalized();
    sphere.V.row(v) = (x * (1.0 + h * std::pow(std::max(0.0, x.dot(d)), k))).transpose();
  }
  return sphere;
}

// Largest distance from the vertices of `fine` to the faces of `w`.
double farthest_from(const WorkingMesh& w, const TriangleMesh& fine) {
  const Eigen::MatrixX3i F = face_matrix(w);
  const std::vector<SurfacePoint> p = closest_surface_points(w.V, F, fine.V);
  double gap = 0;
  for (Eigen::Index v = 0; v < fine.V.rows(); ++v)
    gap = std::max(gap, (position(w.V, F, p[static_cast<std::size_t>(v)]) - fine.V.row(v).transpose()).norm());
  return gap;
}

// A sphere with a spike of `height` (sharpness k) centred on face 0 of icosphere(2), so that no
// vertex of that coarse mesh is on its tip: `fine` (icosphere(5) spiked) is the surface, `coarse`
// the mesh to repair, `d` the spike's direction, `spacing` the coarse mesh's on the fine area.
struct SpikeOnAFace {
  Eigen::Vector3d d;
  TriangleMesh fine;
  WorkingMesh coarse;
  double spacing = 0;
};

SpikeOnAFace spike_on_a_face(double height, int k) {
  const TriangleMesh sphere = test::icosphere(2);
  SpikeOnAFace s;
  s.d = ((sphere.V.row(sphere.F(0, 0)) + sphere.V.row(sphere.F(0, 1)) + sphere.V.row(sphere.F(0, 2))) / 3.0)
            .transpose()
            .normalized();
  s.fine = spiked(test::icosphere(5), s.d, height, k);
  s.coarse = test::working_mesh(spiked(sphere, s.d, height, k));
  s.spacing = std::sqrt(surface_area(s.fine.V, s.fine.F) / s.coarse.num_vertices());
  return s;
}

TEST(CoverageRepair, PutsAVertexBackOnATipThatTheMeshCutOff) {
  const SpikeOnAFace spike = spike_on_a_face(0.35, 48);
  const TriangleMesh& fine = spike.fine;
  const Eigen::Vector3d& d = spike.d;
  const double spacing = spike.spacing;
  const MeshSurfaceProjector surface(fine.V, fine.F);
  WorkingMesh w = spike.coarse;
  const CoverageRepairOptions o;
  const double before = farthest_from(w, fine);
  ASSERT_GT(before, o.max_gap * spacing) << "the coarse mesh must cut the tip for the test";
  const double angle_before = ring_min_angle(w);

  const std::vector<char> all(w.num_vertices(), 1);
  WorkingMesh frozen = w;
  EXPECT_EQ(repair_coverage(frozen, surface, fine.V, spacing, o, &all).moves, 0);
  EXPECT_EQ((frozen.V - w.V).cwiseAbs().maxCoeff(), 0.0);

  const CoverageRepairStats st = repair_coverage(w, surface, fine.V, spacing, o);
  EXPECT_GT(st.moves, 0);
  EXPECT_NEAR(st.gap_before, before, 1e-12);
  EXPECT_LE(st.gap_after, o.max_gap * spacing);
  EXPECT_NEAR(farthest_from(w, fine), st.gap_after, 1e-12);
  EXPECT_EQ(st.uncovered_after, 0);
  EXPECT_GE(ring_min_angle(w), std::min(o.min_angle_deg * kDeg, angle_before) - 1e-9);
  for (int v = 0; v < w.num_vertices(); ++v) {  // every vertex on the spiked surface
    const Eigen::Vector3d x = w.V.row(v).normalized();
    EXPECT_NEAR(w.V.row(v).norm(), 1.0 + 0.35 * std::pow(std::max(0.0, x.dot(d)), 48), 5e-3) << "vertex " << v;
  }
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.vertices, spike.coarse.num_vertices());
}

// The spiked sphere's samples with those of a second, unmeshed copy beside it: half the samples
// are uncovered, a missing piece and not a tip, and the repair leaves the mesh as it is; with
// max_uncovered_fraction = 1 the same call moves vertices onto the tip.
TEST(CoverageRepair, LeavesAMeshThatMissesAWholePieceAsItIs) {
  const SpikeOnAFace spike = spike_on_a_face(0.35, 48);
  const MeshSurfaceProjector surface(spike.fine.V, spike.fine.F);
  Eigen::MatrixX3d samples(2 * spike.fine.V.rows(), 3);
  samples << spike.fine.V, spike.fine.V.rowwise() + Eigen::RowVector3d(5, 0, 0);
  const CoverageRepairOptions o;
  WorkingMesh w = spike.coarse;
  const CoverageRepairStats st = repair_coverage(w, surface, samples, spike.spacing, o);
  ASSERT_GT(st.uncovered_before, o.max_uncovered_fraction * static_cast<double>(samples.rows()));
  EXPECT_TRUE(st.skipped);
  EXPECT_EQ(st.moves, 0);
  EXPECT_EQ(st.uncovered_after, st.uncovered_before);
  EXPECT_EQ(w.V, spike.coarse.V);
  EXPECT_EQ(face_matrix(w), face_matrix(spike.coarse));
  CoverageRepairOptions every = o;
  every.max_uncovered_fraction = 1;
  WorkingMesh tried = spike.coarse;
  const CoverageRepairStats all = repair_coverage(tried, surface, samples, spike.spacing, every);
  EXPECT_FALSE(all.skipped);
  EXPECT_GT(all.moves, 0);
}

// Every vertex of `w` on the surface `fine` (to rounding), and `w` a valid mesh of `vertices`.
void expect_valid_on_surface(const WorkingMesh& w, const TriangleMesh& fine, int vertices) {
  const std::vector<SurfacePoint> on = closest_surface_points(fine.V, fine.F, w.V);
  for (int v = 0; v < w.num_vertices(); ++v)
    EXPECT_LT((position(fine.V, fine.F, on[static_cast<std::size_t>(v)]) - w.V.row(v).transpose()).norm(), 1e-9)
        << "vertex " << v;
  const ValidationReport r = validate(w, true);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.vertices, vertices);
}

TEST(CoverageRepair, DragsTheRingAlongWhereTheVertexAloneWouldMakeSlivers) {
  // A spike about one spacing tall: its nearest corner moved alone onto the tip (or part of the
  // way) would leave its triangles below the angle bound.
  const SpikeOnAFace spike = spike_on_a_face(0.6, 48);
  const TriangleMesh& fine = spike.fine;
  const WorkingMesh& start = spike.coarse;
  const double spacing = spike.spacing;
  const MeshSurfaceProjector surface(fine.V, fine.F);
  const CoverageRepairOptions o;
  CoverageRepairOptions alone = o;
  alone.ring_drag = 0;
  WorkingMesh single = start;
  const CoverageRepairStats st_alone = repair_coverage(single, surface, fine.V, spacing, alone);
  ASSERT_GT(st_alone.gap_after, o.max_gap * spacing) << "the tip must be out of reach of one vertex for the test";

  WorkingMesh w = start;
  const double angle_before = ring_min_angle(w);
  const CoverageRepairStats st = repair_coverage(w, surface, fine.V, spacing, o);
  EXPECT_GT(st.moves, 1);
  EXPECT_LE(st.gap_after, o.max_gap * spacing);
  EXPECT_NEAR(farthest_from(w, fine), st.gap_after, 1e-12);
  EXPECT_GE(ring_min_angle(w), std::min(o.min_angle_deg * kDeg, angle_before) - 1e-9);
  // Every vertex, dragged ones too, on the surface (the fine mesh it was projected to).
  expect_valid_on_surface(w, fine, start.num_vertices());
}

TEST(CoverageRepair, GrowsVerticesOutAlongAPartLongerThanItsRingReaches) {
  // A finger about 3.5 spacings long and one wide on a face of the coarse mesh: no vertex of it is
  // on the finger, and moving vertices (their rings dragged along too) cannot make it.
  const SpikeOnAFace spike = spike_on_a_face(1.0, 96);
  const TriangleMesh& fine = spike.fine;
  const double spacing = spike.spacing;
  const MeshSurfaceProjector surface(fine.V, fine.F);
  const CoverageRepairOptions moves_only;
  ASSERT_EQ(moves_only.grow_gap, 0.0) << "growth is off by default";
  WorkingMesh moved = spike.coarse;
  const CoverageRepairStats st0 = repair_coverage(moved, surface, fine.V, spacing, moves_only);
  ASSERT_GT(st0.gap_after, 1.5 * spacing) << "the finger must be out of reach of the moves for the test";
  EXPECT_EQ(st0.inserted, 0);

  CoverageRepairOptions grow = moves_only;
  grow.grow_gap = 1;
  grow.max_grown_fraction = 0.05;  // 8 of the 162 vertices: 0.5 % is less than one on so coarse a mesh
  WorkingMesh w = spike.coarse;
  const double angle_before = ring_min_angle(w);
  const CoverageRepairStats st = repair_coverage(w, surface, fine.V, spacing, grow);
  EXPECT_GT(st.inserted, 0);
  EXPECT_LE(st.inserted, static_cast<int>(std::floor(grow.max_grown_fraction * spike.coarse.num_vertices())));
  EXPECT_LT(st.gap_after, 0.5 * st0.gap_after) << "the inserted vertices reach out along the finger";
  EXPECT_NEAR(farthest_from(w, fine), st.gap_after, 1e-9);
  EXPECT_GE(ring_min_angle(w), std::min(grow.min_angle_deg * kDeg, angle_before) - 1e-9);
  expect_valid_on_surface(w, fine, spike.coarse.num_vertices() + st.inserted);
}

// The coarse icosphere(2) and the fine icosphere(5) with spikes of `height` (sharpness k) on the
// centroids of faces a and b of the coarse one (radius 1 + the sum of both spike terms).
struct TwoSpikes {
  TriangleMesh fine;
  WorkingMesh coarse;
  double spacing = 0;
};

TwoSpikes two_spikes(int a, int b, double height, int k) {
  const TriangleMesh sphere = test::icosphere(2);
  const auto centre = [&](int f) {
    return ((sphere.V.row(sphere.F(f, 0)) + sphere.V.row(sphere.F(f, 1)) + sphere.V.row(sphere.F(f, 2))) / 3.0)
        .transpose()
        .normalized()
        .eval();
  };
  const Eigen::Vector3d da = centre(a), db = centre(b);
  const auto spike = [&](TriangleMesh m) {
    for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
      const Eigen::Vector3d x = m.V.row(v).normalized();
      const double r = 1.0 + height * (std::pow(std::max(0.0, x.dot(da)), k) + std::pow(std::max(0.0, x.dot(db)), k));
      m.V.row(v) = (x * r).transpose();
    }
    return m;
  };
  TwoSpikes s;
  s.fine = spike(test::icosphere(5));
  s.coarse = test::working_mesh(spike(sphere));
  s.spacing = std::sqrt(surface_area(s.fine.V, s.fine.F) / s.coarse.num_vertices());
  return s;
}

// Two spikes side by side: a ring dragged towards one tip uncovers the other, so a round can
// widen the largest gap. The repair returns the state after the round with the narrowest one,
// and the mesh as given where no round narrowed it.
TEST(CoverageRepair, ReturnsTheRoundWithTheNarrowestLargestGap) {
  CoverageRepairOptions o;
  o.keep_narrowest_round = true;
  {
    const TwoSpikes s = two_spikes(1, 2, 0.5, 48);
    const MeshSurfaceProjector surface(s.fine.V, s.fine.F);
    WorkingMesh w = s.coarse;
    const CoverageRepairStats st = repair_coverage(w, surface, s.fine.V, s.spacing, o);
    ASSERT_GE(st.round_gaps.size(), 2u);
    const double narrowest = *std::min_element(st.round_gaps.begin(), st.round_gaps.end());
    ASSERT_GT(st.round_gaps.back(), narrowest) << "a later round must widen the gap for the test";
    CoverageRepairOptions last = o;  // the last round's state: its gap is the last one listed
    last.keep_narrowest_round = false;
    WorkingMesh w_last = s.coarse;
    EXPECT_EQ(repair_coverage(w_last, surface, s.fine.V, s.spacing, last).gap_after, st.round_gaps.back());
    ASSERT_LT(narrowest, st.gap_before);
    EXPECT_EQ(st.gap_after, narrowest);
    EXPECT_NEAR(farthest_from(w, s.fine), narrowest, 1e-12);
    EXPECT_GT(st.moves, 0);
    const ValidationReport r = validate(w, true);
    EXPECT_TRUE(r.ok()) << r.summary();
  }
  {
    const TwoSpikes s = two_spikes(1, 3, 0.5, 48);
    const MeshSurfaceProjector surface(s.fine.V, s.fine.F);
    WorkingMesh w = s.coarse;
    const CoverageRepairStats st = repair_coverage(w, surface, s.fine.V, s.spacing, o);
    ASSERT_FALSE(st.round_gaps.empty());
    ASSERT_GT(*std::min_element(st.round_gaps.begin(), st.round_gaps.end()), st.gap_before)
        << "every round must leave a wider gap than the mesh as given for the test";
    EXPECT_EQ(st.gap_after, st.gap_before);
    EXPECT_EQ(st.moves, 0);
    EXPECT_EQ(w.V, s.coarse.V);
    EXPECT_NEAR(farthest_from(w, s.fine), st.gap_before, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------

TEST(EdgeSplit, SplitsTheLongEdgesOfSliversAcrossAFilledHole) {
  // A planar grid with a hole of 6 × 1 cells closed by two fans of long slivers (from the hole's
  // lower-left corner to the top row, from its upper-right corner to the bottom row).
  const int n = 12;
  const TriangleMesh g = test::grid(n);
  const MeshSurfaceProjector surface(g.V, g.F);
  WorkingMesh w = test::working_mesh(g);
  std::vector<char> drop(w.num_faces(), 0);
  for (int f = 0; f < w.num_faces(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : w.face(f)) c += w.V.row(v).transpose() / 3.0;
    const int ix = static_cast<int>(std::floor(c.x() * n)), iy = static_cast<int>(std::floor(c.y() * n));
    drop[f] = ix >= 3 && ix <= 8 && iy == 5;
  }
  ASSERT_EQ(w.remove_faces(drop), 12);
  auto vertex_at = [&](int ix, int iy) {
    int best = 0;
    for (int v = 1; v < w.num_vertices(); ++v)
      if ((w.V.row(v) - Eigen::RowVector3d(ix, iy, 0) / n).norm() < (w.V.row(best) - Eigen::RowVector3d(ix, iy, 0) / n).norm())
        best = v;
    return best;
  };
  // Each fill triangle holds one loop edge a-b: oriented against the mesh's half-edge a->b.
  auto add = [&](int apex, int a, int b) {
    if (w.has_half_edge(a, b)) w.add_face({apex, b, a});
    else w.add_face({apex, a, b});
  };
  const int b0 = vertex_at(3, 5), t6 = vertex_at(9, 6);
  for (int i = 3; i < 9; ++i) add(b0, vertex_at(i, 6), vertex_at(i + 1, 6));
  for (int i = 3; i < 9; ++i) add(t6, vertex_at(i, 5), vertex_at(i + 1, 5));
  const ValidationReport r0 = validate(w, false);
  ASSERT_TRUE(r0.ok()) << r0.summary();
  ASSERT_EQ(r0.boundary_loops, 1);
  const int slivers_before = slivers(w, 25);
  ASSERT_GE(slivers_before, 10);
  MesherStats stats;
  EXPECT_GT(split_long_edges(w, surface, {}, stats), 0);
  EXPECT_LT(slivers(w, 25), slivers_before);
  const ValidationReport r = validate(w, false);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(self_intersecting_pairs(w), 0);
  for (int v = 0; v < w.num_vertices(); ++v) EXPECT_NEAR(w.V(v, 2), 0.0, 1e-12);  // on the plane
}

// ---------------------------------------------------------------------------------------------

TEST(Orientation, TurnsAnInsideOutClosedMeshOutward) {
  TriangleMesh s = test::icosphere(2);
  s.F.col(1).swap(s.F.col(2));
  WorkingMesh w = test::working_mesh(s);
  EXPECT_EQ(orient_closed_pieces_outward(w), s.F.rows());
  double volume = 0;
  for (const MeshFace& f : w.faces())
    volume += w.V.row(f[0]).dot(w.V.row(f[1]).cross(w.V.row(f[2]))) / 6.0;
  EXPECT_GT(volume, 0);
  EXPECT_EQ(orient_closed_pieces_outward(w), 0);
}

TEST(Orientation, OpenPiecesKeepTheirOrientation) {
  TriangleMesh g = test::grid(4);
  g.F.col(1).swap(g.F.col(2));
  WorkingMesh w = test::working_mesh(g);
  EXPECT_EQ(orient_closed_pieces_outward(w), 0);
  EXPECT_TRUE(w.faces() == faces_of(g.F));
}

TEST(Orientation, SmallPiecesAreRemoved) {
  const TriangleMesh s = test::icosphere(1);  // 80 faces
  const TriangleMesh t = test::icosphere(0);  // 20 faces
  const int n = static_cast<int>(s.V.rows());
  Eigen::MatrixX3d V(n + t.V.rows(), 3);
  V << s.V, t.V.rowwise() + Eigen::RowVector3d(4, 0, 0);
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(V.rows(), 3), {});
  for (const MeshFace& f : faces_of(s.F)) w.add_face(f);
  for (const MeshFace& f : faces_of(t.F)) w.add_face({f[0] + n, f[1] + n, f[2] + n});
  EXPECT_EQ(remove_small_pieces(w, 21), 20);
  EXPECT_EQ(w.num_faces(), 80);
  EXPECT_EQ(remove_small_pieces(w, 100), 0);  // never every face
}

// ---------------------------------------------------------------------------------------------

TEST(Compaction, DropsUnusedVerticesInOrder) {
  Eigen::MatrixX3d V(5, 3);
  V << 0, 0, 0, 9, 9, 9, 1, 0, 0, 0, 1, 0, 8, 8, 8;
  WorkingMesh w(V, Eigen::MatrixX3d::Zero(5, 3), {});
  w.add_face({0, 2, 3});
  int unused = 0;
  const TriangleMesh m = compact_mesh(w, &unused);
  EXPECT_EQ(unused, 2);
  ASSERT_EQ(m.V.rows(), 3);
  EXPECT_EQ(m.V.row(1), V.row(2));
  EXPECT_EQ(m.F.row(0), Eigen::RowVector3i(0, 1, 2));
}

// ---------------------------------------------------------------------------------------------

TEST(ReconstructionDriver, CvtOptionsFollowTheStartOptions) {
  ReconstructionOptions o;
  o.sites = 1234;
  o.iterations = 7;
  o.seed = 5;
  o.lloyd_relaxation = 1.3;
  const CvtOptions surface = reconstruction_cvt_options(o);  // default: the surface-Lloyd start
  EXPECT_EQ(surface.sites, 1234);
  EXPECT_EQ(surface.iterations, 7);
  EXPECT_EQ(surface.seed, 5u);
  EXPECT_EQ(surface.relaxation, 1.3);
  EXPECT_FALSE(surface.build_dual);
  EXPECT_EQ(surface.initialization, CvtInitialization::farthest_point);
  EXPECT_EQ(surface.surface_lloyd_iterations, o.surface_lloyd_iterations);
  EXPECT_EQ(surface.surface_lloyd_relaxation, o.cloud.surface_lloyd_relaxation);
  EXPECT_EQ(surface.voronoi_rings, surface.voronoi_rings_settled);
  o.surface_lloyd_iterations = 0;
  o.farthest_point_start = true;
  const CvtOptions graph = reconstruction_cvt_options(o);
  EXPECT_EQ(graph.initialization, CvtInitialization::farthest_point);
  EXPECT_EQ(graph.graph_lloyd_iterations, o.cloud.graph_lloyd_iterations);
  EXPECT_EQ(graph.surface_lloyd_iterations, 0);
  o.farthest_point_start = false;
  EXPECT_EQ(reconstruction_cvt_options(o).initialization, CvtInitialization::random);
}

TEST(ReconstructionDriver, RejectsBadStageOptions) {
  const TriangleMesh s = test::icosphere(3);
  ReconstructionOptions o;
  o.sites = 50;
  auto rejects = [&](const ReconstructionOptions& bad, const std::string& needle) {
    try {
      reconstruct_surface(s.V, bad);
      ADD_FAILURE() << "no exception for " << needle;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const std::vector<std::pair<std::function<void(ReconstructionOptions&)>, std::string>> cases = {
      {[](ReconstructionOptions& b) { b.cloud.fit_cells = 0; }, "fit_cells"},
      {[](ReconstructionOptions& b) { b.cloud.max_crossing_fraction = 1.5; }, "max_crossing_fraction"},
      {[](ReconstructionOptions& b) { b.cloud.surface_lloyd_relaxation = 2; }, "surface_lloyd_relaxation"},
      {[](ReconstructionOptions& b) { b.cloud.orientation_offset_penalty = -1; }, "orientation_offset_penalty"},
      {[](ReconstructionOptions& b) { b.fit.min_quadratic_points = 3; }, "min_quadratic_points"},
      {[](ReconstructionOptions& b) { b.mesher.min_piece_faces = -1; }, "min_piece_faces"}};
  for (const auto& [change, needle] : cases) {
    ReconstructionOptions bad = o;
    change(bad);
    rejects(bad, needle);
  }
}

}  // namespace
}  // namespace heatcvt
