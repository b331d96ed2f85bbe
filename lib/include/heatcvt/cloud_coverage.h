#pragma once
/// \file cloud_coverage.h
/// How much of a point cloud the mesh made from it covers, and what the points it leaves out look
/// like: the figure that tells a partial reconstruction from a whole one.
///
/// Every check of a reconstruction (manifold, oriented, no crossings, the vertex count, the angles)
/// can pass on a mesh of one part of the cloud. Two causes are told apart here:
///  - the cloud is not a sampled surface at the requested spacing: its points fill a band or a
///    volume thicker than a fraction of the site spacing (the thickness, estimate_noise() at the
///    spacing), so no surface through them exists for the CVT to find;
///  - a part of the cloud (a cluster of points, an object of a scene) that the mesh does not reach:
///    the largest group of uncovered points, with its size in site spacings. A group smaller than
///    a site spacing across is below the resolution asked for.
#include <Eigen/Core>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// Options of cloud_coverage().
struct CloudCoverageOptions {
  /// Points measured: every point of a cloud of up to this many, an even stride of a larger one.
  /// Default 100,000.
  int max_queries = 100000;
  /// A point is covered where the mesh passes within this many site spacings (the mesh's mean edge
  /// length) of it. Default 1.
  double covered_spacings = 1.0;
  /// Uncovered points closer than this many site spacings (the larger of the mesh's mean edge
  /// length and the spacing asked for) belong to one group. Default 1.
  double group_spacings = 1.0;
  /// A share of uncovered points above which a reconstruction covers the cloud only in part
  /// (CloudCoverage::partial()). Default 0.2: a fifth of the cloud missing is a part of the scene
  /// a user sees missing (docs/benchmarks.md lists the shared clouds' shares).
  double partial_share = 0.2;
  /// A thickness (in site spacings) from which the points fill a band or a volume rather than
  /// sampling a surface (CloudCoverage::volumetric()). Default 0.28, where the heat CVT's dual
  /// breaks (noise_estimate.h): points that fill a ball give 0.29-0.39 (the less, the more
  /// neighbourhoods its surface cuts), blobby.xyz 0.33, pcl_noisy_slice_displaced 0.278 at 500 sites,
  /// the other scans of ../shared/data/clouds at most 0.22 where measured within 2 spacings.
  double volume_thickness = 0.28;
  /// The thickness tells a volume only where it was measured within at most this many site
  /// spacings: over a wider radius (a sampling sparser than about 3 points per site, see
  /// max_radius_doublings) the quadratic's misfit to the shape itself counts (fin90_with_PCA_normals
  /// at 500 sites, 1.5 points per site: 0.33 over 4 spacings). Default 2.
  double volume_radius_spacings = 2.0;
  /// Where fewer than half the thickness's query points have NoiseEstimateOptions::min_neighbors
  /// points within a site spacing (a cloud sparser than the spacing), the radius of the estimate
  /// is doubled, at most this many times; the thickness stays in site spacings. Default 4.
  int max_radius_doublings = 4;
  int threads = 0;  ///< OpenMP threads (0 = all cores); the result does not depend on it.
};

/// What cloud_coverage() measured.
struct CloudCoverage {
  int queries = 0;             ///< cloud points measured
  double spacing = 0;          ///< the mesh's mean edge length, input units
  double uncovered_share = 0;  ///< share of the measured points farther than covered_spacings
  /// RMS height residual of the points about their local quadratic fit within a site spacing
  /// (estimate_noise(); a wider radius in a sparser cloud, see max_radius_doublings), in site
  /// spacings; 0 when too few points for the estimate.
  double thickness_spacings = 0;
  int groups = 0;              ///< groups of uncovered points
  double largest_group_share = 0;     ///< the largest group's share of the measured points
  double largest_group_spacings = 0;  ///< its bounding-box diagonal, in site spacings
  double partial_share = 0.2;         ///< CloudCoverageOptions::partial_share of the measurement
  double volume_thickness = 0.28;     ///< CloudCoverageOptions::volume_thickness of the measurement
  double thickness_radius_spacings = 1;  ///< the radius the thickness was measured within, in site spacings
  double volume_radius_spacings = 2;     ///< CloudCoverageOptions::volume_radius_spacings of the measurement
  /// Whether the mesh leaves more than partial_share of the points uncovered.
  bool partial() const { return uncovered_share > partial_share; }
  /// Whether the points fill a band or a volume at the site spacing.
  bool volumetric() const {
    return thickness_spacings >= volume_thickness && thickness_radius_spacings <= volume_radius_spacings;
  }
};

/// \throw InvalidInputError where an option is out of its range (each option's documented one).
void check_cloud_coverage_options(const CloudCoverageOptions& options);

/// Coverage of the points P (#P by 3, finite, the frame of `mesh`) by `mesh`: points within
/// covered_spacings of the mesh's mean edge length; the thickness at `site_spacing`, the spacing
/// asked for (sqrt(area / sites); 0 = the mesh's mean edge length), which a mesh of one small part
/// of the cloud does not have; the uncovered points grouped at group_spacings of the larger of the
/// two (where the sizing gave all the vertices asked for to a small part, its edges are far
/// shorter than the spacing, and by them every point left out would be alone in its group).
/// \throw InvalidInputError for a mesh without faces, a site_spacing that is negative or not
/// finite, or bad options.
CloudCoverage cloud_coverage(const TriangleMesh& mesh, const Eigen::MatrixX3d& P, double site_spacing = 0,
                             const CloudCoverageOptions& options = {});

}  // namespace heatcvt
