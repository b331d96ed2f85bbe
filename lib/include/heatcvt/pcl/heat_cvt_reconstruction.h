#pragma once
/// \file pcl/heat_cvt_reconstruction.h
/// PCL-style surface reconstruction with heat CVT (paper §7–8, METHOD.md §7): the
/// pcl::SurfaceReconstruction contract (setInputCloud, setIndices, setSearchMethod,
/// camelCase parameters; the base class's reconstruct() does the input set-up and calls the
/// performReconstruction() overrides of this class) around heatcvt::reconstruct_surface().
///
/// Explicitly instantiated in heatcvt_pcl (target heatcvt::pcl) for pcl::PointXYZ,
/// pcl::PointNormal and pcl::PointXYZRGBNormal. For another point type with x, y, z fields,
/// include heatcvt/pcl/impl/heat_cvt_reconstruction.hpp (or define PCL_NO_PRECOMPILE before
/// including this header): the template bodies are then compiled in your translation unit.
#include <pcl/PolygonMesh.h>
#include <pcl/Vertices.h>
#include <pcl/point_cloud.h>
#include <pcl/surface/reconstruction.h>

#include <cstdint>
#include <string>
#include <vector>

#include "heatcvt/depth_steps.h"
#include "heatcvt/flying_pixels.h"
#include "heatcvt/reconstruct.h"

namespace heatcvt {

/// Reconstructs a triangle mesh from a point cloud with a heat centroidal Voronoi tessellation
/// computed directly on the points (point Laplacian → Lloyd iterations with heat Voronoi cells
/// (eq. 15–20) and heat centroids (eq. 21–23) → dual triangulation), i.e. the pipeline of
/// `cloud2mesh`, as a PCL surface reconstruction class.
///
/// Input: the points of `setInputCloud()` restricted to `setIndices()` (all points if none
/// given). An organised cloud (height > 1, a depth-camera frame) first loses its flying pixels
/// (flying_pixels.h, ranges from the cloud's sensor_origin_; setFlyingPixels()). Points with a
/// NaN/inf coordinate are skipped and exact duplicates merged (first occurrence kept), and the
/// quantised depth of a depth frame is refitted (depth_steps.h, rays from sensor_origin_;
/// setDepthSteps()), exactly as `cloud2mesh` does after reading a file, so the same points,
/// options and seed give the same mesh as `cloud2mesh`.
/// Normals and other fields of the input are not used by the reconstruction (it estimates its
/// own normals).
///
/// Output (input units): #sites vertices (fewer if some sites are in no triangle) and
/// consistently oriented triangles. reconstruct(pcl::PolygonMesh&) (inherited from
/// pcl::SurfaceReconstruction) fills `output.cloud` with the fields of PointT and keeps the
/// input's header; reconstruct(points, polygons) returns the vertices as PointT. Fields
/// other than x, y, z are copied from the nearest input point found with the search method
/// (a pcl::search::KdTree is built over the indexed input, after the indices are checked, when
/// none was set: the class clears pcl::SurfaceReconstruction's `check_tree_` so the base class
/// does not build one over unchecked indices), except normals
/// (normal_x/y/z, when PointT has them), which are set to the area-weighted unit vertex normals
/// of the output mesh (curvature copied from the nearest point).
///
/// Errors: no input (a new object holds an empty placeholder cloud until setInputCloud(), so
/// the base class's reconstruct() never dereferences a null cloud), an empty cloud (or no
/// finite point among the indices), an index outside the cloud, more sites than usable points,
/// bad parameters, and any heatcvt exception are reported with
/// `PCL_ERROR("[heatcvt::HeatCVTReconstruction::reconstruct] ...")` and give an empty result
/// (no points, no polygons). Nothing is thrown. As for every PCL class, setInputCloud(nullptr)
/// is not supported.
///
/// Cost: dominated by the CVT, about (sites) × (a few cells) per iteration; see cloud2mesh.
template <typename PointT>
class HeatCVTReconstruction : public pcl::SurfaceReconstruction<PointT> {
 public:
  using Ptr = pcl::shared_ptr<HeatCVTReconstruction<PointT>>;
  using ConstPtr = pcl::shared_ptr<const HeatCVTReconstruction<PointT>>;
  using PointCloud = pcl::PointCloud<PointT>;
  using KdTree = pcl::search::Search<PointT>;
  using KdTreePtr = typename KdTree::Ptr;

