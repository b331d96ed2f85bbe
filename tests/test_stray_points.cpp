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
  off.sparse_group_fraction = 0;
  off.min_group_points = 0;
  const std::vector<char> none = stray_point_mask(P, off);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  StrayPointOptions bad;
  bad.ratio = 0.5;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
  bad = {};
  bad.neighbours = 1;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
  bad = {};
  bad.sparse_group_fraction = 1.5;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
  bad = {};
  bad.sparse_density_ratio = -0.1;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
  bad = {};
  bad.min_group_points = -1;
  EXPECT_THROW(stray_point_mask(P, bad), InvalidInputError);
}

namespace {

// Samples of the square [x0, x0 + side] × [y0, y0 + side] at height z with the given spacing.
void add_patch(std::vector<Eigen::RowVector3d>& out, double x0, double y0, double z, double side, double spacing,
               std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.3 * spacing, 0.3 * spacing);
  for (double x = spacing / 2; x < side; x += spacing)
    for (double y = spacing / 2; y < side; y += spacing) out.emplace_back(x0 + x + jitter(rng), y0 + y + jitter(rng), z);
}

// Which of the groups [begin[g], begin[g + 1]) of `stray` are wholly marked (1), wholly kept
// (0) or split (-1).
std::vector<int> group_marks(const std::vector<char>& stray, const std::vector<int>& begin) {
  std::vector<int> out;
  for (size_t g = 0; g + 1 < begin.size(); ++g) {
    const auto first = stray.begin() + begin[g], last = stray.begin() + begin[g + 1];
    const auto marked = std::count(first, last, 1);
    out.push_back(marked == last - first ? 1 : (marked == 0 ? 0 : -1));
  }
  return out;
}

}  // namespace

// The group rules on a scene built in code: a unit square at spacing 0.01 (10,000 points) and,
// far from it and from each other: a dense group of 20 points (fewer than a Laplacian
// neighbourhood), a scatter of 64 points over 2 × 2 (0.6 % of the points, 25× sparser), a small
// dense object of 64 points (0.6 %, as dense as the square), and a distant wall sampled 3×
// more sparsely (4 % of the points). The first two go; the object and the wall stay. Alone, the
// dense group is the largest and stays.
TEST(StrayPoints, SmallAndSparseGroupsGoASmallObjectAndASparserWallStay) {
  std::vector<Eigen::RowVector3d> rows;
  std::mt19937 rng(11);
  std::vector<int> begin{0};
  add_patch(rows, 0, 0, 0, 1.0, 0.01, rng);  // the square
  begin.push_back(static_cast<int>(rows.size()));
  add_patch(rows, 5, 5, 5, 0.05, 0.01, rng);  // 5 × 5 = 25 ... keep 20 of them
  rows.resize(begin.back() + 20);
  begin.push_back(static_cast<int>(rows.size()));
  add_patch(rows, -6, 0, 2, 2.0, 0.25, rng);  // the scatter: 8 × 8
  begin.push_back(static_cast<int>(rows.size()));
  add_patch(rows, 0, -4, 1, 0.08, 0.01, rng);  // the small object: 8 × 8
  begin.push_back(static_cast<int>(rows.size()));
  add_patch(rows, 4, -6, -3, 0.6, 0.03, rng);  // the wall: 20 × 20
  begin.push_back(static_cast<int>(rows.size()));
  const Eigen::MatrixX3d P = to_matrix(rows);
  ASSERT_EQ(begin[2] - begin[1], 20);
  ASSERT_EQ(begin[3] - begin[2], 64);
  ASSERT_EQ(begin[4] - begin[3], 64);
  ASSERT_EQ(begin[5] - begin[4], 400);
  EXPECT_EQ(group_marks(stray_point_mask(P, {}, 2), begin), (std::vector<int>{0, 1, 1, 0, 0}));
  // Each group rule finds its own group, and the single-point rule neither.
  StrayPointOptions no_size;
  no_size.min_group_points = 0;
  EXPECT_EQ(group_marks(stray_point_mask(P, no_size, 2), begin), (std::vector<int>{0, 0, 1, 0, 0}));
  StrayPointOptions no_sparse;
  no_sparse.sparse_group_fraction = 0;
  EXPECT_EQ(group_marks(stray_point_mask(P, no_sparse, 2), begin), (std::vector<int>{0, 1, 0, 0, 0}));
  StrayPointOptions single = no_size;
  single.sparse_group_fraction = 0;
  EXPECT_EQ(group_marks(stray_point_mask(P, single, 2), begin), (std::vector<int>{0, 0, 0, 0, 0}));
  EXPECT_EQ(stray_point_mask(P, {}, 1), stray_point_mask(P, {}, 2));
  // The largest group is the rest the others are far from: alone, the small group is kept.
  const std::vector<char> alone = stray_point_mask(P.middleRows(begin[1], 20));
  EXPECT_EQ(std::count(alone.begin(), alone.end(), 1), 0);
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
  // One CVT and mesher run: the retries from other start sites (count_retries) may mend a mesh
  // that covers the square in part, which is not what this test is about.
  ReconstructionOptions once = opt;
  once.count_retries = 0;
  const ReconstructionResult kept = reconstruct_surface(P, once);
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
