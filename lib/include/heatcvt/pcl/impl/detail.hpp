#pragma once
/// \file pcl/impl/detail.hpp
/// Non-template helpers of the PCL adapter (compiled once into heatcvt_pcl). Not part of the
/// public API: the class templates in heatcvt/pcl/*.h call them after copying a PCL cloud into
/// plain arrays. No PCL types appear here.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace heatcvt {
namespace pcl_detail {

/// The points of an (indexed) PCL cloud as doubles, after the clean-up of heatcvt::clean_cloud()
/// (cloud_io.h): non-finite points dropped, exact duplicates merged keeping the first occurrence,
/// order otherwise preserved — exactly what read_cloud() hands to cloud2mesh.
struct CleanPoints {
  Eigen::MatrixX3d P;             ///< #U by 3 usable points
  std::vector<int> source;        ///< #U: cloud index of each usable point
  std::vector<int> representative;///< per gathered point (same order as the input arrays): row of P, −1 if non-finite
};

/// Cleans the gathered points: xyz is #G by 3 (float coordinates converted exactly),
/// cloud_index[g] the index in the PCL cloud of gathered point g.
CleanPoints clean_points(const Eigen::MatrixX3d& xyz, const std::vector<int>& cloud_index);

/// Settings of heat_voronoi_point_labels().
struct SegmentationSettings {
  int sites = 100;
  int iterations = 30;
  int k = 30;
  double time_coefficient = 1.0;
  int threads = 0;
  std::uint32_t seed = 1;
};

/// Result of heat_voronoi_point_labels().
struct SegmentationLabels {
  std::vector<int> labels;          ///< #P: heat Voronoi cell of every point, −1 where no heat arrived
  Eigen::MatrixX3d site_positions;  ///< #sites by 3
  int unreached = 0;                ///< points with label −1
};

/// Heat Voronoi labels of the points P (#P by 3, clean): point Laplacian (k neighbours), then
/// either heat_voronoi() of the given sites (rows of P; non-empty `site_rows`) or, if
/// `site_rows` is empty, centroidal_voronoi() with settings.sites sites; the label of point v is
/// the cell of the first refined face of the exact diagram that has v as a corner.
/// \throw heatcvt::InvalidInputError / SolverError from the core.
SegmentationLabels heat_voronoi_point_labels(const Eigen::MatrixX3d& P, const std::vector<int>& site_rows,
                                             const SegmentationSettings& settings);

}  // namespace pcl_detail
}  // namespace heatcvt
