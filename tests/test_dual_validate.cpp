// Surface checks (validate.h) on shapes with known defects, and the dual triangulation
// (dual_mesh.h) of heat Voronoi diagrams and CVTs on real meshes.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/validate.h"
#include "heatcvt/voronoi.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

const MeshCheck& check(const ValidationReport& r, const std::string& name) {
  const MeshCheck* c = r.find(name);
  if (!c) throw std::runtime_error("missing check " + name);
  return *c;
}

TriangleMesh two_components(const TriangleMesh& a, const TriangleMesh& b, const Eigen::Vector3d& shift) {
  TriangleMesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, (b.V.rowwise() + shift.transpose());
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + static_cast<int>(a.V.rows())).matrix();
  return m;
}

}  // namespace

TEST(Validate, CleanClosedSurfacesPassWithTheirGenus) {
  ValidationOptions opt;
  opt.expected_genus = 0;
  opt.expected_components = 1;
  auto sphere = test::icosphere(3);
  ValidationReport r = validate_triangle_mesh(sphere.V, sphere.F, opt);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.euler_characteristic, 2);
  auto torus = test::torus(40, 20);
  opt.expected_genus = 1;
  r = validate_triangle_mesh(torus.V, torus.F, opt);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.genus, 1);
  // two disjoint spheres: genus 0, 2 components, χ = 4
  auto two = two_components(sphere, sphere, Eigen::Vector3d(3, 0, 0));
  opt.expected_genus = 0;
  opt.expected_components = 2;
  r = validate_triangle_mesh(two.V, two.F, opt);
  EXPECT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(r.euler_characteristic, 4);
}

TEST(Validate, RealFilesHaveTheirKnownGenus) {
  for (auto [file, genus] : {std::pair<const char*, int>{"meshes/fertility.off", 4}, {"meshes/casting.obj", 9}}) {
    TriangleMesh m = read_mesh(test::data_path(file));
    ValidationOptions opt;
    opt.expected_genus = genus;
    opt.check_self_intersections = false;
    ValidationReport r = validate_triangle_mesh(m.V, m.F, opt);
    EXPECT_TRUE(r.ok()) << file << "\n" << r.summary();
    EXPECT_EQ(mesh_genus(m.F, static_cast<int>(m.V.rows())), genus) << file;
  }
}

TEST(Validate, OpenGridIsNotClosedAndSaysWhere) {
  auto g = test::grid(4);
  ValidationReport r = validate_triangle_mesh(g.V, g.F);
  EXPECT_FALSE(r.ok());
  const MeshCheck& closed = check(r, "closed");
  EXPECT_FALSE(closed.passed);
  EXPECT_EQ(closed.where.size(), 10u);  // max_listed
  EXPECT_NE(closed.detail.find("16 border edges"), std::string::npos) << closed.detail;
  EXPECT_TRUE(check(r, "manifold_edges").passed);
  EXPECT_EQ(r.boundary_loops, 1);
  EXPECT_EQ(r.genus, 0);  // a disk
  ValidationOptions open;
  open.require_closed = false;
  EXPECT_TRUE(validate_triangle_mesh(g.V, g.F, open).ok());
}

