#pragma once
/// \file cloud_io.h
/// Reading point clouds (PCD via PCL, PLY, XYZ/PWN/TXT text) into double-precision arrays, the
/// standard clean-up (non-finite points dropped, exact duplicates merged) and the recentring /
/// rescaling of normalize.h applied to a cloud.
#include <Eigen/Core>
#include <string>

#include "heatcvt/depth_steps.h"
#include "heatcvt/flying_pixels.h"
#include "heatcvt/normalize.h"

namespace heatcvt {

/// A point cloud as plain arrays.
///   P  #P by 3 positions
///   N  #P by 3 normals (not necessarily unit, not necessarily oriented) or empty (0 rows) if none
///   C  #P by 3 colours (red, green, blue in [0,1]) or empty (0 rows) if none
struct PointCloud {
  Eigen::MatrixX3d P;
  Eigen::MatrixX3d N;
  Eigen::MatrixX3d C;
  bool has_normals() const { return N.rows() > 0 && N.rows() == P.rows(); }
  bool has_colours() const { return C.rows() > 0 && C.rows() == P.rows(); }
};

/// What read_cloud saw and changed.
struct CloudReadReport {
  std::string format;           ///< "pcd-ascii", "pcd-binary", "pcd-binary_compressed", "ply-ascii", ..., "xyz"
  long points_in_file = 0;      ///< including NaN points of organised clouds
  int width = 0, height = 0;    ///< PCD organisation (height > 1: organised); width = points, height = 1 otherwise
  long non_finite_dropped = 0;  ///< points with a NaN/inf coordinate
  long duplicates_merged = 0;   ///< exact positional duplicates removed (first occurrence kept)
  bool has_normals = false;     ///< the result has normals
  bool has_colours = false;     ///< the result has colours
  bool normals_all_zero = false;///< the file had normal columns but every normal was zero: treated as absent
  long invalid_normals_zeroed = 0; ///< finite points whose normal was NaN/inf; normal set to zero
  long flying_pixels_removed = 0;  ///< pixels of an organised cloud dropped as flying (flying_pixels.h)
  /// The sensor position: a PCD file's VIEWPOINT translation, the origin for other formats.
  Eigen::Vector3d sensor = Eigen::Vector3d::Zero();
  /// The quantised depth found and refitted (depth_steps.h; CloudReadOptions::depth_steps).
  DepthStepReport depth_steps;
};

/// Options of read_cloud.
struct CloudReadOptions {
  /// The flying-pixel rule applied to organised PCD clouds (HEIGHT > 1) before the clean-up,
  /// ranges measured from the file's VIEWPOINT (flying_pixels.h). Default on (3 % of the range);
  /// neighbour_distance_ratio = 0 keeps every pixel.
  FlyingPixelOptions flying_pixels;
  /// The refit of quantised depth (depth_steps.h) applied after the clean-up, rays from
  /// CloudReadReport::sensor: a depth frame in its own sensor frame gets its terraces undone; other
  /// clouds are left as they are. Default on; max_distinct_fraction = 0 turns it off.
  DepthStepOptions depth_steps;
};

/// Reads a point cloud, format by extension (case-insensitive):
///   .pcd            PCL PCD (ascii, binary, binary_compressed; organised clouds) through
///                   pcl::io::loadPCDFile; fields x,y,z (+ normal_x, normal_y, normal_z) of any numeric type.
///   .ply            vertices of any PLY file (ascii / binary LE / BE), nx ny nz as normals if present;
///                   faces and other elements are ignored.
///   .xyz .pwn .txt  text lines "x y z [nx ny nz ...]"; blank lines and '#' comments skipped, a single
///                   leading count line is accepted; normals only if every line has >= 6 columns.
/// Organised PCD clouds first lose their flying pixels (options.flying_pixels).
/// Clean-up (deterministic): drop points with a non-finite coordinate, merge exact duplicates keeping
/// the first occurrence (file order is otherwise preserved), all-zero normals => no normals.
/// Coordinates are read as double (float32 data converted exactly).
/// \throw IOError "<path>: <problem>" for a missing/unreadable/empty file, unknown extension or
///        malformed/truncated content; InvalidInputError "<path>: <problem>" when no finite point remains.
PointCloud read_cloud(const std::string& path, CloudReadReport* report = nullptr, const CloudReadOptions& options = {});

/// Drops non-finite points and merges exact duplicates in place (the clean-up of read_cloud).
/// Counts are added to `report` if given.
void clean_cloud(PointCloud& cloud, CloudReadReport* report = nullptr);

/// The frame of normalize.h under the name used by the cloud functions.
using CloudFrame = NormalizationFrame;

/// Moves the cloud into its bounding_box_frame (normalize.h: bbox centred at the origin, bbox
/// diagonal 1) and returns the frame. Normals are unchanged (a similarity with positive scale
/// keeps directions).
CloudFrame normalize_cloud(PointCloud& cloud);

/// Writes "x y z [nx ny nz]" lines (normals if present), atomically. \throw IOError on failure.
void write_cloud_xyz(const std::string& path, const PointCloud& cloud);

}  // namespace heatcvt
