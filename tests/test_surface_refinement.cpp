// Consistent orientation of faces written with mixed orientations (mesh_orientation.h), the
// refinement that keeps the surface and reshapes the slivers of CAD meshes
// (surface_refinement.h), and remesh_cvt() on such meshes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_orientation.h"
#include "heatcvt/remesh.h"
#include "heatcvt/shapes.h"
#include "heatcvt/subdivision.h"
#include "heatcvt/surface_refinement.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A closed cylinder as CAD systems export it: each cap a fan of `segments` needles from its
// centre, the side one strip of two triangles per segment (about 40 times longer than wide for
// the defaults). Outward orientation.
TriangleMesh cad_cylinder(int segments = 64, double radius = 0.5, double height = 2.0) {
  TriangleMesh m;
  m.V.resize(2 * segments + 2, 3);
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * kPi * i / segments;
    m.V.row(i) << radius * std::cos(a), radius * std::sin(a), 0;
    m.V.row(segments + i) << radius * std::cos(a), radius * std::sin(a), height;
  }
  const int bottom = 2 * segments, top = bottom + 1;
  m.V.row(bottom) << 0, 0, 0;
  m.V.row(top) << 0, 0, height;
  m.F.resize(4 * segments, 3);
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    m.F.row(4 * i) << i, j, segments + j;
    m.F.row(4 * i + 1) << i, segments + j, segments + i;
    m.F.row(4 * i + 2) << bottom, j, i;
    m.F.row(4 * i + 3) << top, segments + i, segments + j;
  }
  return m;
}

// A flat square of side 1 triangulated as a fan from one corner to points along the two far
// sides: an open mesh of needles (one boundary loop).
TriangleMesh fan_square(int per_side = 16) {
  TriangleMesh m;
  std::vector<Eigen::Vector3d> p{{0, 0, 0}};
  for (int i = 0; i <= per_side; ++i) p.emplace_back(1.0, static_cast<double>(i) / per_side, 0);
  for (int i = per_side - 1; i >= 0; --i) p.emplace_back(static_cast<double>(i) / per_side, 1.0, 0);
  m.V.resize(static_cast<Eigen::Index>(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) m.V.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(p.size()) - 2, 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) m.F.row(f) << 0, static_cast<int>(f) + 1, static_cast<int>(f) + 2;
  return m;
}

// Smallest angle (degrees) of every face.
std::vector<double> smallest_angles(const TriangleMesh& m) {
  std::vector<double> out;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    double smallest = 180;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = m.V.row(m.F(f, k)), b = m.V.row(m.F(f, (k + 1) % 3)), c = m.V.row(m.F(f, (k + 2) % 3));
      const Eigen::Vector3d u = b - a, w = c - a;
      smallest = std::min(smallest, std::atan2(u.cross(w).norm(), u.dot(w)) * 180 / kPi);
    }
    out.push_back(smallest);
  }
  std::sort(out.begin(), out.end());
  return out;
}

double percentile(const std::vector<double>& sorted, double q) {
  return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
}

// Largest distance from a point of `fine` (its vertices and face centroids) to the surface of
// `coarse`.
double largest_distance_to(const TriangleMesh& coarse, const TriangleMesh& fine) {
  Eigen::MatrixX3d points(fine.V.rows() + fine.F.rows(), 3);
  points.topRows(fine.V.rows()) = fine.V;
  for (Eigen::Index f = 0; f < fine.F.rows(); ++f)
    points.row(fine.V.rows() + f) = (fine.V.row(fine.F(f, 0)) + fine.V.row(fine.F(f, 1)) + fine.V.row(fine.F(f, 2))) / 3;
  const std::vector<SurfacePoint> nearest = closest_surface_points(coarse.V, coarse.F, points);
  double largest = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    largest = std::max(largest, (position(coarse.V, coarse.F, nearest[static_cast<std::size_t>(i)]) - points.row(i).transpose()).norm());
  return largest;
}