TEST(Validate, DetectsFlippedFaceNonManifoldEdgeAndVertex) {
  auto sphere = test::icosphere(2);
  {  // one flipped face: three inconsistent edges
    auto m = sphere;
    std::swap(m.F(7, 1), m.F(7, 2));
    ValidationReport r = validate_triangle_mesh(m.V, m.F);
    const MeshCheck& c = check(r, "consistent_orientation");
    EXPECT_FALSE(c.passed);
    EXPECT_EQ(c.where.size(), 3u);
    for (const auto& e : c.where) {
      int hits = 0;
      for (int k = 0; k < 3; ++k) hits += (m.F(7, k) == e[0]) + (m.F(7, k) == e[1]);
      EXPECT_EQ(hits, 2) << "edge not on the flipped face";
    }
    EXPECT_FALSE(check(r, "cgal_polygon_mesh").passed);
    EXPECT_FALSE(check(r, "no_self_intersections").ran);
    EXPECT_EQ(r.genus, -1);
  }
  {  // a fin: a third face on an edge
    auto m = sphere;
    const int a = m.F(0, 0), b = m.F(0, 1);
    m.V.conservativeResize(m.V.rows() + 1, 3);
    m.V.row(m.V.rows() - 1) = 2.0 * m.V.row(a);
    m.F.conservativeResize(m.F.rows() + 1, 3);
    m.F.row(m.F.rows() - 1) << a, b, static_cast<int>(m.V.rows()) - 1;
    ValidationReport r = validate_triangle_mesh(m.V, m.F);
    const MeshCheck& c = check(r, "manifold_edges");
    ASSERT_FALSE(c.passed);
    EXPECT_EQ(c.where[0], (std::vector<int>{std::min(a, b), std::max(a, b)}));
  }
  {  // two spheres glued at one vertex (a bow-tie vertex)
    auto m = two_components(sphere, sphere, Eigen::Vector3d(2, 0, 0));
    const int n = static_cast<int>(sphere.V.rows());
    const int glued = 0;
    for (int f = 0; f < m.F.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (m.F(f, k) == n + glued) m.F(f, k) = glued;
    ValidationReport r = validate_triangle_mesh(m.V, m.F);
    const MeshCheck& c = check(r, "manifold_vertices");
    ASSERT_FALSE(c.passed);
    EXPECT_EQ(c.where[0], std::vector<int>{glued});
    EXPECT_FALSE(check(r, "all_vertices_used").passed);  // the copy of the glued vertex
  }
}

TEST(Validate, FindsSelfIntersections) {
  auto sphere = test::icosphere(2);
  auto m = two_components(sphere, sphere, Eigen::Vector3d(1.0, 0.1, 0.05));  // overlapping spheres
  ValidationReport r = validate_triangle_mesh(m.V, m.F);
  const MeshCheck& c = check(r, "no_self_intersections");
  EXPECT_TRUE(c.ran);
  EXPECT_FALSE(c.passed);
  EXPECT_GT(r.self_intersecting_pairs, 0);
  ASSERT_FALSE(c.where.empty());
  const int n = static_cast<int>(sphere.F.rows());
  for (const auto& p : c.where) EXPECT_TRUE((p[0] < n) != (p[1] < n)) << "pair within one sphere";
  // separated: clean
  auto apart = two_components(sphere, sphere, Eigen::Vector3d(2.5, 0, 0));
  EXPECT_TRUE(check(validate_triangle_mesh(apart.V, apart.F), "no_self_intersections").passed);
}

TEST(Validate, BadInputThrows) {
  auto s = test::icosphere(1);
  EXPECT_THROW(validate_triangle_mesh(s.V, Eigen::MatrixX3i(0, 3)), InvalidInputError);
  auto bad = s;
  bad.F(0, 0) = static_cast<int>(s.V.rows());
  EXPECT_THROW(validate_triangle_mesh(bad.V, bad.F), InvalidInputError);
  bad = s;
  bad.V(0, 0) = std::nan("");
  EXPECT_THROW(validate_triangle_mesh(bad.V, bad.F), InvalidInputError);
}

TEST(DualMesh, DualOfHeatVoronoiOnSphereIsAClosedGenus0Manifold) {
  auto sphere = test::icosphere(4);
  HeatSolver solver(cotan_laplacian(sphere.V, sphere.F));
  // well-spread sites: every 25th face centre
  std::vector<SurfacePoint> sites;
  for (int f = 0; f < sphere.F.rows(); f += 61) sites.push_back({f, Eigen::Vector3d(1.0 / 3, 1.0 / 3, 1.0 / 3)});
  VoronoiDiagram d = heat_voronoi(sphere.V, sphere.F, solver, sites);
  Eigen::MatrixX3d P(sites.size(), 3);
  for (size_t s = 0; s < sites.size(); ++s) P.row(s) = position(sphere.V, sphere.F, sites[s]);
  DualMesh dual = dual_mesh(d, P);
  EXPECT_EQ(dual.V.rows(), static_cast<Eigen::Index>(sites.size()));
  EXPECT_TRUE(dual.unused_sites.empty());
  EXPECT_EQ(dual.flipped_against_input, 0);
  ValidationOptions opt;
  opt.expected_genus = 0;
  ValidationReport r = validate_triangle_mesh(dual.V, dual.F, opt);
  EXPECT_TRUE(r.ok()) << r.summary();
  // Euler: a closed genus-0 triangulation with n vertices has 2n − 4 faces
  EXPECT_EQ(dual.F.rows(), 2 * static_cast<Eigen::Index>(sites.size()) - 4);
  // outward: the dual's normals agree with the sphere's position vectors
  for (int f = 0; f < dual.F.rows(); ++f) {
    Eigen::Vector3d a = dual.V.row(dual.F(f, 0)), b = dual.V.row(dual.F(f, 1)), c = dual.V.row(dual.F(f, 2));
    EXPECT_GT((b - a).cross(c - a).dot(a + b + c), 0.0);
  }
  // triangle_quality against the angles computed here from the dot products (acos of the
  // normalised edge vectors): the smallest angle and the mean of the per-triangle smallest angles.
  TriangleQuality q = triangle_quality(dual.V, dual.F);
  double smallest = 180, sum_of_smallest = 0;
  for (int f = 0; f < dual.F.rows(); ++f) {
    double tri_min = 180;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = dual.V.row(dual.F(f, k)), u = dual.V.row(dual.F(f, (k + 1) % 3)) - p.transpose(),
                            w = dual.V.row(dual.F(f, (k + 2) % 3)) - p.transpose();
      tri_min = std::min(tri_min, std::acos(u.normalized().dot(w.normalized())) * 180.0 / M_PI);
    }
    smallest = std::min(smallest, tri_min);
    sum_of_smallest += tri_min;
  }
  EXPECT_NEAR(q.min_angle_deg, smallest, 1e-9);
  EXPECT_NEAR(q.mean_min_angle_deg, sum_of_smallest / dual.F.rows(), 1e-9);
  EXPECT_GT(smallest, 0.0);  // no degenerate triangle
}

