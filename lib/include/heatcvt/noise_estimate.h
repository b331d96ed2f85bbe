#pragma once
/// \file noise_estimate.h
/// How noisy a point cloud is at the scale of the output's site spacing, and the site count
/// below which its heat Voronoi diagram still has a usable dual.
///
/// A CVT whose sites are only a few noise widths apart sees the noise band as a thick shell: the
/// point triangles under the cells run every way, cells touch across the band, and many dual
/// triangles conflict. Measured on armadillo with Gaussian noise (docs/benchmarks.md): from about
/// 0.28 noise widths per site spacing (this estimate) a third or more of the sites end in no
/// triangle and holes stay open. Fewer sites on the same cloud do not see the band.
#include <Eigen/Core>

namespace heatcvt {

/// Options of estimate_noise().
struct NoiseEstimateOptions {
  /// Query points where the local fit is measured (evenly strided over the rows). Default 3000.
  int queries = 3000;
  /// Radius of each query's neighbourhood, in site spacings: wide enough to hold a noise band of
  /// up to about a quarter spacing, narrow enough that a quadratic describes the surface in it.
  /// Default 1.
  double radius_spacings = 1.0;
  /// Queries with fewer points within the radius are skipped (sparse or stray points). Default 20.
  int min_neighbors = 20;
  /// A query with more points within the radius fits this many of them, evenly strided over
  /// their rows (a dense cluster smaller than the radius would have every query on it fit all
  /// of its points: quadratic time). 0 = every point. Default 1000.
  int max_fit_points = 1000;
  int threads = 0;  ///< OpenMP threads (0 = all cores); the result does not depend on it.
};

/// What estimate_noise() measured.
struct NoiseEstimate {
  /// Median over the queries of the RMS height residual of the least-squares quadratic height
  /// field (over the neighbourhood's PCA plane) fitted to the points within the radius: the
  /// noise's standard deviation across the surface where the surface is smooth at that scale
  /// (the quadratic takes the curvature; the median passes over edges, creases and clutter).
  /// Input units; 0 when no query had enough neighbours.
  double sigma = 0;
  int queries_used = 0;  ///< queries with enough neighbours
};

/// Noise of the points P (#P by 3, finite) at the scale of `spacing` (input units).
/// \throw InvalidInputError for a spacing that is not finite and > 0, or bad options.
NoiseEstimate estimate_noise(const Eigen::MatrixX3d& P, double spacing, const NoiseEstimateOptions& options = {});

/// The site count at which `sigma` is at most `max_noise_spacings` site spacings, for a request of
/// `sites` at `spacing`: sites · (max_noise_spacings · spacing / sigma)² where the request is
/// finer than that, else `sites`; never below sites / max_reduction, nor below 4.
int noise_limited_sites(int sites, double spacing, double sigma, double max_noise_spacings, double max_reduction);

}  // namespace heatcvt
