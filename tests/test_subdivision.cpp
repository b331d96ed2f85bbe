// Loop subdivision keeps topology (χ, closedness) and grows #V by #E.
#include <gtest/gtest.h>

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

TEST(LoopSubdivision, ConvergesTowardSmoothSurfaceAndPlaneStaysPlanar) {
  // A planar grid stays planar; the icosphere's subdivided area stays within the sphere's area.
  TriangleMesh plane = loop_subdivide(test::grid(4));
  EXPECT_LT(plane.V.col(2).cwiseAbs().maxCoeff(), 1e-15);
  TriangleMesh sphere = loop_subdivide_to(test::icosphere(1), 2000);
  EXPECT_GE(sphere.V.rows(), 2000);
  EXPECT_LT(surface_area(sphere.V, sphere.F), 4 * M_PI);
  EXPECT_GT(surface_area(sphere.V, sphere.F), 0.8 * 4 * M_PI);  // Loop shrinks a coarse sphere a little
}
