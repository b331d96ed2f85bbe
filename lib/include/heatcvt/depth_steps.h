#pragma once
/// \file depth_steps.h
/// Quantised depth of depth cameras. Structured-light and stereo cameras (Kinect, RealSense and
/// most RGB-D sensors) measure disparity in fixed steps, so the depth coordinate of a frame takes
/// only a few hundred distinct values, spaced by a step that grows with the square of the range
/// (about 1 cm at 2 m and 10-20 cm at 6 m for a Kinect). A surface seen at an angle comes out as a
/// staircase of terraces, each a strip of points at one depth. Where a step is a fair fraction of
/// the site spacing, the point Laplacian's neighbourhoods follow the terraces, the cells follow
/// them too, and the dual leaves the far part of a scene out.
///
/// Detection (depth_steps_of()): the coordinate axis with the fewest distinct values holds at most
/// max_distinct_fraction of the point count as distinct values, and every point lies in front of
/// the sensor along that axis, within max_view_angle_deg of it, spanning min_view_extent_deg, with
/// steps of at least min_relative_step of the depth. The cloud is then a depth frame in its own
/// sensor frame. A cloud in a world frame (a registered or merged scan, a lidar tile whose
/// coordinates are rounded or held in float far from the origin) fails one of these and is left as
/// it is.
///
/// Smoothing (smooth_depth_steps()): a pinhole camera maps a plane to an inverse depth that is
/// linear in the image coordinates (u, v) = (x / z, y / z). Each point's inverse depth is
/// refitted as such a linear function over its nearest points in the image, weighted by a
/// Gaussian of the image distance. The window grows until it spans min_levels depth levels among
/// the points within window_steps steps of the point's depth (the same surface). The fit is
/// repeated once without the points more than inlier_steps off the first fit (the other side of
/// a depth edge). The point then moves along its ray from the sensor to the fitted depth, by at
/// most max_move_steps steps. A plane comes out exactly, and a curved surface moves by at most
/// a step, so the rounding of the depth is undone and nothing else changes.
#include <Eigen/Core>
#include <cstdint>

namespace heatcvt {

/// Options of depth_steps_of() and smooth_depth_steps().
struct DepthStepOptions {
  /// The depth is quantised where its distinct values number at most this fraction of the points.
  /// The depth frames of ../shared/data/clouds give 0.0003-0.013, and scans with continuous
  /// depth give 0.1-1. 0 turns the smoothing off. Default 0.05.
  double max_distinct_fraction = 0.05;
  /// Fewer points than this are not judged (too few to tell levels from values). Default 1000.
  int min_points = 1000;
  /// Every point must lie within this angle of the depth axis, seen from the sensor: a camera's
  /// field of view. Default 75°.
  double max_view_angle_deg = 75;
  /// ... and the cloud must span at least this angle in one image direction: a world frame with a
  /// large offset (UTM coordinates, millions of metres from the origin) looks like a view from
  /// afar, but spans a few thousandths of a degree. Default 1°.
  double min_view_extent_deg = 1;
  /// ... and the median step must be at least this fraction of the median depth: a camera's steps
  /// are 10⁻⁴-10⁻² of the depth, while the float precision of far coordinates (0.5 m at 5·10⁶ m)
  /// or their rounding in a world frame is far less. Default 10⁻⁵.
  double min_relative_step = 1e-5;
  /// The fit window: the nearest points in the image, from start_neighbours and doubling up to
  /// max_neighbours, until the points on the same surface span min_levels levels and number at
  /// least min_fit_points. Defaults 16, 128, 3 and 12.
  int start_neighbours = 16;
  int max_neighbours = 128;
  int min_levels = 3;
  int min_fit_points = 12;
  /// Points within this many steps of the point's depth lie on its surface. Default 3.
  double window_steps = 3;
  /// The second fit leaves out the points farther than this many steps from the first. Default 1.
  double inlier_steps = 1;
  /// A point moves by at most this many steps along its ray. Default 1: rounding puts the true
  /// depth within half a step, and a step more leaves room for sensors that truncate.
  double max_move_steps = 1;
  int threads = 0;  ///< 0 = all cores; the result does not depend on it. Default 0.
  bool enabled() const { return max_distinct_fraction > 0; }
};

/// \throw InvalidInputError where an option is out of its range (fractions in [0, 1], an angle in
/// (0, 90), counts ≥ 3 with start_neighbours ≤ max_neighbours ≤ 1024, steps > 0).
void check_depth_step_options(const DepthStepOptions& options);

/// What depth_steps_of() found and smooth_depth_steps() did.
struct DepthStepReport {
  bool quantised = false;       ///< the cloud is a depth frame with quantised depth (file comment)
  int axis = -1;                ///< the depth axis (0, 1, 2 for x, y, z); -1 where none
  std::int64_t levels = 0;      ///< distinct values of the depth coordinate
  double distinct_fraction = 1; ///< levels over points
  double median_step = 0;       ///< median over the points of their level's step, input units
  std::int64_t points_moved = 0;  ///< points whose depth was refitted
  double mean_move_steps = 0;   ///< their mean move, in their level's steps
  double seconds = 0;           ///< time of the detection and the refit
};

/// Detection alone (the file comment): whether the rows of P (finite), seen from `sensor`, are a
/// depth frame with quantised depth, and along which axis. No point is moved.
DepthStepReport depth_steps_of(const Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor,
                               const DepthStepOptions& options = {});

/// Where depth_steps_of() finds quantised depth, moves each point of P along its ray from
/// `sensor` to its refitted depth (the file comment). Points whose window is too small or
/// degenerate (a strip one pixel wide, a lone point) stay where they are.
/// \throw InvalidInputError on bad options or a non-finite coordinate.
DepthStepReport smooth_depth_steps(Eigen::MatrixX3d& P, const Eigen::Vector3d& sensor,
                                   const DepthStepOptions& options = {});

}  // namespace heatcvt
