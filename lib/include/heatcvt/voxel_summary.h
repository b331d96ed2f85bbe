#pragma once
/// \file voxel_summary.h
/// A point cloud summarised per voxel while it streams in: points are binned into a hash of
/// cubic voxels keyed by integer cell, and each occupied voxel keeps its moments (point count,
/// sum of positions, sum of outer products for the covariance, colour sums). Memory is
/// proportional to the number of occupied voxels, never to the number of points. Plus the
/// voxel size chooser that sizes the voxels from the target site count.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "heatcvt/cloud_stream.h"

namespace heatcvt {

/// Options of VoxelSummary::surface_points(): the plane fit of each voxel mean.
struct VoxelSurfaceFit {
  /// Smallest / middle eigenvalue of a neighbourhood's covariance up to which it counts as a
  /// plane. A flat patch 3 voxels wide with Gaussian noise σ along the normal has λ0/λ1 ≈
  /// σ² / (0.75 h²): 0.2 is reached at σ ≈ 0.4 h. Default 0.2.
  double planarity = 0.2;
  /// Coarser levels tried (cells 2^1 … 2^max_levels voxels); 0 = the 3×3×3 voxel fit only. Default 2.
  int max_levels = 2;
  /// Where the voxel neighbourhood is no plane (a noise band as thick as it is wide) but a wider
  /// level is, the projected mean is then moved along the wider normal this many times to the
  /// mean of the voxels around it (a mean shift with a box kernel of 3 voxels, towards the middle
  /// of the band). Default 4.
  int shift_steps = 4;
  /// The wider levels and the shift are used only when at least this fraction of the voxels have
  /// a neighbourhood that is no plane: a noise band thicker than the voxels over most of the
  /// surface. Below it the non-planar neighbourhoods are edges, clutter and depth steps of a scan
  /// (a few to 40 % of the voxels on the shared RGB-D and stereo scenes at 2,000 sites), which a
  /// wider plane does not describe, and every voxel keeps its 3×3×3 fit. Default 0.5.
  double min_thick_fraction = 0.5;
};

/// Per-voxel moments of a streamed cloud.
///
/// Determinism: each voxel accumulates its points in the order they are added, and the outputs
/// are listed in cell-key order (lexicographic x, y, z), so how the cloud is cut into chunks
/// does not change any bit of the summary. Sums are taken relative to the voxel's own corner,
/// so the covariance keeps its precision far from the origin.
class VoxelSummary {
 public:
  /// Voxels are the cubes [c·h, (c+1)·h)³ for integer cells c, h = voxel_size. `threads`: the
  /// OpenMP threads of the binning and of surface_points() (0 = all cores); no result depends
  /// on it.
  /// \throw InvalidInputError unless voxel_size is finite and > 0.
  explicit VoxelSummary(double voxel_size, int threads = 0);
  ~VoxelSummary();
  VoxelSummary(VoxelSummary&&) noexcept;
  VoxelSummary& operator=(VoxelSummary&&) noexcept;

  /// Adds the points of a chunk (its colours too when it has them). Points with a non-finite
  /// coordinate are skipped and counted. The push interface: feed a cloud piece by piece.
  /// \throw InvalidInputError when a coordinate / voxel_size exceeds the integer cell range (2^52).
  void add(const CloudChunk& chunk);
  /// Adds positions P (#P by 3) and optional colours C (#P by 3 or 0 rows).
  void add(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C = Eigen::MatrixX3d(0, 3));

  /// Adds each row of P (with colour row of C when C has as many rows) as `weight` coincident
  /// points: count += weight, sums += weight × value. add(P, C) is add_weighted(P, C, 1).
  void add_weighted(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C, std::int64_t weight);

  double voxel_size() const { return h_; }
  /// Occupied voxels.
  Eigen::Index voxels() const;
  /// Finite points added so far; points skipped for a non-finite coordinate.
  std::int64_t points_added() const { return added_; }
  std::int64_t non_finite_skipped() const { return skipped_; }
  /// Every added point carried a colour (and at least one point was added).
  bool has_colours() const { return added_ > 0 && coloured_ == added_; }

