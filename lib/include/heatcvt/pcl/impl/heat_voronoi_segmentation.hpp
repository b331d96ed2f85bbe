#pragma once
/// \file pcl/impl/heat_voronoi_segmentation.hpp
/// Template bodies of heatcvt::HeatVoronoiSegmentation (see heat_voronoi_segmentation.h).
#include <pcl/console/print.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cstdio>
#include <exception>

#include "heatcvt/pcl/heat_voronoi_segmentation.h"
#include "heatcvt/pcl/impl/detail.hpp"

namespace heatcvt {

template <typename PointT>
void HeatVoronoiSegmentation<PointT>::extract(std::vector<pcl::PointIndices>& clusters) {
  clusters.clear();
  site_positions_.resize(0, 3);
  unreached_ = 0;
  if (!input_) {
    PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] No input cloud given (setInputCloud).\n");
    return;
  }
  if (input_->empty()) {
    PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] The input cloud is empty.\n");
    return;
  }
  if (!initCompute()) {
    PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] Invalid input cloud or indices.\n");
    return;
  }
  try {
    const std::size_t n_cloud = input_->size();
    const std::size_t g = indices_->size();
    Eigen::MatrixX3d xyz(static_cast<Eigen::Index>(g), 3);
    std::vector<int> cloud_index(g);
    for (std::size_t i = 0; i < g; ++i) {
      const auto idx = (*indices_)[i];
      if (idx < 0 || static_cast<std::size_t>(idx) >= n_cloud) {
        PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] Index %ld is outside the cloud (%zu points).\n",
                  static_cast<long>(idx), n_cloud);
        deinitCompute();
        return;
      }
      const PointT& p = (*input_)[static_cast<std::size_t>(idx)];
      xyz.row(static_cast<Eigen::Index>(i)) << p.x, p.y, p.z;
      cloud_index[i] = static_cast<int>(idx);
    }
    const pcl_detail::CleanPoints clean = pcl_detail::clean_points(xyz, cloud_index);
    const long usable = static_cast<long>(clean.P.rows());
    std::vector<int> row_of_cloud(n_cloud, -1);
    for (std::size_t i = 0; i < g; ++i) row_of_cloud[static_cast<std::size_t>(cloud_index[i])] = clean.representative[i];

    const char* fail = nullptr;
    char msg[256];
    std::vector<int> site_rows;
    if (usable == 0) {
      fail = "The input cloud is empty (no finite point among the indices).";
    } else if (!site_indices_.empty()) {
      if (static_cast<long>(site_indices_.size()) > usable) {
        std::snprintf(msg, sizeof msg, "Too many sites: %zu given but only %ld usable points.", site_indices_.size(), usable);
        fail = msg;
      }
      for (std::size_t s = 0; !fail && s < site_indices_.size(); ++s) {
        const auto idx = site_indices_[s];
        if (idx < 0 || static_cast<std::size_t>(idx) >= n_cloud || row_of_cloud[static_cast<std::size_t>(idx)] < 0) {
          std::snprintf(msg, sizeof msg, "Site %zu (point %ld) is not a finite point among the indices.", s,
                        static_cast<long>(idx));
          fail = msg;
        } else {
          site_rows.push_back(row_of_cloud[static_cast<std::size_t>(idx)]);
        }
      }
    } else if (sites_ < 1) {
      std::snprintf(msg, sizeof msg, "The number of sites must be at least 1 (got %d).", sites_);
      fail = msg;
    } else if (sites_ > usable) {
      std::snprintf(msg, sizeof msg, "Too many sites: %d requested but only %ld usable points.", sites_, usable);
      fail = msg;
    }
    if (fail) {
      PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] %s\n", fail);
      deinitCompute();
      return;
    }

    pcl_detail::SegmentationSettings settings;
    settings.sites = sites_;
    settings.iterations = iterations_;
    settings.k = k_;
    settings.time_coefficient = time_coefficient_;
    settings.threads = threads_;
    settings.seed = seed_;
    const pcl_detail::SegmentationLabels seg = pcl_detail::heat_voronoi_point_labels(clean.P, site_rows, settings);
    std::vector<int> labels = seg.labels;

    if (seg.unreached > 0) {
      // Nearest labelled point (labels of the diffusion only, so the order of the fix-up does not matter).
      if (!tree_) tree_.reset(new pcl::search::KdTree<PointT>(false));
      tree_->setInputCloud(input_, indices_);
      pcl::Indices nn;
      std::vector<float> d2;
      for (long r = 0; r < usable; ++r) {
        if (seg.labels[static_cast<std::size_t>(r)] >= 0) continue;
        const PointT& q = (*input_)[static_cast<std::size_t>(clean.source[static_cast<std::size_t>(r)])];
        int found = -1;
        for (int k = std::min<int>(16, static_cast<int>(g)); found < 0; k = std::min<int>(4 * k, static_cast<int>(g))) {
          tree_->nearestKSearch(q, k, nn, d2);
          for (const auto c : nn) {
            const int row = row_of_cloud[static_cast<std::size_t>(c)];
            if (row >= 0 && seg.labels[static_cast<std::size_t>(row)] >= 0) {
              found = seg.labels[static_cast<std::size_t>(row)];
              break;
            }
          }
          if (k >= static_cast<int>(g)) break;
        }
        if (found < 0) {
          PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] No heat reached any point.\n");
          deinitCompute();
          return;
        }
        labels[static_cast<std::size_t>(r)] = found;
      }
    }

    std::vector<pcl::PointIndices> out(static_cast<std::size_t>(seg.site_positions.rows()));
    for (auto& c : out) c.header = input_->header;
    for (std::size_t i = 0; i < g; ++i) {
      const int row = clean.representative[i];
      if (row < 0) continue;
      out[static_cast<std::size_t>(labels[static_cast<std::size_t>(row)])].indices.push_back(cloud_index[i]);
    }
    for (auto& c : out) {
      std::sort(c.indices.begin(), c.indices.end());
      c.indices.erase(std::unique(c.indices.begin(), c.indices.end()), c.indices.end());
    }
    clusters = std::move(out);
    site_positions_ = seg.site_positions;
    unreached_ = seg.unreached;
  } catch (const std::exception& e) {
    PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] %s\n", e.what());
    clusters.clear();
  } catch (...) {
    PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] Unknown error.\n");
    clusters.clear();
  }
  deinitCompute();
}

}  // namespace heatcvt
