#pragma once
/// \file reconstruct_stream.h
/// Surface reconstruction from a cloud that does not have to fit in memory: the cloud is
/// streamed (cloud_stream.h) into a voxel summary (voxel_summary.h) sized from the target site
/// count, and reconstruct_surface() (reconstruct.h) runs on the voxel means. A cloud small enough
/// (StreamOptions::max_raw_points) is reconstructed from its raw points instead, exactly as the
/// whole-cloud path does.
#include <cstdint>
#include <functional>
#include <string>

#include "heatcvt/cloud_io.h"
#include "heatcvt/cloud_stream.h"
#include "heatcvt/noise_estimate.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/voxel_summary.h"

namespace heatcvt {

/// Options of the streamed front end.
struct StreamOptions {
  /// A cloud of at most this many points (finite or not) is kept whole and reconstructed from
  /// its raw points: read_cloud's clean-up, then reconstruct_surface(points, options), the same
  /// mesh as the whole-cloud path. reconstruct_surface needs about 2.1 KB per point, so the
  /// default 200,000 keeps that path under ~0.5 GB. 0 = always summarise. Default 200000.
  std::int64_t max_raw_points = 200000;
  /// ... and, where set, of at most this many points per requested site (ReconstructionOptions::
  /// sites): beyond it the output's resolution needs only a summary of the cloud, which the voxel
  /// means give in less time and memory, with the noise averaged down, and the time per site
  /// no longer grows with the points per site. 0 = no limit per site. Default 40.
  double max_raw_points_per_site = 40;
  /// Points per chunk read from a file. Default 65536.
  std::int64_t chunk_points = 65536;
  /// Voxel size of the summary (input units); 0 = chosen by choose_voxel_size() from a
  /// reservoir sample of the first pass, for ReconstructionOptions::sites. Default 0.
  double voxel_size = 0.0;
  /// The chooser's options (points_per_site: voxel means per site). Defaults as VoxelSizeOptions;
  /// its `threads` is replaced by ReconstructionOptions::threads, as is the summary's.
  VoxelSizeOptions voxel;
  /// Size of the uniform reservoir sample (first pass) the voxel size is chosen from. Default 100000.
  std::int64_t sample_points = 100000;
  /// Reconstruct from VoxelSummary::surface_points(sites × voxel.points_per_site) (means
  /// projected on the plane fitted to their voxel neighbourhood, then thinned to at most
  /// that many points) instead of the plain voxel means: removes the double layer of means where
  /// the noise band spans two voxel layers, and hits the points-per-site target. Default true.
  bool project_to_surface = true;
  /// The plane fit of each voxel mean under project_to_surface (widened where the noise band is
  /// as thick as the 3×3×3 voxel neighbourhood). Defaults as VoxelSurfaceFit.
  VoxelSurfaceFit surface_fit;
  /// With project_to_surface and a chosen voxel size h, the summary is built at h / f, so that
  /// the thinning has points to spare (about f² times more voxels in memory), where
  /// f = min(fine_voxel_factor, max(1, sqrt(points per voxel at h / min_points_per_fine_voxel))):
  /// finer only while each fine voxel still averages enough points to damp the noise (at a fixed
  /// density of ~5 raw points per output point, finer voxels of ~2 points gave a spurious handle
  /// on armadillo). Defaults 1.5 and 10.
  double fine_voxel_factor = 1.5;
  double min_points_per_fine_voxel = 10.0;
  /// The flying-pixel rule applied to an organised PCD file (flying_pixels.h; read_cloud applies
  /// the same). Default on; neighbour_distance_ratio = 0 keeps every pixel.
  FlyingPixelOptions flying_pixels;
  /// The refit of quantised depth (depth_steps.h) of an organised PCD file (a depth frame, whose
  /// size its sensor bounds): where it is enabled, such a file is read whole as read_cloud() does
  /// (flying pixels, clean-up, the refit) and then streamed from memory (path version only).
  /// Unorganised files are streamed as they are. Default on.
  DepthStepOptions depth_steps;
  /// The summary's reconstruction stops the CVT's surface Lloyd once the mean site move is below
  /// this · site spacing (ReconstructionOptions::surface_lloyd_mean_tolerance). At tens of
  /// thousands of sites the max-move rule never stops it (a few sites at folds keep swapping
  /// corners, 0.3 spacings at 20,000 sites) and the iterations after this point no longer change
  /// the mesh's quality. 0 = every iteration. Default 0.005 (measurements in docs/benchmarks.md).
  double surface_lloyd_mean_tolerance = 0.005;
  /// The noise limit of the site count (noise_estimate.h). Pass 1 also keeps a second reservoir
  /// sample of max(sample_points, noise_sample_points_per_site × sites) points, and
  /// estimate_noise() measures the noise σ on it at the requested site spacing (the area from
  /// estimate_surface_area()). Where σ exceeds max_noise_spacings spacings, the CVT runs on
  /// noise_limited_sites() sites (at most max_noise_reduction times fewer), the summary is built
  /// for that count, and the mesher's sizing remeshes the result on the fitted surface to the
  /// requested count. Below the limit nothing changes. 0 = off. Defaults 0.17 spacings (the dual
  /// broke from about 0.28 on armadillo; with a limit of 0.2 and 0.14 some sized meshes kept a
  /// second piece or a sliver, measurements in docs/benchmarks.md), 8, 40 points per site (about
  /// 120 within each query's radius of one spacing; the sample, its copy and its kd-tree take
  /// about 3 MB per 1,000 sites until pass 2 starts).
  double max_noise_spacings = 0.17;
  double max_noise_reduction = 8.0;
  std::int64_t noise_sample_points_per_site = 40;
  NoiseEstimateOptions noise;
  /// Seed of the reservoir sampling (std::mt19937_64). Default 1.
  std::uint64_t sample_seed = 1;
  /// Reading progress: pass 1 (raw points / sample) or 2 (voxel summary), and the reader's counters.
  std::function<void(int pass, const StreamProgress&)> progress;
};

/// Result of the streamed reconstruction.
struct StreamedReconstruction {
  ReconstructionResult result;   ///< of reconstruct_surface on `cloud.P`
  /// The points the reconstruction ran on: the cleaned raw cloud, or the voxel points (surface
  /// points or plain means, see StreamOptions::project_to_surface) with their mean colours; for
  /// plain means also their covariance normals (unoriented; zero rows where undefined).
  PointCloud cloud;
  bool summarised = false;       ///< true: voxel means; false: the raw points
  double voxel_size = 0;         ///< of the summary (0 when not summarised)
  std::int64_t points_read = 0;  ///< points handed out by the source (one pass); a depth frame read whole: its file's points
  /// Passes over the source: 1 or 2, and one more where dense pieces of the summary
  /// (ReconstructionOptions::dense_pieces) are read again into summaries of their own.
  int passes = 0;
  std::int64_t flying_pixels_removed = 0;  ///< by StreamOptions::flying_pixels (path version only)
  DepthStepReport depth_steps;  ///< by StreamOptions::depth_steps (path version only)
  /// Noise σ of the cloud in requested site spacings (StreamOptions::max_noise_spacings; 0 when
  /// not estimated: the raw path, an explicit voxel size, or the limit off).
  double noise_spacings = 0;
  /// Sites of the CVT: the requested count, or fewer where the noise limits it (the mesh is
  /// then sized to the requested count).
  int cvt_sites = 0;
};

/// The most points a cloud may have to be reconstructed from its raw points for a request of
/// `sites`: max_raw_points, and max_raw_points_per_site × sites where that is set and smaller.
std::int64_t raw_point_limit(const StreamOptions& stream, int sites);

/// Streams `source` and reconstructs its surface:
///  1. pass 1 keeps the raw points while there are at most raw_point_limit() (then drops them)
///     and a uniform reservoir sample of `sample_points` finite points; if the source ends within
///     that limit, the raw points are cleaned as read_cloud does and reconstructed exactly;
///  2. otherwise the noise limit is applied (StreamOptions::max_noise_spacings), pass 2 (after
///     rewind()) bins every point into a VoxelSummary of `voxel_size` (or choose_voxel_size(sample,
///     CVT sites, voxel)) and reconstruct_surface runs on the voxel means with
///     cvt_points_per_site = 0 (the summary already is the spatially uniform subset). With an
///     explicit voxel_size the summary is built during pass 1 (one pass, no noise limit).
/// Chunk size does not change the result (per-voxel sums in point order, reservoir sampling
/// point by point). \throw as the source (IOError) and reconstruct_surface; InvalidInputError
/// when the source holds no finite point.
StreamedReconstruction reconstruct_surface_streamed(CloudChunkSource& source, const ReconstructionOptions& options = {},
                                                    const StreamOptions& stream = {},
                                                    const ReconstructionCallback& progress = {});

/// The same on a cloud file (formats of CloudChunkReader), read in chunks of stream.chunk_points.
StreamedReconstruction reconstruct_surface_streamed(const std::string& path, const ReconstructionOptions& options = {},
                                                    const StreamOptions& stream = {},
                                                    const ReconstructionCallback& progress = {});

/// Reconstructs from a summary filled through VoxelSummary::add (the push interface: a PCL user
/// feeds clouds piece by piece): reconstruct_surface on its voxel points (stream.project_to_surface),
/// cvt_points_per_site = 0; the other StreamOptions are not used.
/// \throw InvalidInputError on an empty summary, as reconstruct_surface otherwise.
StreamedReconstruction reconstruct_surface_from_summary(const VoxelSummary& summary, const ReconstructionOptions& options = {},
                                                        const StreamOptions& stream = {},
                                                        const ReconstructionCallback& progress = {});

}  // namespace heatcvt