double longest_edge(const TriangleMesh& m) {
  double longest = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) longest = std::max(longest, (m.V.row(m.F(f, k)) - m.V.row(m.F(f, (k + 1) % 3))).norm());
  return longest;
}

// `faces` of F reversed.
Eigen::MatrixX3i with_reversed(Eigen::MatrixX3i F, const std::vector<int>& faces) {
  for (const int f : faces) std::swap(F(f, 1), F(f, 2));
  return F;
}

}  // namespace

// A third of a closed mesh's faces reversed at random: they are turned back, the others are left
// as they are (the piece keeps the orientation most of its faces have), and the result has no
// edge traversed twice in the same direction. With two thirds reversed the piece takes their
// orientation: every face ends reversed from the original.
TEST(MeshOrientation, FlippedFacesAreTurnedToTheOrientationOfMostOfThePiece) {
  const TriangleMesh sphere = test::icosphere(3);
  const int nf = static_cast<int>(sphere.F.rows());
  std::vector<int> order(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) order[static_cast<std::size_t>(f)] = f;
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  const std::vector<int> third(order.begin(), order.begin() + nf / 3), two_thirds(order.begin(), order.begin() + 2 * nf / 3);

  Eigen::MatrixX3i F = with_reversed(sphere.F, third);
  ASSERT_GT(mesh_topology(F, static_cast<int>(sphere.V.rows())).inconsistent_edges, 0);
  EXPECT_EQ(orient_faces_consistently(F), static_cast<int>(third.size()));
  EXPECT_EQ(F, sphere.F);

  F = with_reversed(sphere.F, two_thirds);
  EXPECT_EQ(orient_faces_consistently(F), nf - static_cast<int>(two_thirds.size()));
  std::vector<int> all(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) all[static_cast<std::size_t>(f)] = f;
  EXPECT_EQ(F, with_reversed(sphere.F, all));
  EXPECT_EQ(mesh_topology(F, static_cast<int>(sphere.V.rows())).inconsistent_edges, 0);
}

// Each piece of a mesh of two pieces is oriented on its own; a consistent mesh is left as it is;
// a Klein bottle (no consistent orientation) and a mesh with an edge of three faces are refused
// with −1 and left as they are.
TEST(MeshOrientation, PiecesAreOrientedAloneAndMeshesWithoutAnOrientationAreLeftAsTheyAre) {
  const TriangleMesh a = test::icosphere(2), b = test::torus(12, 8);
  TriangleMesh both;
  both.V.resize(a.V.rows() + b.V.rows(), 3);
  both.V << a.V, b.V;
  both.F.resize(a.F.rows() + b.F.rows(), 3);
  both.F << a.F, (b.F.array() + static_cast<int>(a.V.rows())).matrix();
  // Most of the torus reversed, a few faces of the sphere.
  std::vector<int> reversed{0, 5, 9};
  for (int f = 0; f < 3 * static_cast<int>(b.F.rows()) / 4; ++f) reversed.push_back(static_cast<int>(a.F.rows()) + f);
  Eigen::MatrixX3i F = with_reversed(both.F, reversed);
  EXPECT_EQ(orient_faces_consistently(F), 3 + static_cast<int>(b.F.rows()) - 3 * static_cast<int>(b.F.rows()) / 4);
  EXPECT_EQ(F.topRows(a.F.rows()), a.F);
  EXPECT_EQ(mesh_topology(F, static_cast<int>(both.V.rows())).inconsistent_edges, 0);
  EXPECT_NE(F.bottomRows(b.F.rows()), both.F.bottomRows(b.F.rows()));  // the torus took its majority's orientation

  Eigen::MatrixX3i same = both.F;
  EXPECT_EQ(orient_faces_consistently(same), 0);
  EXPECT_EQ(same, both.F);

  const TriangleMesh klein = klein_bottle_mesh(40, 16);
  Eigen::MatrixX3i kf = klein.F;
  EXPECT_EQ(orient_faces_consistently(kf), -1);
  EXPECT_EQ(kf, klein.F);

  Eigen::MatrixX3i fin(3, 3);  // three faces on the edge {0, 1}
  fin << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  const Eigen::MatrixX3i fin_before = fin;
  EXPECT_EQ(orient_faces_consistently(fin), -1);
  EXPECT_EQ(fin, fin_before);
}

