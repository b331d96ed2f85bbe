#pragma once
// Open surfaces sampled in code, for the tests and benchmarks of the border of open scans: a
// square, a disc, a square with a round hole, a saddle and an open hemisphere.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace heatcvt::test {

/// The names open_shape_samples() knows, in a fixed order.
std::vector<std::string> open_shape_names();

/// `count` points of the named open shape, uniform in its (u, v) parameters (area-uniform on the
/// flat shapes and the hemisphere; the saddle's density varies by its slope), seeded by `seed`:
/// - "square": [0, 1]² at z = 0;
/// - "disc": radius 0.5 at z = 0;
/// - "square_with_hole": the square without the disc of radius 0.2 at its centre;
/// - "saddle": z = x² − y² over [−0.5, 0.5]²;
/// - "hemisphere": the upper half of the unit sphere (its border the equator).
/// \throw std::invalid_argument for another name.
Eigen::MatrixX3d open_shape_samples(const std::string& name, int count, std::uint32_t seed = 1);

/// A jittered n × n grid of points on z = 0 with spacing 1 (each point moved by up to 0.2 by a
/// fixed pattern), and its normals, all +z.
Eigen::MatrixX3d jittered_grid(int n);
Eigen::MatrixX3d up_normals(Eigen::Index count);

}  // namespace heatcvt::test
