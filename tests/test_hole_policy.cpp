// The hole policy of the surface mesher (mesher/hole_filling.h, cloud2mesh --holes): a closed
// object scanned with a hole is closed with the right genus by `fill`, keeps a boundary loop
// around the hole with `keep`, and a completely scanned object stays closed under every policy.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <string>

#include "heatcvt/cloud_io.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/point_index.h"
#include "heatcvt/reconstruct.h"
#include "test_support.h"
#include "virtual_scanner.h"

using namespace heatcvt;

namespace {

// Points sampled from `mesh`, without those within `radius` of `centre` (the hole).
Eigen::MatrixX3d scan_with_hole(const TriangleMesh& mesh, int count, const Eigen::RowVector3d& centre, double radius) {
  const Eigen::MatrixX3d all = sample_surface(mesh.V, mesh.F, count, 3);
  Eigen::MatrixX3d kept(all.rows(), 3);
  Eigen::Index n = 0;
  for (Eigen::Index i = 0; i < all.rows(); ++i)
    if ((all.row(i) - centre).norm() > radius) kept.row(n++) = all.row(i);
  kept.conservativeResize(n, 3);
  return kept;
}

ReconstructionResult reconstruct_with(const Eigen::MatrixX3d& P, HolePolicy policy, int sites) {
  ReconstructionOptions opt;
  opt.sites = sites;
  opt.mesher.holes.policy = policy;
  return reconstruct_surface(P, opt);
}

}  // namespace

TEST(HolePolicy, SphereWithACapCutOff) {
  // Unit sphere without the cap within 0.63 of the north pole (z > 0.8): a hole of radius 0.6, a
  // loop of more than max_hole_edges (8) edges at 500 sites (edge length ≈ 0.17).
  const Eigen::MatrixX3d P = scan_with_hole(test::icosphere(5), 30000, Eigen::RowVector3d(0, 0, 1), 0.63);
  const ReconstructionResult filled = reconstruct_with(P, HolePolicy::fill, 500);
  EXPECT_EQ(filled.validation.boundary_loops, 0);
  EXPECT_EQ(filled.validation.components, 1);
  EXPECT_EQ(filled.validation.genus, 0);
  EXPECT_EQ(filled.validation.self_intersecting_pairs, 0);
  ASSERT_FALSE(filled.filled_hole_edges.empty());
  int largest = 0;
  for (int e : filled.filled_hole_edges) largest = std::max(largest, e);
  EXPECT_GT(largest, HoleFillingOptions().max_hole_edges);  // the cap's loop, not only extraction holes

  const ReconstructionResult kept = reconstruct_with(P, HolePolicy::keep, 500);
  EXPECT_EQ(kept.validation.boundary_loops, 1);
  EXPECT_EQ(kept.validation.components, 1);
  EXPECT_EQ(kept.validation.self_intersecting_pairs, 0);
  // The loop lies at the cut: no vertex of the kept mesh more than half a site spacing above it
  // (border vertices may lie a little beyond the scan's averaged edge:
  // AnglePolishOptions::sample_border_overshoot).
  const double spacing = mean_edge_length(kept.mesh.V, kept.mesh.F);
  EXPECT_LE(kept.mesh.V.col(2).maxCoeff(), 0.8 + 0.5 * spacing);
}

TEST(HolePolicy, TorusWithAHoleFilledKeepsItsGenus) {
  // Torus R = 1, r = 0.4 with a hole of radius 0.35 on the outer equator.
  const Eigen::MatrixX3d P = scan_with_hole(test::torus(96, 48), 30000, Eigen::RowVector3d(1.4, 0, 0), 0.35);
  const ReconstructionResult filled = reconstruct_with(P, HolePolicy::fill, 800);
  EXPECT_EQ(filled.validation.boundary_loops, 0);
  EXPECT_EQ(filled.validation.components, 1);
  EXPECT_EQ(filled.validation.genus, 1);
  EXPECT_EQ(filled.validation.self_intersecting_pairs, 0);
  const ReconstructionResult kept = reconstruct_with(P, HolePolicy::keep, 800);
  EXPECT_EQ(kept.validation.boundary_loops, 1);
  EXPECT_EQ(kept.validation.components, 1);
}

TEST(HolePolicy, ACompleteScanStaysClosedUnderEveryPolicy) {
  const TriangleMesh sphere = test::icosphere(5);
  const Eigen::MatrixX3d P = sample_surface(sphere.V, sphere.F, 20000, 4);
  for (HolePolicy policy : {HolePolicy::automatic, HolePolicy::fill, HolePolicy::keep}) {
    const ReconstructionResult r = reconstruct_with(P, policy, 400);
    EXPECT_EQ(r.validation.boundary_loops, 0) << static_cast<int>(policy);
    EXPECT_EQ(r.validation.genus, 0) << static_cast<int>(policy);
    EXPECT_EQ(r.mesh.V.rows(), 400) << static_cast<int>(policy);
  }
}

TEST(HolePolicy, FillClosesAVeryNoisySphere) {
  // CGAL's sphere_20k_normal: 21,000 points on the unit sphere with radial noise σ = 0.04, half
  // the site spacing at 2,000 sites. The dual leaves dozens of holes, and the fills of a dozen
  // of them cut through the folds of the noisy surface. `fill` asks for a watertight mesh: every
  // fill stays and is untangled.
  const PointCloud cloud = read_cloud(test::data_path("clouds/sphere_20k_normal.xyz"));
  const ReconstructionResult filled = reconstruct_with(cloud.P, HolePolicy::fill, 2000);
  EXPECT_EQ(filled.validation.boundary_loops, 0);
  EXPECT_EQ(filled.validation.components, 1);
  EXPECT_EQ(filled.validation.genus, 0);
  EXPECT_EQ(filled.validation.self_intersecting_pairs, 0);
}

