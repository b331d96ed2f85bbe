// The Morton order of spatial_order.h: a deterministic permutation that keeps grid neighbours
// close in rank, on grids and points built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "heatcvt/spatial_order.h"

namespace heatcvt {
namespace {

// A 64 x 64 planar grid (tilted out of the coordinate planes), rows shuffled; grid[i][j] = row.
struct ShuffledGrid {
  static constexpr int kSide = 64;
  Eigen::MatrixX3d P;
  std::vector<int> row_of;  // i * kSide + j -> row of P
};

ShuffledGrid shuffled_grid(unsigned seed) {
  ShuffledGrid g;
  const int n = ShuffledGrid::kSide * ShuffledGrid::kSide;
  g.row_of.resize(n);
  std::iota(g.row_of.begin(), g.row_of.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(g.row_of.begin(), g.row_of.end(), rng);
  g.P.resize(n, 3);
  for (int i = 0; i < ShuffledGrid::kSide; ++i)
    for (int j = 0; j < ShuffledGrid::kSide; ++j)
      g.P.row(g.row_of[i * ShuffledGrid::kSide + j]) << 10.0 + i, 5.0 + 0.5 * j, 0.25 * i + 0.75 * j;
  return g;
}

TEST(SpatialOrder, IsADeterministicPermutation) {
  const ShuffledGrid g = shuffled_grid(3);
  const std::vector<int> order = morton_order(g.P);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> identity(g.P.rows());
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(sorted, identity);
  EXPECT_EQ(morton_order(g.P), order);
  EXPECT_TRUE(morton_order(Eigen::MatrixX3d(0, 3)).empty());
}

// Grid neighbours (4-neighbourhood) get nearby ranks: the median rank gap of a neighbour pair is
// at most 4 and three pairs in four are within 16 ranks. In the shuffled input order the median
// gap is about n / 3 and under 1 % of the pairs are within 16 (asserted as the precondition).
TEST(SpatialOrder, GridNeighboursGetNearbyRanks) {
  const ShuffledGrid g = shuffled_grid(5);
  const int side = ShuffledGrid::kSide;
  auto gaps = [&](const std::vector<int>& rank) {
    std::vector<int> gap;
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        const int r = rank[g.row_of[i * side + j]];
        if (i + 1 < side) gap.push_back(std::abs(r - rank[g.row_of[(i + 1) * side + j]]));
        if (j + 1 < side) gap.push_back(std::abs(r - rank[g.row_of[i * side + j + 1]]));
      }
    std::sort(gap.begin(), gap.end());
    return gap;
  };
  auto within16 = [](const std::vector<int>& gap) {
    return static_cast<double>(std::count_if(gap.begin(), gap.end(), [](int x) { return x <= 16; })) / gap.size();
  };
  std::vector<int> input_rank(g.P.rows());
  std::iota(input_rank.begin(), input_rank.end(), 0);
  const std::vector<int> before = gaps(input_rank);
  ASSERT_LT(within16(before), 0.01);
  ASSERT_GT(before[before.size() / 2], 16);

  const std::vector<int> order = morton_order(g.P);
  std::vector<int> rank(order.size());
  for (size_t r = 0; r < order.size(); ++r) rank[order[r]] = static_cast<int>(r);
  const std::vector<int> after = gaps(rank);
  EXPECT_LE(after[after.size() / 2], 4);
  EXPECT_GE(within16(after), 0.75);
}

// A translation and a scale by a power of two (exact in floating point) do not change the order:
// the code is taken in the bounding cube. Rows with a NaN or infinite coordinate go last, in row
// order.
TEST(SpatialOrder, InvariantToFrameAndNonFiniteRowsLast) {
  const ShuffledGrid g = shuffled_grid(7);
  const Eigen::MatrixX3d moved = (g.P * 1024.0).rowwise() + Eigen::RowVector3d(524288.0, -1048576.0, 64.0);
  EXPECT_EQ(morton_order(moved), morton_order(g.P));
  Eigen::MatrixX3d Q = g.P;
  Q(10, 1) = std::numeric_limits<double>::quiet_NaN();
  Q(3, 2) = std::numeric_limits<double>::infinity();
  const std::vector<int> order = morton_order(Q);
  ASSERT_EQ(order.size(), static_cast<size_t>(Q.rows()));
  EXPECT_EQ(order[order.size() - 2], 3);
  EXPECT_EQ(order.back(), 10);
}

}  // namespace
}  // namespace heatcvt
