// Stray points (stray_points.h): the rule on clouds built in code (isolated points and small
// groups go; a wire, a scan's border and a density step stay), its thread independence, and
// reconstruct_surface() on a scanned square with one return far off.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/stray_points.h"

using namespace heatcvt;

namespace {

// Jittered grid samples of the square [x0, x1] × [0, 1] at z = 0 with the given spacing.
void add_square(std::vector<Eigen::RowVector3d>& out, double x0, double x1, double spacing, std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.3 * spacing, 0.3 * spacing);
  for (double x = x0 + spacing / 2; x < x1; x += spacing)
    for (double y = spacing / 2; y < 1; y += spacing) out.emplace_back(x + jitter(rng), y + jitter(rng), 0.0);
}

Eigen::MatrixX3d to_matrix(const std::vector<Eigen::RowVector3d>& rows) {
  Eigen::MatrixX3d P(rows.size(), 3);
  for (size_t i = 0; i < rows.size(); ++i) P.row(i) = rows[i];
  return P;
}

// The scene of the rule's test: a square sampled at spacing 0.01 on its left half and 0.04
// (16× sparser) on its right half, a wire leaving its left edge, then the stray points: one
// isolated return above the square and a group of 5 far off. Returns the index of the first stray point.
int stray_scene(std::vector<Eigen::RowVector3d>& rows) {
  std::mt19937 rng(5);
  add_square(rows, 0.0, 0.5, 0.01, rng);
  add_square(rows, 0.5, 1.0, 0.04, rng);
  for (int i = 1; i <= 40; ++i) rows.emplace_back(-0.01 * i, 0.5, 0.0);  // a wire, 0.01 apart
  const int first = static_cast<int>(rows.size());
  rows.emplace_back(0.3, 0.6, 0.8);
  for (int i = 0; i < 5; ++i) rows.emplace_back(5.0 + 0.002 * i, 5.0, 5.0 - 0.003 * i);
  return first;
}

}  // namespace

TEST(StrayPoints, IsolatedPointsAndSmallGroupsGoAWireABorderAndADensityStepStay) {
  std::vector<Eigen::RowVector3d> rows;
  const int first = stray_scene(rows);
  const Eigen::MatrixX3d P = to_matrix(rows);
  const std::vector<char> stray = stray_point_mask(P);
  for (int i = 0; i < P.rows(); ++i) EXPECT_EQ(stray[i], i >= first) << "point " << i << " at " << P.row(i);
}

TEST(StrayPoints, TheMaskDoesNotDependOnTheThreadCountAndTheRuleCanBeTurnedOff) {
  std::vector<Eigen::RowVector3d> rows;
  stray_scene(rows);
  const Eigen::MatrixX3d P = to_matrix(rows);
  EXPECT_EQ(stray_point_mask(P, {}, 1), stray_point_mask(P, {}, 2));
  StrayPointOptions off;
  off.ratio = 0;
  const std::vector<char> none = stray_point_mask(P, off);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  StrayPointOptions bad;
  bad.ratio = 0.5;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
  bad = {};
  bad.neighbours = 1;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
}

TEST(StrayPoints, AReturnFarOffDoesNotPullTheMeshOutOfTheScannedSquare) {
  // A scanned unit square plus one return 1,000 units away. Left in, the point Laplacian has
  // triangles from the square's corner to it and the CVT puts sites on them; removed by
  // default, every vertex stays on the square.
  std::vector<Eigen::RowVector3d> rows;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 3000; ++i) rows.emplace_back(u(rng), u(rng), 0.0);
  rows.emplace_back(1000.0, 1000.0, 1000.0);
  const Eigen::MatrixX3d P = to_matrix(rows);
  auto farthest_outside = [](const TriangleMesh& m) {  // largest distance of a vertex from the square
    double d = 0;
    for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
      const Eigen::RowVector3d x = m.V.row(v);
      const Eigen::RowVector3d q(std::clamp(x.x(), 0.0, 1.0), std::clamp(x.y(), 0.0, 1.0), 0.0);
      d = std::max(d, (x - q).norm());
    }
    return d;
  };
  auto uncovered = [](const TriangleMesh& m) {  // largest distance from the square's middle to a vertex
    double d = 0;
    for (double x = 0.15; x <= 0.85; x += 0.05)
      for (double y = 0.15; y <= 0.85; y += 0.05)
        d = std::max(d, (m.V.rowwise() - Eigen::RowVector3d(x, y, 0.0)).rowwise().norm().minCoeff());
    return d;
  };
  ReconstructionOptions opt;
  opt.sites = 200;  // spacing about 0.07
  opt.stray.ratio = 0;
  const ReconstructionResult kept = reconstruct_surface(P, opt);
  // Precondition: left in, the stray point pulls the mesh out of the square or off part of it.
  ASSERT_TRUE(farthest_outside(kept.mesh) > 0.1 || uncovered(kept.mesh) > 0.2)
      << farthest_outside(kept.mesh) << " " << uncovered(kept.mesh);
  opt.stray = {};
  const ReconstructionResult r = reconstruct_surface(P, opt);
  EXPECT_EQ(r.points_stray, 1);
  // On the square to within half a site spacing: border vertices may lie up to a quarter of an
  // edge beyond the scan's averaged edge (AnglePolishOptions::sample_border_overshoot).
  EXPECT_LT(farthest_outside(r.mesh), 0.5 * std::sqrt(1.0 / opt.sites));
  // Removed before the frame is chosen: the same mesh as from the square alone.
  const ReconstructionResult alone = reconstruct_surface(P.topRows(P.rows() - 1), opt);
  EXPECT_EQ(alone.points_stray, 0);
  ASSERT_EQ(r.mesh.V.rows(), alone.mesh.V.rows());
  EXPECT_EQ((r.mesh.V - alone.mesh.V).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(r.mesh.F, alone.mesh.F);
  EXPECT_NEAR(r.mesh.V.rows(), 200, 4);
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
}
