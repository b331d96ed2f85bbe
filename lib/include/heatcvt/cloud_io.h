#pragma once
/// \file cloud_io.h
/// Reading point clouds (PCD via PCL, PLY, XYZ/PWN/TXT text) into double-precision arrays, the
/// standard clean-up (non-finite points dropped, exact duplicates merged) and the recentring /
/// rescaling frame used before any computation on clouds with large coordinate offsets.
#include <Eigen/Core>
#include <string>

namespace heatcvt {

/// A point cloud as plain arrays.
///   P  #P by 3 positions
///   N  #P by 3 normals (not necessarily unit, not necessarily oriented) or empty (0 rows) if none
struct PointCloud {
  Eigen::MatrixX3d P;
  Eigen::MatrixX3d N;
  bool has_normals() const { return N.rows() > 0 && N.rows() == P.rows(); }
};

/// What read_cloud saw and changed.
struct CloudReadReport {
  std::string format;           ///< "pcd-ascii", "pcd-binary", "pcd-binary_compressed", "ply-ascii", ..., "xyz"
  long points_in_file = 0;      ///< including NaN points of organised clouds
  int width = 0, height = 0;    ///< PCD organisation (height > 1: organised); width = points, height = 1 otherwise
  long non_finite_dropped = 0;  ///< points with a NaN/inf coordinate
  long duplicates_merged = 0;   ///< exact positional duplicates removed (first occurrence kept)
  bool has_normals = false;     ///< the result has normals
  bool normals_all_zero = false;///< the file had normal columns but every normal was zero: treated as absent
  long invalid_normals_zeroed = 0; ///< finite points whose normal was NaN/inf; normal set to zero
};

/// Reads a point cloud, format by extension (case-insensitive):
///   .pcd            PCL PCD (ascii, binary, binary_compressed; organised clouds) through
///                   pcl::io::loadPCDFile; fields x,y,z (+ normal_x, normal_y, normal_z) of any numeric type.
///   .ply            vertices of any PLY file (ascii / binary LE / BE), nx ny nz as normals if present;
///                   faces and other elements are ignored.
///   .xyz .pwn .txt  text lines "x y z [nx ny nz ...]"; blank lines and '#' comments skipped, a single
///                   leading count line is accepted; normals only if every line has >= 6 columns.
/// Clean-up (deterministic): drop points with a non-finite coordinate, merge exact duplicates keeping
/// the first occurrence (file order is otherwise preserved), all-zero normals => no normals.
/// Coordinates are read as double (float32 data converted exactly).
/// \throw IOError "<path>: <problem>" for a missing/unreadable/empty file, unknown extension or
///        malformed/truncated content; InvalidInputError "<path>: <problem>" when no finite point remains.
PointCloud read_cloud(const std::string& path, CloudReadReport* report = nullptr);

/// Drops non-finite points and merges exact duplicates in place (the clean-up of read_cloud).
/// Counts are added to `report` if given.
void clean_cloud(PointCloud& cloud, CloudReadReport* report = nullptr);

/// Similarity frame: normalized = (original − centre) / scale.
struct CloudFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double scale = 1.0;
};

/// Frame of a point set: centre = bounding-box centre, scale = bounding-box diagonal
/// (1 if the diagonal is zero). \throw InvalidInputError for an empty or non-finite point set.
CloudFrame bounding_box_frame(const Eigen::MatrixX3d& P);

/// Moves the cloud into its bounding_box_frame (bbox centred at the origin, bbox diagonal 1) and
/// returns the frame. Normals are unchanged (a similarity with positive scale keeps directions).
CloudFrame normalize_cloud(PointCloud& cloud);

/// Applies the frame: V ← (V − centre) / scale (rows are points).
void apply_frame(Eigen::MatrixX3d& V, const CloudFrame& frame);

/// Undoes the frame: V ← V · scale + centre, e.g. to write a mesh built on a normalized cloud
/// back in the original coordinates.
void restore_frame(Eigen::MatrixX3d& V, const CloudFrame& frame);

/// Writes "x y z [nx ny nz]" lines (normals if present), atomically. \throw IOError on failure.
void write_cloud_xyz(const std::string& path, const PointCloud& cloud);

}  // namespace heatcvt
