#pragma once
/// \file cvt/start.h
/// The start of a CVT (CvtOptions): initial sites (random or farthest-point), a cheap graph Lloyd
/// and a cheap surface Lloyd on them, all before (or while) the heat factor is computed.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/mesh.h"

namespace heatcvt {

enum class CvtInitialization;
struct CvtOptions;

/// Initial sites: area-uniform random points (seeded) or farthest-point sampling (graph geodesics).
/// With `vertex_density` (#V values ρ > 0, a CVT with density: cells of diameter ∝ ρ^(-1/4)) the
/// random points are drawn in proportion to area × ρ^(1/2) and the farthest points measure each
/// edge by its length × ρ^(1/4), so the start is already spread as the density asks.
/// \throw InvalidInputError if count < 1 (or > #V for farthest-point sampling), or a density of
/// the wrong size, not finite or not positive.
std::vector<SurfacePoint> initial_sites(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, int count,
                                        CvtInitialization method, std::uint32_t seed,
                                        const Eigen::VectorXd& vertex_density = Eigen::VectorXd());

/// The sites sorted by the Morton code of their positions (spatial_order.h): neighbouring cells
/// get neighbouring site numbers (CvtOptions::spatial_site_order).
std::vector<SurfacePoint> in_spatial_order(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                           std::vector<SurfacePoint> sites);

/// The generated start sites of a CVT run: initial_sites() with the options' count, method and
/// seed (and `vertex_density`), in_spatial_order() when options.spatial_site_order.
std::vector<SurfacePoint> generated_sites(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                          const CvtOptions& options,
                                          const Eigen::VectorXd& vertex_density = Eigen::VectorXd());

/// Graph Lloyd (CvtOptions::graph_lloyd_iterations): cells = graph_voronoi() of the sources,
/// new source = the vertex of the cell closest to the cell's area-weighted mean position
/// (`vertex_area` per vertex). At most `iterations`, stops when no source changes; `done`
/// receives the iterations run. Deterministic (ties: smaller index).
std::vector<int> graph_lloyd(const EdgeGraph& g, const Eigen::MatrixX3d& V, const Eigen::VectorXd& vertex_area,
                             std::vector<int> sources, int iterations, int* done);

/// Restricted-Voronoi labels of continuous sites at positions P (a cheap stand-in for the
/// geodesic cells of §7.1): every vertex takes the site at the smallest Euclidean distance among
/// the sites whose region, grown over the edge graph from the corners of the site's face,
/// reaches it first (Dijkstra order on the key |x_v − p_s|², ties by site, then vertex). Cells
/// are edge-connected, so thin parts and nearby sheets are not bridged. X: vertex positions.
/// `key` receives |x_v − p_label(v)|².
void restricted_labels(const EdgeGraph& g, const std::vector<Eigen::Vector3d>& X, const Eigen::MatrixX3i& F,
                       const std::vector<SurfacePoint>& sites, const std::vector<Eigen::Vector3d>& P,
                       std::vector<int>& label, std::vector<double>& key);

/// Update of restricted_labels() after the sites moved a little: each site claims the corners of
/// its face when it is the closest there, then Jacobi sweeps give every vertex the closest site
/// among its own and its neighbours' labels, on the vertices next to a change only, until nothing
/// changes. Deterministic for any thread count.
void update_restricted_labels(const EdgeGraph& g, const std::vector<Eigen::Vector3d>& X, const Eigen::MatrixX3i& F,
                              const std::vector<SurfacePoint>& sites, const std::vector<Eigen::Vector3d>& P,
                              std::vector<int>& label, std::vector<double>& key, int threads);

/// Options of surface_lloyd() (CvtOptions::surface_lloyd_* and CvtTuning).
struct SurfaceLloydOptions {
  int iterations = 0;           ///< at most this many iterations
  double tolerance = 0.01;      ///< stop when no site moved more than tolerance · spacing
  double mean_tolerance = 0;    ///< or when the mean move is below mean_tolerance · spacing (0 = off)
  double relaxation = 1.0;      ///< over-relaxation ω ∈ [1, 2)
  double spacing = 1.0;         ///< site spacing sqrt(area / sites), input units
  double max_extra_step = 0.5;  ///< the over-relaxed step goes at most this · spacing beyond the centroid
  double relaxation_decay = 0.5, relaxation_floor = 0.05;  ///< safeguard of ω (CvtTuning)
  int walk_max_steps = 256;     ///< project_local() limits
  double walk_min_gain = 1e-12;
};

/// Cheap surface Lloyd on the input mesh (CvtOptions::surface_lloyd_iterations): cells =
/// restricted_labels(), centroid = mean position of the restricted cell, weighted by the surface's
/// density where it has one (CvtSurface::face_mass) (faces on cell borders
/// clipped exactly by the Euclidean bisector planes with face_clipper.h, as eq. 20 clips by
/// heat), projected onto the surface by a greedy walk from the cell's vertex closest to it, with
/// over-relaxation ω (safeguarded by the lumped CVT energy Σ a_v |x_v − p_label(v)|²). Sites whose
/// cell is empty go to the vertex of the largest cell farthest from its site. `done` receives the
/// iterations run, `final_labels` (optional) the restricted cells of the returned sites.
/// `threads_now` is asked once per iteration (callers may add threads once a concurrent job has
/// finished); the result does not depend on it.
std::vector<SurfacePoint> surface_lloyd(const CvtSurface& surface, std::vector<SurfacePoint> sites,
                                        const SurfaceLloydOptions& options, int* done,
                                        std::vector<int>* final_labels, const std::function<int()>& threads_now);

/// SurfaceLloydOptions of a CVT run (spacing in input units).
SurfaceLloydOptions surface_lloyd_options(const CvtOptions& options, int iterations, double spacing);

/// What the start step produced besides the sites.
struct CvtStartReport {
  int graph_lloyd_iterations = 0;
  double graph_lloyd_seconds = 0;
  int surface_lloyd_iterations = 0;
  double surface_lloyd_seconds = 0;
  std::vector<int> labels;  ///< restricted cells of the surface-Lloyd sites (empty without it)
};

/// The start step of centroidal_voronoi(): initial sites when `sites` is empty (options.sites,
/// options.initialization, options.seed), then options.graph_lloyd_iterations of graph Lloyd
/// (sites moved to vertices) and, when `surface_on`, options.surface_lloyd_iterations of surface
/// Lloyd.
CvtStartReport cvt_start(const CvtSurface& surface, const CvtOptions& options, bool surface_on,
                         std::vector<SurfacePoint>& sites, const std::function<int()>& threads_now);

}  // namespace heatcvt