  using pcl::SurfaceReconstruction<PointT>::input_;
  using pcl::SurfaceReconstruction<PointT>::indices_;
  using pcl::SurfaceReconstruction<PointT>::tree_;
  using pcl::SurfaceReconstruction<PointT>::check_tree_;
  using pcl::SurfaceReconstruction<PointT>::reconstruct;

  /// Defaults are those of ReconstructionOptions (= `cloud2mesh --help`): 3000 sites, CVT on
  /// ~10 points per site, 40 surface-Lloyd + 6 heat Lloyd iterations, k = 30, t = 1·h̄²,
  /// anisotropy 0, all threads, seed 1.
  HeatCVTReconstruction() {
    check_tree_ = false;
    input_ = no_input_;
  }
  ~HeatCVTReconstruction() override = default;

  /// Number of CVT sites = vertices of the output mesh. Must be ≥ 4 and ≤ the number of
  /// usable points. Default 3000.
  void setNumberOfSites(int sites) { options_.sites = sites; }
  int getNumberOfSites() const { return options_.sites; }

  /// Maximum number of heat Lloyd iterations (≥ 0), after the surface Lloyd
  /// (ReconstructionOptions::surface_lloyd_iterations). Default 6.
  void setMaximumIterations(int iterations) { options_.iterations = iterations; }
  int getMaximumIterations() const { return options_.iterations; }

  /// k of the kNN neighbourhoods of the point Laplacian, in [ReconstructionOptions::min_neighbors,
  /// ReconstructionOptions::max_neighbors] = [6, 200]. Default 30.
  void setKSearch(int k) { options_.neighbors = k; }
  int getKSearch() const { return options_.neighbors; }

  /// Time coefficient C of the diffusion time t = C·h̄² (h̄ = mean edge length of the
  /// Laplacian's local triangles; paper §2, eq. 7, default of Crane et al.). > 0. Default 1.
  void setTimeCoefficient(double coefficient) { options_.time_coefficient = coefficient; }
  double getTimeCoefficient() const { return options_.time_coefficient; }

  /// λ of the anisotropic lift (p, λ n) of paper §7.1 (Fig. 9; paper value 0.05, in units of
  /// the bounding box); 0 = isotropic. ≥ 0. Default 0.
  void setAnisotropy(double lambda) { options_.anisotropy = lambda; }
  double getAnisotropy() const { return options_.anisotropy; }

  /// Curvature-adaptive sizing (heatcvt/adaptive_sizing.h): edge length ∝ κ^(-A/2) of the
  /// largest curvature κ, A in [0, 2] (0 = uniform, 1 = the same chord error everywhere), the
  /// largest over the smallest edge length at most `max_size_ratio` (≥ 1); the vertex count
  /// stays the sites asked for. Default 0 and 3.
  void setAdaptivity(double adaptivity, double max_size_ratio = 3.0) {
    options_.adaptive.adaptivity = adaptivity;
    options_.adaptive.max_size_ratio = max_size_ratio;
  }
  double getAdaptivity() const { return options_.adaptive.adaptivity; }

  /// Threads (OpenMP); 0 = all hardware threads. The mesh does not depend on it. Default 0.
  void setNumberOfThreads(int threads) { options_.threads = threads; }
  int getNumberOfThreads() const { return options_.threads; }

  /// Seed of the initial sites (std::mt19937: first farthest-point site, or the random sites). Default 1.
  void setSeed(std::uint32_t seed) { options_.seed = seed; }
  std::uint32_t getSeed() const { return options_.seed; }

