#pragma once
/// \file point_index.h
/// Nearest-point queries on a fixed set of points: one kd-tree (FLANN) built once and searched
/// exactly, for the repeated single queries of the mesher (is the surface sampled here?).
#include <Eigen/Core>
#include <memory>
#include <vector>

namespace heatcvt {

/// Exact nearest point of a fixed point set. Safe for concurrent queries.
class PointIndex {
 public:
  /// Indexes the rows of P (copied). An empty P gives an index whose queries find nothing.
  /// \throw InvalidInputError if a coordinate is NaN or infinite.
  explicit PointIndex(const Eigen::MatrixX3d& P);
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;
  /// A row of P nearest x (−1 when P is empty), and its exact distance to x in `distance`
  /// (infinity when P is empty).
  int nearest(const Eigen::Vector3d& x, double& distance) const;
  /// The rows of P within `radius` of x, ascending. The search compares squared distances in
  /// single precision, on a radius enlarged by a relative 10⁻⁶: rows that much farther may be
  /// included, none within `radius` is missed.
  std::vector<int> within(const Eigen::Vector3d& x, double radius) const;
  Eigen::Index size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace heatcvt
