#pragma once
/// \file grid_cell.h
/// Cells of a uniform grid over 3D space, as hash keys: the voxels of the streamed summary, the
/// neighbourhoods of the noise estimate, the boxes of the incremental crossing check.
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace heatcvt {

/// Integer coordinates of a grid cell.
using GridCell = std::array<std::int64_t, 3>;

/// Hash of a grid cell: multiplicative mixing of the three integers (large odd constants, then
/// xor-shift).
struct GridCellHash {
  std::size_t operator()(const GridCell& c) const noexcept {
    std::uint64_t h = static_cast<std::uint64_t>(c[0]) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(c[1]) * 0xC2B2AE3D27D4EB4FULL + (h >> 29);
    h ^= static_cast<std::uint64_t>(c[2]) * 0x165667B19E3779F9ULL + (h >> 32);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

/// The cell of side `size` holding x (cells are [k size, (k + 1) size) on each axis). The caller
/// keeps x / size within the range of a 64-bit integer.
inline GridCell grid_cell(const Eigen::Vector3d& x, double size) {
  return {static_cast<std::int64_t>(std::floor(x.x() / size)), static_cast<std::int64_t>(std::floor(x.y() / size)),
          static_cast<std::int64_t>(std::floor(x.z() / size))};
}

}  // namespace heatcvt
