#pragma once
/// \file pcl/impl/heat_cvt_reconstruction.hpp
/// Template bodies of heatcvt::HeatCVTReconstruction (see heat_cvt_reconstruction.h).
#include <limits>
#include <pcl/common/io.h>
#include <pcl/conversions.h>
#include <pcl/point_traits.h>
#include <pcl/console/print.h>
#include <pcl/search/kdtree.h>

#include <exception>
#include <type_traits>

#include "heatcvt/mesh.h"
#include "heatcvt/pcl/heat_cvt_reconstruction.h"
#include "heatcvt/pcl/impl/detail.hpp"

namespace heatcvt {

// The base class's reconstruct(output) has copied the input's header and the input cloud into
// `output`; the cloud is replaced by the mesh vertices (or emptied on failure).
template <typename PointT>
void HeatCVTReconstruction<PointT>::performReconstruction(pcl::PolygonMesh& output) {
  output.polygons.clear();
  output.cloud = pcl::PCLPointCloud2();
  pcl::PointCloud<PointT> points;
  std::vector<pcl::Vertices> polygons;
  if (!run(points, polygons)) return;
  pcl::toPCLPointCloud2(points, output.cloud);
  output.polygons = std::move(polygons);
}

template <typename PointT>
void HeatCVTReconstruction<PointT>::performReconstruction(pcl::PointCloud<PointT>& points,
                                                          std::vector<pcl::Vertices>& polygons) {
  run(points, polygons);
}

template <typename PointT>
bool HeatCVTReconstruction<PointT>::run(pcl::PointCloud<PointT>& points, std::vector<pcl::Vertices>& polygons) {
  // Errors name reconstruct(), the call the user made (the base class calls this through
  // performReconstruction after initCompute()).
  const char* method = "reconstruct";
  points.clear();
  points.width = 0;
  points.height = 1;
  polygons.clear();
  result_ = ReconstructionResult();
  depth_report_ = DepthStepReport();
  if (input_ == no_input_) {
    PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] No input cloud given (setInputCloud).\n", method);
    return false;
  }
  points.header = input_->header;
  if (input_->empty()) {
    PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] The input cloud is empty.\n", method);
    return false;
  }
  bool ok = false;
  try {
    // Gather the indexed points (float → double is exact) and clean them like cloud2mesh.
    const std::size_t g = indices_->size();
    Eigen::MatrixX3d xyz(static_cast<Eigen::Index>(g), 3);
    std::vector<int> cloud_index(g);
    for (std::size_t i = 0; i < g; ++i) {
      const int idx = static_cast<int>((*indices_)[i]);
      if (idx < 0 || static_cast<std::size_t>(idx) >= input_->size()) {
        PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] Index %d is outside the cloud (%zu points).\n", method, idx,
                  static_cast<std::size_t>(input_->size()));
        return false;
      }
      const PointT& p = (*input_)[static_cast<std::size_t>(idx)];
      xyz.row(static_cast<Eigen::Index>(i)) << p.x, p.y, p.z;
      cloud_index[i] = idx;
    }
    // A depth-camera frame: its flying pixels go first (as read_cloud drops them from a PCD frame).
    if (input_->isOrganized() && flying_.enabled()) {
      Eigen::MatrixX3d grid(static_cast<Eigen::Index>(input_->size()), 3);
      for (std::size_t i = 0; i < input_->size(); ++i)
        grid.row(static_cast<Eigen::Index>(i)) << (*input_)[i].x, (*input_)[i].y, (*input_)[i].z;
      const std::vector<char> flying =
          flying_pixel_mask(grid, static_cast<int>(input_->width), static_cast<int>(input_->height),
                            input_->sensor_origin_.template head<3>().template cast<double>(), flying_);
      for (std::size_t i = 0; i < g; ++i)
        if (flying[static_cast<std::size_t>(cloud_index[i])])
          xyz.row(static_cast<Eigen::Index>(i)).setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    const pcl_detail::CleanPoints clean = pcl_detail::clean_points(xyz, cloud_index);
    const Eigen::Index usable = clean.P.rows();
    if (usable == 0) {
      PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] The input cloud is empty (no finite point among %zu indices).\n",
                method, g);
    } else if (options_.sites > usable) {
      PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] Too many sites: %d requested but only %ld usable points.\n",
                method, options_.sites, static_cast<long>(usable));
    } else {
      // Quantised depth refitted in the sensor's frame, as read_cloud() does.
      Eigen::MatrixX3d P = clean.P;
      DepthStepOptions depth = depth_steps_;
      depth.threads = options_.threads;
      depth_report_ = smooth_depth_steps(P, input_->sensor_origin_.template head<3>().template cast<double>(), depth);
      result_ = reconstruct_surface(P, options_, progress_);
      const TriangleMesh& mesh = result_.mesh;
      // Attributes: from the nearest input point (search method; a kd-tree over the indexed input
      // unless the user set one), normals from the mesh.
      if (!tree_) tree_.reset(new pcl::search::KdTree<PointT>(false));
      tree_->setInputCloud(input_, indices_);
      const Eigen::MatrixX3d N = mesh.F.rows() > 0 ? vertex_normals(mesh.V, mesh.F)
                                                   : Eigen::MatrixX3d::Zero(mesh.V.rows(), 3);
      points.resize(static_cast<std::size_t>(mesh.V.rows()));
      pcl::Indices nn(1);
      std::vector<float> nn_d2(1);
      for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
        PointT q;
        q.x = static_cast<float>(mesh.V(v, 0));
        q.y = static_cast<float>(mesh.V(v, 1));
        q.z = static_cast<float>(mesh.V(v, 2));
        PointT out = q;
        if (tree_->nearestKSearch(q, 1, nn, nn_d2) > 0) out = (*input_)[static_cast<std::size_t>(nn[0])];
        out.x = q.x;
        out.y = q.y;
        out.z = q.z;
        if constexpr (pcl::traits::has_normal_v<PointT>) {
          out.normal_x = static_cast<float>(N(v, 0));
          out.normal_y = static_cast<float>(N(v, 1));
          out.normal_z = static_cast<float>(N(v, 2));
        }
        points[static_cast<std::size_t>(v)] = out;
      }
      points.width = static_cast<std::uint32_t>(points.size());
      points.height = 1;
      points.is_dense = true;
      polygons.resize(static_cast<std::size_t>(mesh.F.rows()));
      for (Eigen::Index f = 0; f < mesh.F.rows(); ++f)
        polygons[static_cast<std::size_t>(f)].vertices = {static_cast<pcl::index_t>(mesh.F(f, 0)),
                                                          static_cast<pcl::index_t>(mesh.F(f, 1)),
                                                          static_cast<pcl::index_t>(mesh.F(f, 2))};
      ok = true;
    }
  } catch (const std::exception& e) {
    PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] %s\n", method, e.what());
  } catch (...) {
    PCL_ERROR("[heatcvt::HeatCVTReconstruction::%s] Unknown error.\n", method);
  }
  if (!ok) {
    points.clear();
    points.width = 0;
    points.height = 1;
    polygons.clear();
    result_ = ReconstructionResult();
  }
  return ok;
}

}  // namespace heatcvt