TEST(HolePolicy, Cloud2MeshOptionAndReport) {
  test::ScratchDir dir("holes_tool");
  const std::string out = dir.path("m.ply"), rep = dir.path("m.json");
  const auto ok = test::run_tool("cloud2mesh", test::data_path("clouds/pcl_milk.pcd") + " -n 300 -q --holes keep -o " + out +
                                                   " --report " + rep);
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  std::ifstream in(rep);
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(json.find("\"filled_hole_edges\""), std::string::npos);
  const auto bad = test::run_tool("cloud2mesh", test::data_path("clouds/pcl_milk.pcd") + " -n 300 -q --holes sometimes -o " +
                                                    dir.path("x.ply"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err.rfind("cloud2mesh: error: ", 0), 0u) << bad.err;
}

TEST(HolePolicy, AutoLeavesTheRimOfOneViewOfABallOpen) {
  // A ball on a floor seen by a depth camera (virtual_scanner.h: rgbd noise, flying pixels
  // dropped by read_cloud's rule). The rim of what is seen of the ball encloses half of it or
  // more; closing it under `auto` would stand for the unseen back with a cap through the ball.
  const TriangleMesh ball = test::normalised(read_mesh(test::data_path("meshes/sphere_cgal.off")));
  const double radius = ball.V.rowwise().norm().mean();
  const test::DepthFrame frame = test::virtual_scan(test::scene_mesh(ball, true), {30, 25, true}, false, {}, 1);
  test::ScratchDir dir("ball_view");
  test::write_organised_pcd(dir.path("frame.pcd"), frame);
  const Eigen::MatrixX3d P = read_cloud(dir.path("frame.pcd")).P;
  // How deep inside the ball a face's centroid reaches, in radii.
  auto inside_the_ball = [&](const TriangleMesh& m) {
    double worst = 0;
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
      const Eigen::RowVector3d g = (m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))) / 3.0;
      worst = std::max(worst, radius - g.norm());
    }
    return worst / radius;
  };
  ReconstructionOptions opt;
  opt.sites = 2000;
  // The precondition: with caps of any size allowed, the rim is closed across the ball.
  opt.mesher.holes.max_cap_area_fraction = std::numeric_limits<double>::infinity();
  EXPECT_GT(inside_the_ball(reconstruct_surface(P, opt).mesh), 0.3);
  opt.mesher.holes.max_cap_area_fraction = HoleFillingOptions().max_cap_area_fraction;
  const ReconstructionResult view = reconstruct_surface(P, opt);
  EXPECT_LT(inside_the_ball(view.mesh), 0.05);
  EXPECT_EQ(view.validation.components, 2);  // the floor and the ball, each open
  EXPECT_EQ(view.validation.boundary_loops, 2);
}

TEST(HolePolicy, AutoLeavesTheShadowOfAnObjectOnTheFloorOpen) {
  // Spot on a floor seen from high above by a stereo camera (virtual_scanner.h). The floor is
  // missing where the cow hides it; beyond that shadow's loop lies the cow's silhouette, seen
  // edge-on. Closing the shadow under `auto` puts a floor under the cow, far from every sample and
  // through the legs that stand on it, which the sizing cannot refine.
  const TriangleMesh spot = test::normalised(read_mesh(test::data_path("meshes/spot.obj")));
  const test::DepthFrame frame = test::virtual_scan(test::scene_mesh(spot, true), {0, 80, true}, true, {}, 53);
  test::ScratchDir dir("shadow_view");
  test::write_organised_pcd(dir.path("frame.pcd"), frame);
  const Eigen::MatrixX3d P = read_cloud(dir.path("frame.pcd")).P;
  const PointIndex samples(P);
  // The largest distance from a face's centroid to the nearest sample, in mean edge lengths; a
  // mesh of the sampled surface stays within kReach of them.
  const double kReach = 2.5;
  auto reach_beyond_samples = [&](const TriangleMesh& m) {
    double worst = 0, edges = 0;
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
      const Eigen::Vector3d g = ((m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))) / 3.0).transpose();
      double d = 0;
      samples.nearest(g, d);
      worst = std::max(worst, d);
      for (int k = 0; k < 3; ++k) edges += (m.V.row(m.F(f, k)) - m.V.row(m.F(f, (k + 1) % 3))).norm();
    }
    return worst / (edges / (3.0 * m.F.rows()));
  };
  ReconstructionOptions opt;
  opt.sites = 2000;
  // The precondition: where any surface beyond the loop counts, the shadow is closed (on the
  // mesh whose border is drawn in by the relaxation: one that follows the samples' border keeps
  // the shadow's loop out of reach of the rule).
  opt.mesher.holes.surrounded_normal_agreement = 0;
  opt.mesher.polish.follow_sample_border = opt.mesher.sizing.follow_sample_border = false;
  EXPECT_GT(reach_beyond_samples(reconstruct_surface(P, opt).mesh), kReach);
  opt.mesher = ReconstructionOptions().mesher;
  const ReconstructionResult view = reconstruct_surface(P, opt);
  EXPECT_LT(reach_beyond_samples(view.mesh), kReach);
  EXPECT_TRUE(view.validation.ok()) << view.validation.summary();
  EXPECT_NEAR(view.mesh.V.rows(), 2000, 40);
}
