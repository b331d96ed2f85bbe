#pragma once
/// \file scan_merge.h
/// Several scans of one scene as one cloud: rigid poses read from files (a 4×4 or 3×4 matrix per
/// scan, or a Stanford-style `.conf` listing every scan with a translation and a quaternion),
/// applied to each scan, and the scans concatenated. Overlapping scans are merged into one surface
/// by the reconstruction itself (its voxel subset and local surface fits average the layers).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "heatcvt/cloud_io.h"

namespace heatcvt {

/// One scan to read: its file and the rigid transform x ↦ R x + t into the common frame.
struct ScanInput {
  std::string path;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

/// Largest deviation of a pose's linear part from a rotation (|RᵀR − I| and |det R − 1|) that is
/// still accepted as rigid: poses are usually written with 6–9 significant digits.
constexpr double kPoseRigidityTolerance = 1e-4;

/// Reads a pose file: 16 numbers (a 4×4 matrix, row by row, last row 0 0 0 1) or 12 numbers (the
/// top 3×4 block), separated by white space; '#' starts a comment. The matrix must be finite and
/// rigid (a rotation and a translation: no scale, shear or reflection, see kPoseRigidityTolerance);
/// the rotation is re-orthonormalised.
/// \throw IOError "<path>: <problem>" for a missing, unreadable or malformed file;
///        InvalidInputError "<path>: <problem>" for a non-finite or non-rigid matrix.
Eigen::Isometry3d read_pose_file(const std::string& path);

/// Reads a Stanford `.conf` file (the format of the Stanford 3D Scanning Repository): lines
/// `bmesh FILE tx ty tz qx qy qz qw` (or `mesh ...`) give each scan's file, relative to the .conf's
/// folder unless absolute, with translation t and unit quaternion q (w last): x ↦ R(q) x + t.
/// `camera` lines and '#' comments are ignored. Every listed file must exist.
/// \throw IOError for a missing/malformed .conf or a listed file that does not exist;
///        InvalidInputError for a non-finite value or a quaternion far from unit length.
std::vector<ScanInput> read_stanford_conf(const std::string& path);

/// Applies `pose` to the cloud in place: positions x ↦ R x + t, normals n ↦ R n.
void transform_cloud(PointCloud& cloud, const Eigen::Isometry3d& pose);

/// Reads every scan (read_cloud), applies its pose and concatenates them in order. The result has
/// normals (colours) only if every scan has them. Reports are added up into `report` if given
/// (format of the first scan).
/// \throw as read_cloud; InvalidInputError if `scans` is empty.
PointCloud read_scans(const std::vector<ScanInput>& scans, CloudReadReport* report = nullptr,
                      const CloudReadOptions& options = {});

}  // namespace heatcvt
