// Tests of mesh_dual_surface() (mesher/surface_mesher.h): the post-CVT stages on the dual of a heat
// CVT of a mesh, with the mesh as projector, on shapes built in code.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "heatcvt/cvt.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/surface_mesher.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

// ---------------------------------------------------------------------------------------------

// The post-CVT stages on the dual of a heat CVT of `shape` (its own cotan Laplacian), with the
// shape as projector.
DualSurfaceResult dual_of_cvt(const TriangleMesh& shape, int sites, CvtResult* cvt_out = nullptr) {
  CvtOptions o;
  o.sites = sites;
  o.iterations = 10;
  o.threads = 2;
  const CvtResult cvt = centroidal_voronoi(shape.V, shape.F, cotan_laplacian(shape.V, shape.F), o);
  if (cvt_out) *cvt_out = cvt;
  const MeshSurfaceProjector surface(shape.V, shape.F);
  SurfaceMesherOptions mo;
  mo.threads = 2;
  return mesh_dual_surface(cvt.dual.V, cvt.dual.F, surface, mo);
}

void expect_valid_closed(const DualSurfaceResult& r, int genus, int sites) {
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
  EXPECT_EQ(r.validation.boundary_loops, 0);
  EXPECT_EQ(r.validation.components, 1);
  EXPECT_EQ(r.validation.genus, genus);
  EXPECT_EQ(r.validation.self_intersecting_pairs, 0);
  EXPECT_LE(r.mesh.V.rows(), sites + r.stats.split_edges);
  EXPECT_GE(r.mesh.V.rows(), 0.95 * sites);
  const TriangleQuality q = triangle_quality(r.mesh.V, r.mesh.F);
  EXPECT_GE(q.min_angle_deg, 25.0);       // the polish's sliver threshold
  EXPECT_GE(q.mean_min_angle_deg, 45.0);  // well-shaped on average
  std::vector<std::string> names;
  for (const auto& [name, seconds] : r.stats.stage_seconds) {
    names.push_back(name);
    EXPECT_GE(seconds, 0.0);
  }
  const std::vector<std::string> expected = {"sites", "extraction and holes", "border growth", "untangle", "relaxation polish",
                                             "angle polish", "sliver collapse", "long-edge split", "boundary sliver trim", "sizing", "untangle after sizing", "compact",
                                             "validate"};
  EXPECT_EQ(names, expected);
}

TEST(DualSurface, SphereDualBecomesAValidPolishedSphere) {
  const TriangleMesh s = test::icosphere(4);
  const DualSurfaceResult r = dual_of_cvt(s, 300);
  expect_valid_closed(r, 0, 300);
  for (Eigen::Index v = 0; v < r.mesh.V.rows(); ++v) EXPECT_NEAR(r.mesh.V.row(v).norm(), 1.0, 2e-3);  // on the input
}

TEST(DualSurface, TorusDualKeepsItsGenus) {
  const TriangleMesh t = test::torus(96, 48);
  const DualSurfaceResult r = dual_of_cvt(t, 400);
  expect_valid_closed(r, 1, 400);
}

TEST(DualSurface, RepairsADualWithAFinAndAMissingFace) {
  const TriangleMesh s = test::icosphere(4);
  CvtResult cvt;
  (void)dual_of_cvt(s, 200, &cvt);
  // A fin on the first edge (a third triangle to a far site) and the last triangle left out.
  Eigen::MatrixX3i F = cvt.dual.F.topRows(cvt.dual.F.rows() - 1);
  int opposite = 0;
  for (int v = 1; v < cvt.dual.V.rows(); ++v)
    if ((cvt.dual.V.row(v) + cvt.dual.V.row(F(0, 0))).norm() < (cvt.dual.V.row(opposite) + cvt.dual.V.row(F(0, 0))).norm())
      opposite = v;
  Eigen::MatrixX3i broken(F.rows() + 1, 3);
  broken << F, Eigen::RowVector3i(F(0, 1), F(0, 0), opposite);
  ValidationOptions vo;
  const ValidationReport before = validate_triangle_mesh(cvt.dual.V, broken, vo);
  ASSERT_FALSE(before.ok());
  const MeshSurfaceProjector surface(s.V, s.F);
  const DualSurfaceResult r = mesh_dual_surface(cvt.dual.V, broken, surface);
  expect_valid_closed(r, 0, 200);
}

// A cancellation query (SurfaceMesherOptions::cancelled) is asked after every stage and before
// each of the sizing's steps. One that never fires leaves the result as it is without one; one
// that fires at its k-th call stops the stages there with StagesCancelled, which is no Error.
TEST(DualSurface, StopsWithStagesCancelledWhenTheQueryFires) {
  const TriangleMesh s = test::icosphere(4);
  CvtResult cvt;
  (void)dual_of_cvt(s, 300, &cvt);
  const MeshSurfaceProjector surface(s.V, s.F);
  SurfaceMesherOptions mo;
  mo.threads = 2;
  mo.sizing.target_vertices = 400;  // so that the sizing remeshes
  const DualSurfaceResult plain = mesh_dual_surface(cvt.dual.V, cvt.dual.F, surface, mo);
  int asked = 0;
  mo.cancelled = [&] {
    ++asked;
    return false;
  };
  const DualSurfaceResult queried = mesh_dual_surface(cvt.dual.V, cvt.dual.F, surface, mo);
  ASSERT_GT(asked, static_cast<int>(queried.stats.stage_seconds.size())) << "the sizing's steps must ask too";
  EXPECT_TRUE(queried.mesh.V == plain.mesh.V);
  EXPECT_TRUE(queried.mesh.F == plain.mesh.F);
  for (const int fire_at : {1, asked / 2, asked}) {
    int calls = 0;
    mo.cancelled = [&] { return ++calls >= fire_at; };
    try {
      (void)mesh_dual_surface(cvt.dual.V, cvt.dual.F, surface, mo);
      ADD_FAILURE() << "no StagesCancelled at call " << fire_at;
    } catch (const Error&) {
      ADD_FAILURE() << "an Error instead of StagesCancelled at call " << fire_at;
    } catch (const StagesCancelled&) {
    }
    EXPECT_EQ(calls, fire_at);
  }
}

TEST(DualSurface, RejectsFacesOutOfRange) {
  const TriangleMesh s = test::icosphere(2);
  const MeshSurfaceProjector surface(s.V, s.F);
  Eigen::MatrixX3i F(1, 3);
  F << 0, 1, static_cast<int>(s.V.rows());
  EXPECT_THROW(mesh_dual_surface(s.V, F, surface), InvalidInputError);
}

}  // namespace
}  // namespace heatcvt
