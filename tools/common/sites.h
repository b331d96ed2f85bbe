#pragma once
// Sites (generators, handles) given in a text file, snapped to a triangle mesh.
#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/normalize.h"

namespace heatcvt::cli {

/// Default of --snap-tolerance: a site farther than 10⁻³ of the bounding-box diagonal from the
/// surface is an error (a site file for another mesh or in other units), not moved silently.
constexpr double kDefaultSnapTolerance = 1e-3;

/// Adds --snap-tolerance (a fraction of the bounding-box diagonal) bound to `tolerance`.
CLI::Option* add_snap_tolerance_option(CLI::App& app, double& tolerance);

/// Checks --snap-tolerance: a positive finite number. Throws heatcvt::InvalidInputError.
void check_snap_tolerance(double tolerance);

/// Reads "x y z" rows from `path` (cli::read_number_rows), moves them into `frame` (the frame
/// (V, F) was normalised with, normalize.h) and snaps each to its closest point on (V, F).
/// Throws InvalidInputError "<path>: ..." when a site is farther than `max_distance` (in
/// normalised units, i.e. a fraction of the bounding-box diagonal) from the surface, or when two
/// sites snap to the same surface point (their cells would be empty).
std::vector<SurfacePoint> read_snapped_sites(const std::string& path, const Eigen::MatrixX3d& V,
                                             const Eigen::MatrixX3i& F, const NormalizationFrame& frame,
                                             double max_distance = std::numeric_limits<double>::infinity());

}  // namespace heatcvt::cli
