#include "sites.h"

#include "cli_common.h"
#include "heatcvt/atomic_file.h"
#include "heatcvt/errors.h"

#include <cmath>

namespace heatcvt::cli {

CLI::Option* add_snap_tolerance_option(CLI::App& app, double& tolerance) {
  return app
      .add_option("--snap-tolerance", tolerance,
                  "sites farther than this fraction of the bounding-box diagonal from the surface are an error")
      ->capture_default_str();
}

void check_snap_tolerance(double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance)) throw InvalidInputError("--snap-tolerance must be a positive number");
}

std::vector<SurfacePoint> read_snapped_sites(const std::string& path, const Eigen::MatrixX3d& V,
                                             const Eigen::MatrixX3i& F, const NormalizationFrame& frame,
                                             double max_distance) {
  // Two snapped sites closer than this (normalised units: a fraction of the bounding-box
  // diagonal) are the same point for the heat: one of their cells would be empty.
  constexpr double duplicate_distance = 1e-9;
  const auto rows = read_number_rows(path, 3, "sites");
  const int ns = static_cast<int>(rows.size());
  Eigen::MatrixX3d P(ns, 3);
  for (int i = 0; i < ns; ++i) P.row(i) << rows[i][0], rows[i][1], rows[i][2];
  apply_frame(P, frame);
  const std::vector<SurfacePoint> sites = closest_surface_points(V, F, P);
  Eigen::MatrixX3d S(ns, 3);
  for (int i = 0; i < ns; ++i) {
    S.row(i) = position(V, F, sites[i]).transpose();
    const double d = (S.row(i) - P.row(i)).norm();
    if (d > max_distance)
      throw InvalidInputError(path + ": site " + std::to_string(i + 1) + " is off the surface (distance " +
                              format_double(d * frame.scale) + " > " + format_double(max_distance * frame.scale) +
                              " = --snap-tolerance x diagonal)");
  }
  for (int i = 0; i < ns; ++i)
    for (int j = 0; j < i; ++j)
      if ((S.row(i) - S.row(j)).norm() <= duplicate_distance)
        throw InvalidInputError(path + ": sites " + std::to_string(j + 1) + " and " + std::to_string(i + 1) +
                                " are duplicates (same point on the surface)");
  return sites;
}

}  // namespace heatcvt::cli
