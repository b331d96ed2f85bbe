#pragma once
// A virtual depth camera for benchmarks and tests: partial views of a mesh (scaled to a bounding
// diagonal of 1 m) with a floor under it, taken by a pinhole camera of W × H pixels whose depth
// gets a sensor model:
//   rgbd:   structured-light / time-of-flight camera: depth noise σ(z) = rgbd_sigma · z², depth
//           quantised to disparity steps Δz(z) = rgbd_step · z², and flying pixels: where
//           horizontal neighbours differ by more than flying_jump, flying_share of those pixels
//           get a depth between the two;
//   stereo: stereo_sigma_factor times the noise, no quantisation, and speckle: speckle_share of
//           the pixels off by up to 3 σ more.
// The frame is organised (row-major, NaN where the ray hits nothing), as depth drivers save it.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "heatcvt/mesh.h"

namespace heatcvt::test {

/// The camera and sensor constants of the simulation (scene in metres, diagonal 1).
struct ScanOptions {
  int width = 320, height = 240;       ///< pixels
  double fov_deg = 50;                 ///< horizontal field of view
  double distance = 1.3;               ///< camera to object centre
  double rgbd_sigma = 0.0015;          ///< σ(z) = rgbd_sigma · z² (m)
  double rgbd_step = 0.0025;           ///< quantisation step Δz(z) = rgbd_step · z² (m)
  double flying_jump = 0.05;           ///< neighbour depth jump (m) that makes flying pixels
  double flying_share = 0.5;           ///< share of the pixels at a jump that fly
  double stereo_sigma_factor = 2.0;    ///< stereo σ over the rgbd σ
  double speckle_share = 0.01;         ///< stereo pixels off by up to 3 σ more
};

/// Where the camera stands (azimuth and elevation around the object's centre, z up) and whether
/// the scene has a floor.
struct View {
  double azimuth_deg, elevation_deg;
  bool floor;
};

/// `m` scaled to bounding diagonal 1 and centred at the origin.
TriangleMesh normalised(const TriangleMesh& m);

/// The (normalised) mesh with a floor quad under it (z = min z, 1.6 diagonals wide) when `floor`.
TriangleMesh scene_mesh(const TriangleMesh& m, bool floor);

/// One organised frame of the scene.
struct DepthFrame {
  int width = 0, height = 0;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();  ///< the camera position
  Eigen::MatrixX3d P;                             ///< width·height rows, NaN where nothing was hit
};

/// The frame of `scene` seen from `view` with the rgbd or stereo sensor model; `seed` drives the
/// noise (std::mt19937).
DepthFrame virtual_scan(const TriangleMesh& scene, const View& view, bool stereo, const ScanOptions& options,
                        std::uint32_t seed);

/// A rotating multi-beam lidar (Velodyne, Ouster, Hesai): `beams` beams at elevations spread evenly
/// over [min_elevation_deg, max_elevation_deg], each returning the first hit every
/// azimuth_step_deg of a full turn, up to max_range, with Gaussian range noise. Its points lie in
/// rings (on a floor, circles whose spacing grows with the square of the range) and, on walls,
/// in rows: dense along the ring, sparse across.
struct LidarOptions {
  int beams = 32;
  double min_elevation_deg = -25, max_elevation_deg = -2;
  double azimuth_step_deg = 0.2;
  double max_range = 40;
  double range_sigma = 0.01;               ///< m
  Eigen::Vector3d origin{0.0, 0.0, 1.8};   ///< the sensor, 1.8 m above the floor z = 0
};

/// The returns of one turn of the lidar in `scene` (metres); `seed` drives the noise.
Eigen::MatrixX3d lidar_scan(const TriangleMesh& scene, const LidarOptions& options, std::uint32_t seed);

/// Scenes for the lidar, z up, the floor at z = 0 (80 m square) around the sensor at the origin:
/// "floor" (the floor alone), "yard" (a box 2 × 2 × 1.5 m at x = 5 and a post 0.6 m in radius,
/// 2 m high, at (−3, 3)), "street" (two house fronts 5 m high along y = ±6 from x = −30 to 30).
/// \throw std::invalid_argument for another name.
TriangleMesh lidar_scene(const std::string& name);

/// Writes the frame as an organised ASCII PCD ("nan" where there is no return) with the camera
/// position as its VIEWPOINT. \throw std::runtime_error when the file cannot be written.
void write_organised_pcd(const std::string& path, const DepthFrame& frame);

}  // namespace heatcvt::test
