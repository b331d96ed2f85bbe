#pragma once
/// \file reconstruct.h
/// Surface reconstruction from a point cloud (the design card's headline pipeline; paper §8,
/// METHOD.md §7): point Laplacian → heat CVT on the points → dual triangulation → sites placed
/// on a locally fitted surface → orientation, clean-up, validation. The same CVT engine as the
/// mesh path (cvt.h); only the Laplacian builder differs.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "heatcvt/mesh.h"
#include "heatcvt/validate.h"

namespace heatcvt {

/// Options of reconstruct_surface(). Every default is the one `cloud2mesh --help` shows.
struct ReconstructionOptions {
  int sites = 3000;               ///< vertices of the output mesh (CVT sites). Default 3000.
  int iterations = 30;            ///< maximum Lloyd iterations. Default 30.
  int neighbors = 30;             ///< k of the kNN neighbourhoods of the point Laplacian. Default 30.
  double anisotropy = 0.0;        ///< λ of the anisotropic lift (paper §7.1); 0 = isotropic. Default 0.
  bool denoise = false;           ///< statistical outlier removal before everything. Default false.
  double voxel_size = 0.0;        ///< voxel-grid downsampling (input units); 0 = off. Default 0.
  double time_coefficient = 1.0;  ///< t = C·h̄². Default 1.
  std::uint32_t seed = 1;         ///< seed of the initial sites. Default 1.
  int threads = 0;                ///< 0 = all cores. Default 0.
};

/// Progress of a reconstruction: a stage name and a fraction in [0, 1].
using ReconstructionCallback = std::function<void(const std::string& stage, double fraction)>;

/// Result of reconstruct_surface(), in the input's coordinates.
struct ReconstructionResult {
  TriangleMesh mesh;               ///< the reconstructed, consistently oriented surface
  ValidationReport validation;     ///< CGAL checks of `mesh`
  int points_used = 0;             ///< after clean-up / denoising / downsampling
  double laplacian_seconds = 0, factor_seconds = 0, cvt_seconds = 0, total_seconds = 0;
  int iterations = 0;              ///< Lloyd iterations run
  double min_angle_deg = 0;        ///< φmin: smallest interior angle over all triangles
  double mean_min_angle_deg = 0;   ///< φm: mean over triangles of their smallest angle
};

/// Reconstructs a surface from the points P (#P by 3; NaN-free, duplicates allowed).
/// \throw InvalidInputError for empty / too small clouds, sites < 4 or > usable points, bad options.
ReconstructionResult reconstruct_surface(const Eigen::MatrixX3d& P, const ReconstructionOptions& options = {},
                                         const ReconstructionCallback& progress = {});

}  // namespace heatcvt
