// weld_coincident_borders() (weld.h): a triangle soup comes back as the closed surface it was cut
// from; sheets that would share an edge three times, and vertices off the border, are left apart.
#include <gtest/gtest.h>

#include "heatcvt/mesh.h"
#include "heatcvt/shapes.h"
#include "heatcvt/weld.h"
#include "triangle_soup.h"

using namespace heatcvt;

namespace {

MeshTopology topology(const TriangleMesh& m) { return mesh_topology(m.F, static_cast<int>(m.V.rows())); }

}  // namespace

TEST(Weld, ATriangleSoupOfASphereIsTheClosedSphereAgain) {
  const TriangleMesh sphere = random_sphere_mesh(400, 3);
  TriangleMesh soup = test::triangle_soup(sphere);
  const MeshTopology before = topology(soup);
  ASSERT_EQ(before.components, sphere.F.rows()) << "precondition: one piece per face";
  const WeldStats w = weld_coincident_borders(soup);
  EXPECT_EQ(w.refused, 0);
  EXPECT_EQ(w.welded, 3 * sphere.F.rows() - sphere.V.rows());
  EXPECT_EQ(soup.V.rows(), sphere.V.rows());
  const MeshTopology t = topology(soup);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.euler_characteristic(), 2);
  // Same faces on the same positions, in the same corner order.
  for (Eigen::Index f = 0; f < sphere.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(soup.V.row(soup.F(f, k)), sphere.V.row(sphere.F(f, k)));
}

TEST(Weld, AMeshWithoutCoincidentBorderVerticesIsUnchanged) {
  const TriangleMesh sphere = random_sphere_mesh(200, 5);
  TriangleMesh same = sphere;
  const WeldStats w = weld_coincident_borders(same);
  EXPECT_EQ(w.welded, 0);
  EXPECT_EQ(w.refused, 0);
  EXPECT_EQ(same.V, sphere.V);
  EXPECT_EQ(same.F, sphere.F);
  // An interior vertex with a twin at its position (unreferenced) is not a border: nothing welds.
  TriangleMesh twin = sphere;
  twin.V.conservativeResize(twin.V.rows() + 1, 3);
  twin.V.row(twin.V.rows() - 1) = twin.V.row(0);
  EXPECT_EQ(weld_coincident_borders(twin).welded, 0);
  EXPECT_EQ(twin.V.rows(), sphere.V.rows() + 1);
}

TEST(Weld, ThreeSheetsOnOneEdgeAreLeftApart) {
  // Three triangles on the edge (0,0,0)-(1,0,0), each with its own vertices: welding would give
  // that edge three faces.
  TriangleMesh book;
  book.V.resize(9, 3);
  book.F.resize(3, 3);
  const double tips[3][3] = {{0.5, 1, 0}, {0.5, -0.5, 0.8}, {0.5, -0.5, -0.8}};
  for (int p = 0; p < 3; ++p) {
    book.V.row(3 * p) << 0, 0, 0;
    book.V.row(3 * p + 1) << 1, 0, 0;
    book.V.row(3 * p + 2) << tips[p][0], tips[p][1], tips[p][2];
    book.F.row(p) << 3 * p, 3 * p + 1, 3 * p + 2;
  }
  const TriangleMesh original = book;
  const WeldStats w = weld_coincident_borders(book);
  EXPECT_EQ(w.welded, 0);
  EXPECT_EQ(w.refused, 4);  // two of the three copies of each end
  EXPECT_EQ(w.bad_edges, 1);
  EXPECT_EQ(book.V, original.V);
  EXPECT_EQ(book.F, original.F);
}
