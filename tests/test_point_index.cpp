// Nearest-point and radius queries of PointIndex (point_index.h) against brute force, on random
// points built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/point_index.h"

namespace heatcvt {
namespace {

TEST(PointIndex, NearestAndWithinAgreeWithBruteForce) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixX3d P(2000, 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << u(rng), u(rng), u(rng);
  const PointIndex index(P);
  EXPECT_EQ(index.size(), 2000);
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3d x(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < P.rows(); ++i) best = std::min(best, (P.row(i).transpose() - x).norm());
    double d = -1;
    const int row = index.nearest(x, d);
    ASSERT_GE(row, 0);
    EXPECT_DOUBLE_EQ(d, best);
    EXPECT_DOUBLE_EQ((P.row(row).transpose() - x).norm(), best);
    // Every row within the radius is found; anything else found is at most 10⁻⁶ farther.
    const double radius = 0.3;
    const std::vector<int> found = index.within(x, radius);
    std::vector<int> expected;
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if ((P.row(i).transpose() - x).norm() <= radius) expected.push_back(static_cast<int>(i));
    std::vector<int> missing;
    std::set_difference(expected.begin(), expected.end(), found.begin(), found.end(), std::back_inserter(missing));
    EXPECT_TRUE(missing.empty());
    for (int i : found) EXPECT_LE((P.row(i).transpose() - x).norm(), radius * (1 + 2e-6));
  }
}

TEST(PointIndex, EmptySetAndNonFinitePoints) {
  const PointIndex empty(Eigen::MatrixX3d(0, 3));
  double d = 0;
  EXPECT_EQ(empty.nearest(Eigen::Vector3d::Zero(), d), -1);
  EXPECT_TRUE(std::isinf(d));
  EXPECT_TRUE(empty.within(Eigen::Vector3d::Zero(), 1.0).empty());
  Eigen::MatrixX3d bad(2, 3);
  bad << 0, 0, 0, std::nan(""), 0, 0;
  EXPECT_THROW(PointIndex{bad}, InvalidInputError);
}

}  // namespace
}  // namespace heatcvt
