#pragma once
/// \file heatcvt.h
/// Umbrella header of the core library (target heatcvt::heatcvt; Eigen in, Eigen out, no PCL,
/// CGAL or CHOLMOD types) and the one-call API for users who just want a result:
///
///   heat_voronoi_diagram()  heat Voronoi cells of sites on a triangle mesh  (paper §4)
///   heat_centroids_of()     the cells and their heat centroids               (paper §5)
///   remesh_cvt()            CVT remeshing of a triangle mesh (= `meshcvt`; remesh.h) (paper §7.1)
///   reconstruct_surface()   mesh from a point cloud (= `cloud2mesh`; reconstruct.h) (paper §8)
///
/// Every function takes an options struct whose defaults are documented below (the same as the
/// corresponding tool's --help) and throws heatcvt::InvalidInputError on bad input and
/// heatcvt::SolverError if the heat matrix M − tL cannot be factored (errors.h).
/// The building blocks (Laplacians, HeatSolver, localized solves, tessellation, centroids, CVT,
/// dual mesh, I/O, validation) are in the headers included here. PCL users: heatcvt/pcl/*.h.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "heatcvt/adaptive_sizing.h"
#include "heatcvt/centroid.h"
#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/flying_pixels.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/localized_solve.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/normalize.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"
#include "heatcvt/point_laplacian.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/remesh.h"
#include "heatcvt/scan_merge.h"
#include "heatcvt/shapes.h"
#include "heatcvt/subdivision.h"
#include "heatcvt/validate.h"
#include "heatcvt/vertex_attributes.h"
#include "heatcvt/voronoi.h"
#include "heatcvt/weld.h"

namespace heatcvt {

/// Options of heat_voronoi_diagram() and heat_centroids_of().
struct HeatDiagramOptions {
  /// t = time_coefficient · h̄² (h̄ = mean edge length; paper §2, eq. 7). > 0. Default 1.
  double time_coefficient = 1.0;
  /// Cut faces exactly along the bisectors (eq. 20). Default true.
  bool exact = true;
  /// Threads; 0 = all hardware threads. Results do not depend on it. Default 0.
  int threads = 0;
  /// Options of the centroids (heat_centroids_of() only): implicit steps, quadratic refinement.
  /// Default 1 step, refinement on.
  CentroidOptions centroid;
};

/// Heat Voronoi diagram of `sites` on the triangle mesh (paper §4, eq. 15–20): cotan Laplacian
/// (eq. 5–6), one factorisation of M − tL, one point-source diffusion per site (eq. 8), exact
/// tessellation.
///   mesh   V #V by 3, F #F by 3 (a valid triangle mesh)
///   sites  surface points (face + barycentric coordinates); a vertex v is any face containing v
///          with barycentric coordinate 1 at v's corner
/// Returns the refined mesh with one cell per site (VoronoiDiagram, voronoi.h).
/// \throw InvalidInputError (invalid mesh, no sites, site out of range); SolverError.
inline VoronoiDiagram heat_voronoi_diagram(const TriangleMesh& mesh, const std::vector<SurfacePoint>& sites,
                                           const HeatDiagramOptions& options = {}) {
  validate_mesh(mesh.V, mesh.F, "mesh");
  HeatSolverOptions solver_options;
  solver_options.time_coefficient = options.time_coefficient;
  solver_options.threads = options.threads;
  const HeatSolver solver(cotan_laplacian(mesh.V, mesh.F), solver_options);
  VoronoiOptions voronoi_options;
  voronoi_options.exact = options.exact;
  voronoi_options.threads = options.threads;
  return heat_voronoi(mesh.V, mesh.F, solver, sites, voronoi_options);
}

/// Result of heat_centroids_of().
struct HeatCentroids {
  VoronoiDiagram diagram;              ///< the heat Voronoi diagram of the sites
  std::vector<SurfacePoint> centroids; ///< #sites heat centroids; face −1 for an empty cell
  Eigen::MatrixX3d positions;          ///< #sites by 3 centroid positions (NaN rows for empty cells)
};

/// Heat Voronoi cells of `sites` and their heat centroids c_i = argmax_y ∫_{C_i} k(t, x, y) dx
/// (paper §5, eq. 21–23; area sources eq. 10–11; sub-vertex refinement of §7.1). One Lloyd step
/// moves the sites to `positions`. Same inputs and errors as heat_voronoi_diagram().
inline HeatCentroids heat_centroids_of(const TriangleMesh& mesh, const std::vector<SurfacePoint>& sites,
                                       const HeatDiagramOptions& options = {}) {
  validate_mesh(mesh.V, mesh.F, "mesh");
  HeatSolverOptions solver_options;
  solver_options.time_coefficient = options.time_coefficient;
  solver_options.threads = options.threads;
  const HeatSolver solver(cotan_laplacian(mesh.V, mesh.F), solver_options);
  VoronoiOptions voronoi_options;
  voronoi_options.exact = options.exact;
  voronoi_options.threads = options.threads;
  HeatCentroids out;
  out.diagram = heat_voronoi(mesh.V, mesh.F, solver, sites, voronoi_options);
  CentroidOptions centroid_options = options.centroid;
  if (centroid_options.threads == 0) centroid_options.threads = options.threads;
  out.centroids = heat_centroids(mesh.V, mesh.F, solver, out.diagram, centroid_options);
  out.positions.resize(static_cast<Eigen::Index>(out.centroids.size()), 3);
  for (std::size_t i = 0; i < out.centroids.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    if (out.centroids[i].face >= 0)
      out.positions.row(row) = position(mesh.V, mesh.F, out.centroids[i]).transpose();
    else
      out.positions.row(row).setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

}  // namespace heatcvt
