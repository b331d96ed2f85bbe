// Loop subdivision keeps topology (χ, closedness) and grows #V by #E.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "heatcvt/laplacian.h"
#include "heatcvt/subdivision.h"
#include "test_support.h"

using namespace heatcvt;

TEST(LoopSubdivision, KeepsTopologyAndCounts) {
  for (const auto& mesh : {test::icosphere(1), test::torus(12, 8), test::grid(5)}) {
    MeshTopology before = mesh_topology(mesh.F, static_cast<int>(mesh.V.rows()));
    TriangleMesh fine = loop_subdivide(mesh);
    MeshTopology after = mesh_topology(fine.F, static_cast<int>(fine.V.rows()));
    EXPECT_EQ(fine.V.rows(), before.vertices + before.edges);
    EXPECT_EQ(fine.F.rows(), 4 * mesh.F.rows());
    EXPECT_EQ(after.euler_characteristic(), before.euler_characteristic());
    EXPECT_EQ(after.boundary_edges, 2 * before.boundary_edges);
    EXPECT_EQ(after.nonmanifold_edges, 0);
    EXPECT_EQ(after.inconsistent_edges, 0);
  }
}

// Largest angle (radians) between the normals of two faces sharing an edge: the crease of a
// polyhedral surface, which goes to 0 as Loop subdivision converges to its smooth limit surface.
double largest_crease(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> first_face;
  double crease = 0;
  for (int f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    for (int k = 0; k < 3; ++k) {
      const auto key = std::minmax(m.F(f, k), m.F(f, (k + 1) % 3));
      const auto [it, inserted] = first_face.emplace(key, f);
      if (inserted) continue;
      const int g = it->second;
      const Eigen::Vector3d p = m.V.row(m.F(g, 0)), q = m.V.row(m.F(g, 1)), r = m.V.row(m.F(g, 2));
      const Eigen::Vector3d ng = (q - p).cross(r - p).normalized();
      crease = std::max(crease, std::acos(std::clamp(n.dot(ng), -1.0, 1.0)));
    }
  }
  return crease;
}

constexpr double kCreaseRatio = 0.6;      // per level, largest crease angle
constexpr double kAreaChangeRatio = 0.3;  // per level, change of the area

TEST(LoopSubdivision, ConvergesTowardSmoothSurfaceAndPlaneStaysPlanar) {
  // A planar grid stays planar.
  TriangleMesh plane = loop_subdivide(test::grid(4));
  EXPECT_LT(plane.V.col(2).cwiseAbs().maxCoeff(), 1e-15);
  // Convergence toward a smooth (C1) limit surface, from a coarse icosphere: the largest crease
  // angle shrinks with the edge length, by a factor of about 1/2 per level (0.56 where it is
  // largest, at the valence-5 vertices), and the area converges with the squared edge length
  // (changes shrinking by about 1/4 per level); the subdivided surface stays inside the sphere
  // through the coarse vertices (Loop shrinks).
  TriangleMesh m = test::icosphere(1);
  double crease = largest_crease(m), area = surface_area(m.V, m.F);
  std::vector<double> area_change;
  for (int level = 1; level <= 4; ++level) {
    m = loop_subdivide(m);
    const double c = largest_crease(m), a = surface_area(m.V, m.F);
    std::printf("[ info ] level %d: %ld vertices, largest crease %.4f rad, area %.6f\n", level,
                static_cast<long>(m.V.rows()), c, a);
    EXPECT_LT(c, kCreaseRatio * crease) << "level " << level;
    EXPECT_LT(a, 4 * M_PI);
    area_change.push_back(std::abs(a - area));
    crease = c;
    area = a;
  }
  for (size_t k = 1; k < area_change.size(); ++k) EXPECT_LT(area_change[k], kAreaChangeRatio * area_change[k - 1]) << "level " << k + 1;
  EXPECT_GE(loop_subdivide_to(test::icosphere(1), 2000).V.rows(), 2000);
}