  /// #voxels by 3 mean position of each voxel, in cell-key order.
  Eigen::MatrixX3d points() const;
  /// #voxels point counts, in the same order.
  Eigen::VectorXi counts() const;
  /// #voxels by 3 unit normals (unoriented): the eigenvector of the smallest eigenvalue of each
  /// voxel's covariance. Voxels with fewer than `min_points` points, or whose points lie on one
  /// line (second eigenvalue <= 1e-12 × the largest, which includes a zero covariance), get a
  /// zero row and `valid[i] = false`.
  Eigen::MatrixX3d normals(std::vector<bool>* valid = nullptr, int min_points = 3) const;
  /// #voxels by 3 mean colours (empty, 0 rows, unless has_colours()).
  Eigen::MatrixX3d colours() const;
  /// The voxel means moved onto the local surface and thinned, for a noisy cloud whose noise
  /// band spans more than one voxel layer (there the plain means form a double layer, one mean
  /// per layer, each pulled off the surface towards its side):
  ///  1. each voxel's moments are merged with those of its 3×3×3 neighbourhood; the merged mean μ
  ///     and the smallest-eigenvalue eigenvector n of the merged covariance (a plane fit to every
  ///     point of the neighbourhood) give the local surface, and the voxel mean m is projected on
  ///     it: m − ((m − μ)·n) n (kept as is when the neighbourhood has < 3 points or lies on a line).
  ///     Where the noise band is as thick as that neighbourhood is wide, its covariance is no
  ///     plane (λ0/λ1 above `fit.planarity`) and its normal is noise: the normal is then taken
  ///     from the 3×3×3 neighbourhood of cells 2, 4, … 2^fit.max_levels times the voxel size, the
  ///     first that is a plane (moments merged per coarse cell once per level), still through the
  ///     local μ (a wide plane's μ would merge the two sides of a thin part); where none is (a
  ///     crease, a corner), the voxel neighbourhood's normal is kept. Where a wider normal was
  ///     taken, the projected mean is then mean-shifted along it to the middle of the band
  ///     (fit.shift_steps). Both only when such voxels are most of the cloud
  ///     (fit.min_thick_fraction); else every voxel keeps its 3×3×3 fit;
  ///  2. the projected means are binned again, each weighted by its point count, and each cell's
  ///     weighted mean is one output point (cell-key order). The cells are of the voxel size when
  ///     target_points is 0 (or not exceeded), else of the smallest size (within 0.02 %, found by
  ///     bisection) at which at most target_points cells are occupied: the projected means lie on
  ///     a thin surface, so the count hits the target without the noise of the raw points.
  /// `weights` (optional) receives the point count behind each output point; `colours` (optional)
  /// the count-weighted mean colour (0 rows unless has_colours()). Runs on the summary's
  /// threads; the result does not depend on their number.
  Eigen::MatrixX3d surface_points(Eigen::Index target_points = 0, Eigen::VectorXi* weights = nullptr,
                                  Eigen::MatrixX3d* colours = nullptr, const VoxelSurfaceFit& fit = {}) const;
  /// #voxels by 3 integer cells, in the same order.
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3> cells() const;

 private:
  struct Impl;
  const std::vector<std::uint32_t>& order() const;  // voxel indices in cell-key order (cached)
  // One point of `weight` coincident copies (colour: 3 values or null).
  void add_point(double x, double y, double z, const double* colour, std::int64_t weight);
  // The number of the voxel of cell `key`, a new one when it has none yet.
  std::uint32_t slot_of(const std::array<std::int64_t, 3>& key);
  void project_means(const VoxelSurfaceFit& fit, Eigen::MatrixX3d& P, Eigen::VectorXd& w, Eigen::MatrixX3d& C) const;
  double h_, inv_h_;  // voxel size and its inverse (cells are floor(p · inv_h_))
  int threads_;       // resolved OpenMP thread count
  std::int64_t added_ = 0, skipped_ = 0, coloured_ = 0;
  std::unique_ptr<Impl> impl_;
};

/// Options of choose_voxel_size().
struct VoxelSizeOptions {
  /// Voxel means wanted per output site. Default 10 (ReconstructionOptions::cvt_points_per_site).
  double points_per_site = 10.0;
  /// The area probe: the sample is binned at the voxel size where an occupied voxel holds about
  /// this many sample points on average (dense enough that almost every voxel the surface
  /// crosses is occupied). Default 20.
  double sample_points_per_voxel = 20.0;
  /// Refinements of that probe size (each rescales it by the square root of the count ratio,
  /// the law of a surface: occupied voxels ∝ h⁻²). Default 6.
  int probe_iterations = 6;
  /// OpenMP threads of the probe's binning (0 = all cores); the result does not depend on it.
  /// Default 0.
  int threads = 0;
};

/// Surface-area estimate from an unbiased sample of the cloud (e.g. a reservoir sample):
/// occupied voxels at the probe size h (see VoxelSizeOptions::sample_points_per_voxel) × h² / 1.5
/// (a plane crossing cubes of side h occupies (|nx|+|ny|+|nz|)·A/h² of them, 1.5·A/h² on average
/// over orientations). Also returns the probe size and its occupied count.
struct SurfaceAreaEstimate {
  double area = 0;
  double probe_voxel_size = 0;
  Eigen::Index probe_voxels = 0;
};
/// \throw InvalidInputError when the sample has < 10 finite points or no extent.
SurfaceAreaEstimate estimate_surface_area(const Eigen::MatrixX3d& sample, const VoxelSizeOptions& options = {});

/// The voxel size at which a surface sampled by `sample` occupies about sites × points_per_site
/// voxels: h = h_probe · sqrt(probe_voxels / (sites · points_per_site)) (occupied voxels ∝ h⁻²
/// on a surface, so the orientation factor of the area estimate cancels).
/// \throw InvalidInputError for sites < 1, points_per_site <= 0, or a sample as above.
double choose_voxel_size(const Eigen::MatrixX3d& sample, int sites, const VoxelSizeOptions& options = {});

}  // namespace heatcvt