// The refinement keeps the surface: with flips only between exactly coplanar faces, every vertex
// and every face centroid of the refined CAD cylinder lies on the input (to rounding), the
// topology is the input's (closed, genus 0, oriented manifold), it has at least the vertices asked
// for, and no edge is longer than split_ratio times the last target length.
TEST(SurfaceRefinement, KeepsTheSurfaceTheTopologyAndBoundsTheEdgeLength) {
  const TriangleMesh input = cad_cylinder();
  SurfaceRefinementOptions o;
  o.target_vertices = 8000;
  o.flat_angle_deg = 0;
  const SurfaceRefinement r = refine_surface(input, o);
  EXPECT_GE(r.mesh.V.rows(), 8000);
  EXPECT_GT(r.splits, 0);
  EXPECT_GT(r.flips, 0);
  EXPECT_LT(largest_distance_to(input, r.mesh), 1e-12);
  EXPECT_LE(longest_edge(r.mesh), o.split_ratio * r.target_edge_length * (1 + 1e-12));
  ValidationOptions vo;
  vo.check_self_intersections = true;
  vo.expected_genus = 0;
  const ValidationReport checks = validate_triangle_mesh(r.mesh.V, r.mesh.F, vo);
  EXPECT_TRUE(checks.ok()) << checks.summary();
  EXPECT_EQ(checks.boundary_loops, 0);
  EXPECT_NEAR(surface_area(r.mesh.V, r.mesh.F), surface_area(input.V, input.F), 1e-9);
}

// Needles become well-shaped triangles where the surface allows it. Rule for every input here:
// the refinement's 1st percentile of the smallest angle is at least 20°, where midpoint
// subdivision to at least as many vertices keeps the input's needles (below 5°). Inputs: the CAD
// cylinder (fans on flat caps, strips on a faceted side) and a flat square fanned from a corner
// (open: its border keeps its length and its vertices stay on it).
TEST(SurfaceRefinement, ReshapesTheNeedlesOfFansAndStrips) {
  for (const TriangleMesh& input : {cad_cylinder(), fan_square()}) {
    SurfaceRefinementOptions o;
    o.target_vertices = 4000;
    const SurfaceRefinement r = refine_surface(input, o);
    TriangleMesh midpoint = input;
    while (midpoint.V.rows() < r.mesh.V.rows()) midpoint = midpoint_subdivide(midpoint);
    const double refined_p1 = percentile(smallest_angles(r.mesh), 0.01);
    const double midpoint_p1 = percentile(smallest_angles(midpoint), 0.01);
    ASSERT_LT(midpoint_p1, 5.0) << "the input must have needles that midpoint subdivision keeps";
    EXPECT_GE(refined_p1, 20.0) << input.V.rows() << " input vertices";
    const MeshTopology before = mesh_topology(input.F, static_cast<int>(input.V.rows()));
    const MeshTopology after = mesh_topology(r.mesh.F, static_cast<int>(r.mesh.V.rows()));
    EXPECT_EQ(after.boundary_loops, before.boundary_loops);
    EXPECT_EQ(after.euler_characteristic(), before.euler_characteristic());
    double border_before = 0, border_after = 0;
    for (const auto& [u, v] : boundary_edges(input.F)) border_before += (input.V.row(u) - input.V.row(v)).norm();
    for (const auto& [u, v] : boundary_edges(r.mesh.F)) border_after += (r.mesh.V.row(u) - r.mesh.V.row(v)).norm();
    EXPECT_NEAR(border_after, border_before, 1e-9);
  }
}