TEST(DualMesh, FourSitesInASquareGiveTwoOrientedTriangles) {
  // Four sites around the centre of a grid: one degree-4 Voronoi vertex (split into a fan of two)
  // or two degree-3 ones; either way two triangles, oriented like the grid.
  auto g = test::grid(40, -1, 1, -1, 1, false);
  HeatSolver solver(cotan_laplacian(g.V, g.F));
  std::vector<SurfacePoint> sites;
  auto vertex_point = [&](double x, double y) {
    int best = 0;
    for (int v = 0; v < g.V.rows(); ++v)
      if ((g.V.row(v) - Eigen::RowVector3d(x, y, 0)).norm() < (g.V.row(best) - Eigen::RowVector3d(x, y, 0)).norm())
        best = v;
    for (int f = 0; f < g.F.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (g.F(f, k) == best) {
          SurfacePoint p;
          p.face = f;
          p.bary = Eigen::Vector3d::Zero();
          p.bary[k] = 1;
          return p;
        }
    return SurfacePoint{};
  };
  for (auto [x, y] : {std::pair<double, double>{0.5, 0.5}, {-0.5, 0.5}, {-0.5, -0.5}, {0.5, -0.5}})
    sites.push_back(vertex_point(x, y));
  VoronoiDiagram d = heat_voronoi(g.V, g.F, solver, sites);
  Eigen::MatrixX3d P(4, 3);
  for (int s = 0; s < 4; ++s) P.row(s) = position(g.V, g.F, sites[s]);
  DualMesh dual = dual_mesh(d, P);
  EXPECT_EQ(dual.F.rows(), 2) << "voronoi vertices " << dual.voronoi_vertices << " split " << dual.split_vertices;
  for (int f = 0; f < dual.F.rows(); ++f) {  // oriented like the grid (+z)
    Eigen::Vector3d a = P.row(dual.F(f, 0)), b = P.row(dual.F(f, 1)), c = P.row(dual.F(f, 2));
    EXPECT_GT((b - a).cross(c - a).z(), 0.0);
  }
  ValidationOptions open;
  open.require_closed = false;
  EXPECT_TRUE(validate_triangle_mesh(dual.V, dual.F, open).ok());
}
