// The scenes of thin_scenes.h.
#include "thin_scenes.h"

#include <array>
#include <random>
#include <vector>

namespace heatcvt::test {

namespace {

// `count` points area-uniform on the faces of the box [lo, hi] (all six, or without the bottom).
void sample_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int count, bool bottom, std::mt19937& rng,
                std::vector<Eigen::Vector3d>& out) {
  const Eigen::Vector3d size = hi - lo;
  std::vector<std::array<int, 2>> faces;  // (axis, side)
  std::vector<double> area;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      if (!bottom && axis == 2 && side == 0) continue;
      faces.push_back({axis, side});
      area.push_back(size.prod() / size[axis]);
    }
  std::discrete_distribution<int> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < count; ++i) {
    const auto [axis, side] = faces[static_cast<size_t>(pick(rng))];
    Eigen::Vector3d p(u(rng), u(rng), u(rng));
    p[axis] = side;
    out.push_back(lo + p.cwiseProduct(size));
  }
}

Eigen::MatrixX3d with_noise(const std::vector<Eigen::Vector3d>& points, double sigma, std::mt19937& rng) {
  std::normal_distribution<double> noise(0, sigma);
  Eigen::MatrixX3d P(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i)
    P.row(static_cast<Eigen::Index>(i)) = (points[i] + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).transpose();
  return P;
}

}  // namespace

Eigen::MatrixX3d thin_plate(double t, int count, double sigma, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Vector3d> points;
  sample_box(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, t), count, true, rng, points);
  return with_noise(points, sigma, rng);
}

Eigen::MatrixX3d wall_on_floor(double t, int count, double sigma, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<Eigen::Vector3d> points;
  const double floor_area = 9.0, wall_area = 2 * (2 * 0.8 + t * 0.8) + 2 * t;
  const int on_floor = static_cast<int>(count * floor_area / (floor_area + wall_area));
  while (static_cast<int>(points.size()) < on_floor) {
    const Eigen::Vector3d p(u(rng), u(rng), 0);
    if (std::abs(p.x()) >= 1 || std::abs(p.y()) >= t / 2) points.push_back(p);
  }
  sample_box(Eigen::Vector3d(-1, -t / 2, 0), Eigen::Vector3d(1, t / 2, 0.8), count - on_floor, false, rng, points);
  return with_noise(points, sigma, rng);
}

Eigen::MatrixX3d offset_scans(double offset, int count, double sigma, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) points.emplace_back(0.7 * u(rng), u(rng), 0.0);
  for (int i = 0; i < count; ++i) points.emplace_back(0.3 + 0.7 * u(rng), u(rng), offset);
  return with_noise(points, sigma, rng);
}

}  // namespace heatcvt::test
