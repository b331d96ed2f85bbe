#pragma once
/// \file spatial_order.h
/// A spatially coherent order of points (Morton / Z-order): points close in space get close
/// indices, so loops that visit each item's neighbours (the CVT's cells, the mesher's rings) read
/// memory that is close together instead of jumping across the whole array.
#include <Eigen/Core>
#include <vector>

namespace heatcvt {

/// The permutation that sorts the rows of P by the Morton code of their position quantised to
/// 2²¹ steps per axis of P's bounding cube (ties by row index, so the order is deterministic):
/// order[r] = the row placed at rank r. Non-finite rows are placed last, in row order.
std::vector<int> morton_order(const Eigen::MatrixX3d& P);

}  // namespace heatcvt
