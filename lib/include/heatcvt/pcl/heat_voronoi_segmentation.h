#pragma once
/// \file pcl/heat_voronoi_segmentation.h
/// PCL-style segmentation of a point cloud into heat Voronoi cells (paper §4): every point gets
/// the site whose heat is largest there (eq. 15/17, ties by eq. 19), with heat diffused on the
/// cloud itself through the point Laplacian. The result is a list of pcl::PointIndices, one per
/// site, like pcl::EuclideanClusterExtraction::extract().
///
/// Explicitly instantiated in heatcvt_pcl (target heatcvt::pcl) for pcl::PointXYZ,
/// pcl::PointNormal and pcl::PointXYZRGBNormal. For other point types with x, y, z fields,
/// include heatcvt/pcl/impl/heat_voronoi_segmentation.hpp (or define PCL_NO_PRECOMPILE before
/// including this header).
#include <pcl/PointIndices.h>
#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>
#include <pcl/search/search.h>

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace heatcvt {

/// Heat Voronoi segmentation of a point cloud.
///
/// Sites: either given explicitly as indices into the input cloud (setSiteIndices(); each must
/// be a finite point among the indexed ones), or, when none are given, `setNumberOfSites()` sites
/// of a heat centroidal Voronoi tessellation of the points (Lloyd iteration, paper §7.1, seeded
/// random start, `setMaximumIterations()` iterations).
///
/// Method: the indexed points are gathered, non-finite ones skipped, exact duplicates merged;
/// the point Laplacian (k = setKSearch() neighbours; point_laplacian.h) is built; one diffusion
/// (M − tL)u = b(site) per site (eq. 8, t = C·h̄²); the exact heat Voronoi diagram (voronoi.h) on
/// the Laplacian's local triangles; each point takes the cell of the diagram at its position.
/// Duplicates take the label of their first copy. Points no heat reached (in no local triangle, or
/// in a connected part of the cloud without any site; counted by getNumberOfUnreachedPoints())
/// take the label of the nearest labelled point, found with the search method (a
/// pcl::search::KdTree over the indexed input unless one was set).
///
/// Output of extract(): `clusters[s]` holds the cloud indices (ascending) of the points in the
/// cell of site s, so the clusters partition the finite indexed points (each exactly once); a
/// cluster may be empty (a CVT site whose cell contains no input point). With explicit sites,
/// `clusters[s]` contains site s itself unless two sites coincide.
///
/// Errors (PCL_ERROR("[heatcvt::HeatVoronoiSegmentation::extract] ...") and an empty result):
/// no input, empty cloud / no finite point, no sites, more sites than usable points, a site index
/// outside the cloud / not among the indices / non-finite, bad parameters, heatcvt exceptions.
template <typename PointT>
class HeatVoronoiSegmentation : public pcl::PCLBase<PointT> {
 public:
  using PointCloud = pcl::PointCloud<PointT>;
  using KdTree = pcl::search::Search<PointT>;
  using KdTreePtr = typename KdTree::Ptr;
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

  /// Defaults: 100 CVT sites, 30 iterations, k = 30, t = 1·h̄², all threads, seed 1.
  HeatVoronoiSegmentation() = default;
  virtual ~HeatVoronoiSegmentation() = default;

  /// Search method for the nearest-labelled-point fallback (see the class comment). Default:
  /// a pcl::search::KdTree built at extract().
  void setSearchMethod(const KdTreePtr& tree) { tree_ = tree; }
  KdTreePtr getSearchMethod() const { return tree_; }

  /// Explicit sites as indices into the input cloud. Non-empty: used instead of CVT sites.
  void setSiteIndices(const pcl::Indices& sites) { site_indices_ = sites; }
  const pcl::Indices& getSiteIndices() const { return site_indices_; }

  /// Number of CVT sites when no explicit sites are given (≥ 1, ≤ usable points). Default 100.
  void setNumberOfSites(int sites) { sites_ = sites; }
  int getNumberOfSites() const { return sites_; }

  /// Lloyd iterations of the CVT sites (≥ 0; 0 = the seeded random sites). Default 30.
  void setMaximumIterations(int iterations) { iterations_ = iterations; }
  int getMaximumIterations() const { return iterations_; }

  /// k of the point Laplacian's neighbourhoods (≥ 3). Default 30.
  void setKSearch(int k) { k_ = k; }
  int getKSearch() const { return k_; }

  /// C of the diffusion time t = C·h̄² (eq. 7). > 0. Default 1.
  void setTimeCoefficient(double coefficient) { time_coefficient_ = coefficient; }
  double getTimeCoefficient() const { return time_coefficient_; }

  /// Threads; 0 = all. Labels do not depend on it. Default 0.
  void setNumberOfThreads(int threads) { threads_ = threads; }
  int getNumberOfThreads() const { return threads_; }

  /// Seed of the CVT's random initial sites. Default 1.
  void setSeed(std::uint32_t seed) { seed_ = seed; }
  std::uint32_t getSeed() const { return seed_; }

  /// Labels the points; see the class comment. On failure: PCL_ERROR and `clusters` empty.
  void extract(std::vector<pcl::PointIndices>& clusters);

  /// Positions (#sites by 3, input units) of the sites of the last extract(): the given points,
  /// or the final CVT sites (on the point Laplacian's local triangles).
  const Eigen::MatrixX3d& getSitePositions() const { return site_positions_; }

  /// Points of the last extract() that no heat reached and were labelled by nearest neighbour.
  int getNumberOfUnreachedPoints() const { return unreached_; }

 protected:
  std::string getClassName() const { return "heatcvt::HeatVoronoiSegmentation"; }

 private:
  KdTreePtr tree_;
  pcl::Indices site_indices_;
  int sites_ = 100;
  int iterations_ = 30;
  int k_ = 30;
  double time_coefficient_ = 1.0;
  int threads_ = 0;
  std::uint32_t seed_ = 1;
  Eigen::MatrixX3d site_positions_;
  int unreached_ = 0;
};

}  // namespace heatcvt

#ifdef PCL_NO_PRECOMPILE
#include "heatcvt/pcl/impl/heat_voronoi_segmentation.hpp"
#endif
