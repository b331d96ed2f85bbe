#include "heatcvt/spatial_order.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace heatcvt {

namespace {

// The 21 low bits of x spread to every third bit of a 63-bit word.
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffffULL;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::vector<int> morton_order(const Eigen::MatrixX3d& P) {
  const int n = static_cast<int>(P.rows());
  constexpr double kSteps = 2097151.0;  // 2^21 - 1
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (int i = 0; i < n; ++i)
    if (P.row(i).allFinite()) {
      lo = lo.cwiseMin(P.row(i).transpose());
      hi = hi.cwiseMax(P.row(i).transpose());
    }
  const double extent = (hi - lo).maxCoeff();
  const double scale = extent > 0 ? kSteps / extent : 0.0;
  std::vector<std::pair<std::uint64_t, int>> key(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (!P.row(i).allFinite()) {
      key[i] = {~std::uint64_t{0}, i};
      continue;
    }
    std::uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double q = std::clamp((P(i, a) - lo[a]) * scale, 0.0, kSteps);
      code |= spread_bits(static_cast<std::uint64_t>(q)) << a;
    }
    key[i] = {code, i};
  }
  std::sort(key.begin(), key.end());
  std::vector<int> order(static_cast<size_t>(n));
  for (int r = 0; r < n; ++r) order[r] = key[r].second;
  return order;
}

}  // namespace heatcvt
