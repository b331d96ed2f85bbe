#include "open_shapes.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace heatcvt::test {
namespace {

// Maps (u, v) in [0, 1]² to a point of the named shape; false where (u, v) is not on it.
bool point_of(const std::string& name, double u, double v, Eigen::Vector3d& p) {
  if (name == "square") {
    p = {u, v, 0};
    return true;
  }
  if (name == "disc") {
    p = {u - 0.5, v - 0.5, 0};
    return p.norm() <= 0.5;
  }
  if (name == "square_with_hole") {
    p = {u, v, 0};
    return (p - Eigen::Vector3d(0.5, 0.5, 0)).norm() >= 0.2;
  }
  if (name == "saddle") {
    p = {u - 0.5, v - 0.5, (u - 0.5) * (u - 0.5) - (v - 0.5) * (v - 0.5)};
    return true;
  }
  if (name == "hemisphere") {  // z uniform in [0, 1] and a uniform azimuth: area-uniform
    const double r = std::sqrt(std::max(0.0, 1 - u * u)), phi = 2 * M_PI * v;
    p = {r * std::cos(phi), r * std::sin(phi), u};
    return true;
  }
  throw std::invalid_argument("open_shape_samples: unknown shape " + name);
}

}  // namespace

std::vector<std::string> open_shape_names() { return {"square", "disc", "square_with_hole", "saddle", "hemisphere"}; }

Eigen::MatrixX3d open_shape_samples(const std::string& name, int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  Eigen::MatrixX3d P(count, 3);
  for (int i = 0; i < count;) {
    Eigen::Vector3d p;
    const double u = uni(rng), v = uni(rng);
    if (point_of(name, u, v, p)) P.row(i++) = p.transpose();
  }
  return P;
}

Eigen::MatrixX3d jittered_grid(int n) {
  Eigen::MatrixX3d P(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      P.row(j * n + i) << i + 0.2 * std::sin(7.0 * j + 3.0 * i), j + 0.2 * std::cos(5.0 * i + 2.0 * j), 0;
  return P;
}

Eigen::MatrixX3d up_normals(Eigen::Index count) {
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(count, 3);
  N.col(2).setOnes();
  return N;
}

}  // namespace heatcvt::test