  /// Statistical outlier removal before the reconstruction (cloud2mesh --denoise). Default false.
  void setDenoise(bool denoise) { options_.denoise = denoise; }
  bool getDenoise() const { return options_.denoise; }

  /// The stray-point rules (stray_points.h, cloud2mesh --stray-ratio and --keep-small). Default
  /// on (ratio 8, 16 neighbours, groups of fewer than 30 points or sparse ones); ratio 0,
  /// min_group_points 0 and sparse_group_fraction 0 together keep every point.
  void setStrayPoints(const StrayPointOptions& stray) { options_.stray = stray; }
  const StrayPointOptions& getStrayPoints() const { return options_.stray; }

  /// Voxel-grid downsampling edge length in input units; 0 = off. Default 0.
  void setVoxelSize(double size) { options_.voxel_size = size; }
  double getVoxelSize() const { return options_.voxel_size; }

  /// The flying-pixel rule for organised input clouds (cloud2mesh --flying-pixels). Default on
  /// (3 % of the range); neighbour_distance_ratio = 0 keeps every pixel.
  void setFlyingPixels(const FlyingPixelOptions& options) { flying_ = options; }
  const FlyingPixelOptions& getFlyingPixels() const { return flying_; }

  /// The refit of quantised depth (cloud2mesh --depth-steps). Default on; max_distinct_fraction
  /// = 0 leaves the depth as it is. getDepthStepReport(): what the last reconstruction found.
  void setDepthSteps(const DepthStepOptions& options) { depth_steps_ = options; }
  const DepthStepOptions& getDepthSteps() const { return depth_steps_; }
  const DepthStepReport& getDepthStepReport() const { return depth_report_; }

  /// All options at once (the same struct as reconstruct_surface() and cloud2mesh).
  void setOptions(const ReconstructionOptions& options) { options_ = options; }
  const ReconstructionOptions& getOptions() const { return options_; }

  /// Optional progress callback (stage name, fraction in [0, 1]). Default none.
  void setProgressCallback(const ReconstructionCallback& callback) { progress_ = callback; }

  /// Result of the last successful reconstruction (mesh in input units, CGAL validation report,
  /// timings, φmin / φm); empty after a failure.
  const ReconstructionResult& getReconstructionResult() const { return result_; }

 protected:
  std::string getClassName() const override { return "heatcvt::HeatCVTReconstruction"; }

  /// Called by pcl::SurfaceReconstruction::reconstruct(pcl::PolygonMesh&) after initCompute():
  /// reconstructs input_/indices_ into `output` (cloud with the fields of PointT, triangles as
  /// pcl::Vertices; the base class has copied the input's header). On failure: PCL_ERROR and an
  /// empty mesh.
  void performReconstruction(pcl::PolygonMesh& output) override;
  /// Called by pcl::SurfaceReconstruction::reconstruct(points, polygons) after initCompute():
  /// reconstructs into `points` (#vertices PointT, see the class comment for the fields) and
  /// `polygons` (triangles indexing `points`). On failure: PCL_ERROR, both empty.
  void performReconstruction(pcl::PointCloud<PointT>& points, std::vector<pcl::Vertices>& polygons) override;

 private:
  /// Common path of both overloads; false (after PCL_ERROR) on failure.
  bool run(pcl::PointCloud<PointT>& points, std::vector<pcl::Vertices>& polygons);

  /// Placeholder input of a new object: empty, recognised as "no input given".
  const typename PointCloud::ConstPtr no_input_{new PointCloud};
  ReconstructionOptions options_;
  FlyingPixelOptions flying_;
  DepthStepOptions depth_steps_;
  DepthStepReport depth_report_;
  ReconstructionCallback progress_;
  ReconstructionResult result_;
};

}  // namespace heatcvt

#ifdef PCL_NO_PRECOMPILE
#include "heatcvt/pcl/impl/heat_cvt_reconstruction.hpp"
#endif
