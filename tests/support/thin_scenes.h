#pragma once
// Scenes with two faces closer than a site spacing, sampled in code, for the tests and the
// benchmark of thin parts (bench_thin_parts): a closed plate, a wall standing on a floor, and
// two scans of one plane misregistered across their overlap.
#include <Eigen/Core>
#include <cstdint>

namespace heatcvt::test {

/// `count` points, area-uniform on the six faces of the box [0, 1] × [0, 1] × [0, t], with
/// Gaussian noise σ = `sigma` on every coordinate.
Eigen::MatrixX3d thin_plate(double t, int count, double sigma, std::uint32_t seed = 10);

/// A floor [−1.5, 1.5]² (z = 0, without the wall's footprint) and a wall [−1, 1] × [−t/2, t/2]
/// × [0, 0.8] standing on it (its four sides and top), about `count` points in all, area-uniform,
/// noise σ.
Eigen::MatrixX3d wall_on_floor(double t, int count, double sigma, std::uint32_t seed = 11);

/// Two scans of the plane z = 0 over [0, 1]²: the first of x < 0.7, the second of x > 0.3 moved
/// by `offset` along z (a registration error), `count` points each, noise σ.
Eigen::MatrixX3d offset_scans(double offset, int count, double sigma, std::uint32_t seed = 20);

}  // namespace heatcvt::test