// A finely faceted cylinder (2,048 strips, bent by 0.18° from one to the next) under a flat
// angle of 0.2°: its side is flat pair by pair only, and there the flips make long edges as the
// splits remove them. The refinement ends, with at least the vertices asked for and at most the
// input's plus max_vertex_factor times as many, and keeps the topology.
TEST(SurfaceRefinement, EndsOnACurveFlatOnlyPairByPair) {
  const TriangleMesh input = cad_cylinder(2048);
  SurfaceRefinementOptions o;
  o.target_vertices = 2000;
  o.flat_angle_deg = 0.2;
  ASSERT_LT(360.0 / 2048, o.flat_angle_deg) << "neighbouring strips must be within the flat angle";
  const SurfaceRefinement r = refine_surface(input, o);
  EXPECT_GE(r.mesh.V.rows(), 2000);
  EXPECT_LE(r.mesh.V.rows(), input.V.rows() + o.max_vertex_factor * o.target_vertices);
  const MeshTopology after = mesh_topology(r.mesh.F, static_cast<int>(r.mesh.V.rows()));
  EXPECT_EQ(after.nonmanifold_edges, 0);
  EXPECT_EQ(after.boundary_loops, 0);
  EXPECT_EQ(after.euler_characteristic(), 2);
  SurfaceRefinementOptions bad = o;
  bad.max_vertex_factor = 0.5;
  EXPECT_THROW(refine_surface(input, bad), InvalidInputError);
}

// The same input and options give the same mesh; a mesh without anything to split or flip
// (a regular grid of right triangles, cocircular pairs) is returned as it is; inputs that are
// not oriented edge manifolds are refused.
TEST(SurfaceRefinement, IsDeterministicLeavesDelaunayMeshesAndRefusesOtherInputs) {
  SurfaceRefinementOptions o;
  o.target_vertices = 3000;
  const SurfaceRefinement a = refine_surface(cad_cylinder(), o), b = refine_surface(cad_cylinder(), o);
  EXPECT_EQ(a.mesh.V, b.mesh.V);
  EXPECT_EQ(a.mesh.F, b.mesh.F);

  const TriangleMesh grid = test::grid(10);
  SurfaceRefinementOptions flips_only;
  const SurfaceRefinement g = refine_surface(grid, flips_only);
  EXPECT_EQ(g.splits + g.flips, 0);
  EXPECT_EQ(g.mesh.F, grid.F);

  TriangleMesh flipped = cad_cylinder();
  std::swap(flipped.F(0, 1), flipped.F(0, 2));
  EXPECT_THROW(refine_surface(flipped, o), InvalidInputError);
  EXPECT_THROW(refine_surface(klein_bottle_mesh(40, 16), o), InvalidInputError);
}

// remesh_cvt() on the CAD cylinder with a fifth of its faces written reversed: the faces are
// oriented first (reoriented_faces counts them), the refinement reshapes the needles, and the
// output passes every check (closed, genus 0, oriented, no self-intersection) with the count
// within 2 % and φm ≥ 52°; its sites lie on the input.
TEST(RemeshCvt, ACadMeshWithFlippedFacesGivesAValidRemesh) {
  TriangleMesh input = cad_cylinder();
  std::vector<int> reversed;
  for (int f = 0; f < input.F.rows(); f += 5) reversed.push_back(f);
  input.F = with_reversed(input.F, reversed);
  RemeshOptions o;
  o.cvt.sites = 1000;
  o.cvt.threads = 2;
  const RemeshResult r = remesh_cvt(input, o);
  EXPECT_EQ(r.reoriented_faces, static_cast<int>(reversed.size()));
  EXPECT_GT(r.refinement_splits, 0);
  EXPECT_EQ(r.refinement_levels, 0);
  EXPECT_TRUE(r.checks.ok()) << r.checks.summary();
  EXPECT_EQ(r.checks.genus, 0);
  EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), 1000, 20);
  EXPECT_GE(r.quality.mean_min_angle_deg, 52.0);
  for (const SurfacePoint& s : r.sites) ASSERT_TRUE(s.face >= 0 && s.face < input.F.rows());
}
