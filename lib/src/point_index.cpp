// Exact nearest-point queries with one FLANN kd-tree.
#include "heatcvt/point_index.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <limits>
#include <vector>

#include "heatcvt/errors.h"

namespace heatcvt {

struct PointIndex::Impl {
  std::vector<double> data;  // row-major copy the kd-tree refers to
  Eigen::Index rows = 0;
  std::unique_ptr<flann::Index<flann::L2<double>>> index;
};

PointIndex::PointIndex(const Eigen::MatrixX3d& P) : impl_(std::make_unique<Impl>()) {
  if (!P.allFinite()) throw InvalidInputError("PointIndex: a point has a NaN or infinite coordinate");
  impl_->rows = P.rows();
  if (P.rows() == 0) return;
  impl_->data.resize(static_cast<size_t>(P.rows()) * 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) impl_->data[static_cast<size_t>(i) * 3 + c] = P(i, c);
  const flann::Matrix<double> dataset(impl_->data.data(), static_cast<size_t>(P.rows()), 3);
  impl_->index = std::make_unique<flann::Index<flann::L2<double>>>(dataset, flann::KDTreeSingleIndexParams(10));
  impl_->index->buildIndex();
}

PointIndex::~PointIndex() = default;

Eigen::Index PointIndex::size() const { return impl_->rows; }

int PointIndex::nearest(const Eigen::Vector3d& x, double& distance) const {
  distance = std::numeric_limits<double>::infinity();
  if (!impl_->index) return -1;
  double q[3] = {x.x(), x.y(), x.z()};
  int idx = -1;
  double d2 = 0;
  const flann::Matrix<double> query(q, 1, 3);
  flann::Matrix<int> indices(&idx, 1, 1);
  flann::Matrix<double> dists(&d2, 1, 1);
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true);
  params.cores = 1;
  impl_->index->knnSearch(query, indices, dists, 1, params);
  if (idx < 0) return -1;
  distance = std::sqrt(d2);
  return idx;
}

std::vector<int> PointIndex::within(const Eigen::Vector3d& x, double radius) const {
  std::vector<int> out;
  if (!impl_->index || !(radius >= 0)) return out;
  double q[3] = {x.x(), x.y(), x.z()};
  const flann::Matrix<double> query(q, 1, 3);
  std::vector<std::vector<int>> indices;
  std::vector<std::vector<double>> dists;
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0.0f, false);
  params.cores = 1;
  const double r = radius * (1 + 1e-6);
  impl_->index->radiusSearch(query, indices, dists, static_cast<float>(r * r), params);
  out = indices[0];
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace heatcvt
