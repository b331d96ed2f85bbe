#pragma once
/// \file natural_neighbour.h
/// Natural-neighbour coordinates by area stealing on heat Voronoi diagrams (paper §7.2,
/// Fig. 10–11): skinning weights of handles and interpolation of values given at sites.
///
/// Sites p_1..p_n on a surface have heat Voronoi cells C_i (exact tessellation, voronoi.h) of
/// area a_i. Inserting a query point q as an extra site gives new areas ã_i and a_q, and
///     b_i(q) = (a_i − ã_i) / a_q = area(C_q ∩ C_i) / area(C_q)            ("area stealing").
/// The heat of the old sites does not change when q is inserted (one linear diffusion per
/// site), so the new cell is C_q = {x : u_q(x) ≥ max_i u_i(x)} (ties go to q) and only the faces
/// where q's heat competes are clipped: the area q steals from C_i is measured per face by
/// clipping the face with the half-planes u_q ≥ u_j and u_i ≥ u_j (every u is linear on a face).
/// Properties: b_i ≥ 0, Σ_i b_i = 1, b_i(p_j) = δ_ij, b_i(q) = 0 exactly when C_q does not
/// reach C_i (locality), continuous in q.
///
/// All vertices at once (skinning weights): one exact query costs a diffusion from q plus the
/// clipping; with few sites the cells are large and nothing localises (the paper: ~1.1 ms per
/// vertex on 4 cores, about a minute for 55k vertices). vertex_weights() therefore computes the
/// coordinates exactly at a farthest-point sample of vertices (the sites' nearest vertices
/// first) and propagates them to the other vertices by biharmonic interpolation
/// (min Σ xᵀ L M⁻¹ L x with the samples fixed, one sparse Cholesky factorisation for all sites),
/// then clamps, drops tiny weights and renormalises. The paper suggests exactly this ("compute
/// on a coarse mesh and propagate"). vertex_weights_direct() is the exact per-vertex computation.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Options of NaturalNeighbourCoordinates.
struct NaturalNeighbourOptions {
  /// t = time_coefficient · h̄² (h̄ = mean edge length), as everywhere in the paper. Default 1.
  double time_coefficient = 1.0;
  /// Threads for the solves and the per-query clipping; 0 = all hardware threads. Results do
  /// not depend on it. Default 0.
  int threads = 0;
  /// Sites kept per vertex in the heat field of the sites (voronoi.h). Default 8.
  int keep_sites_per_vertex = 8;
  /// vertex_weights(): number of farthest-point samples where the coordinates are computed
  /// exactly before being propagated; 0 = automatic: max(500, #V / 20), at most #V. Default 0
  /// (2,162 on the 43k-vertex armadillo; measured errors in bench_nncoords / README).
  int samples = 0;
  /// vertex_weights(): propagated weights below this value are set to 0 before renormalising
  /// (the biharmonic interpolation leaves small ripples where the exact weights are exactly 0).
  /// Default 1e-4.
  double drop_below = 1e-4;
  /// vertex_weights(): a check sample whose propagated weights differ from its exact ones by more
  /// than this gets its two vertex rings computed exactly. Default 2e-3.
  double refine_tolerance = 2e-3;
  /// Exact queries solved together (one block of right-hand sides). Default 64.
  int batch = 64;
};

/// One exact query (area stealing).
struct NaturalNeighbourQuery {
  /// Non-zero coordinates (site, b_i(q)) sorted by site; empty when no site reaches q
  /// (q on a connected component without sites).
  std::vector<std::pair<int, double>> weights;
  /// (site, area(C_q ∩ C_i)) for the same sites: the area q steals from each cell (a_i − ã_i).
  std::vector<std::pair<int, double>> stolen_area;
  /// a_q = area(C_q) = Σ stolen areas.
  double cell_area = 0;
};

/// Per-vertex weights: #V by #sites, row v holds the non-zero b_i(vertex v) (rows sum to 1,
/// empty rows for vertices no site reaches).
using VertexWeights = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Progress callback: (done, total) work units; called from the calling thread only.
using NaturalNeighbourProgress = std::function<void(long done, long total)>;

/// Natural-neighbour coordinates of a fixed set of sites on a triangle mesh. Factors M − tL once
/// (heat_solver.h), diffuses from every site once and tessellates (the base diagram); every query
/// afterwards is one diffusion plus local clipping. Thread-safe for concurrent const queries.
class NaturalNeighbourCoordinates {
 public:
  /// V #V by 3, F #F by 3, sites: ≥ 2 points on the surface (face + barycentric coordinates).
  /// \throw InvalidInputError on an invalid mesh, fewer than 2 sites, a site not on a face or
  ///        with non-finite / negative barycentric coordinates, bad options;
  ///        SolverError if M − tL cannot be factored.
  NaturalNeighbourCoordinates(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                              const std::vector<SurfacePoint>& sites, const NaturalNeighbourOptions& options = {});
  ~NaturalNeighbourCoordinates();
  NaturalNeighbourCoordinates(NaturalNeighbourCoordinates&&) noexcept;
  NaturalNeighbourCoordinates& operator=(NaturalNeighbourCoordinates&&) noexcept;

  int num_sites() const;
  int num_vertices() const;
  /// Heat Voronoi diagram of the sites (before any insertion); cell_area = a_i.
  const VoronoiDiagram& diagram() const;
  const HeatSolver& solver() const;
  const NaturalNeighbourOptions& options() const;

  /// Exact area-stealing coordinates at q (one full diffusion from q, clipping of the faces where
  /// q's heat competes). A q at a site's position returns that site with weight 1 exactly.
  /// \throw InvalidInputError if q is not on a face.
  NaturalNeighbourQuery query(const SurfacePoint& q) const;
  /// Same for many points: diffusions in blocks of options.batch right-hand sides, parallel.
  std::vector<NaturalNeighbourQuery> query(const std::vector<SurfacePoint>& points,
                                           const NaturalNeighbourProgress& progress = {}) const;

  /// Exact coordinates at every vertex (one query per vertex: slow for large meshes).
  VertexWeights vertex_weights_direct(const NaturalNeighbourProgress& progress = {}) const;
  /// Coordinates at every vertex, exact at options.samples farthest-point samples (plus the
  /// refinement below) and biharmonically propagated to the others (see the file comment).
  /// Adaptive: the weights propagated from the first 60 % of the samples are compared with the
  /// exact ones at the other 40 %; around every sample where they differ by more than
  /// options.refine_tolerance, its two vertex rings are computed exactly too (at most
  /// options.samples / 2 extra vertices); then everything is propagated again.
  /// Rows are ≥ 0 and sum to 1 (empty on components without sites).
  ///   exact_vertices: optional, receives the vertices computed exactly (sorted).
  VertexWeights vertex_weights(const NaturalNeighbourProgress& progress = {},
                               std::vector<int>* exact_vertices = nullptr) const;
  /// The first `count` farthest-point samples (graph distances, shrunk near the sites) in the
  /// order they are chosen, starting with the sites' nearest vertices.
  std::vector<int> farthest_point_samples(int count) const;

 private:
  std::vector<std::vector<std::pair<int, double>>> propagate(
      const std::vector<int>& samples, const std::vector<std::vector<std::pair<int, double>>>& exact) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Interpolates per-site values to the vertices: result = W · values
///   W #V by #sites (vertex_weights), values #sites by k; returns #V by k.
/// \throw InvalidInputError if values.rows() != W.cols() or values has NaN/inf.
Eigen::MatrixXd interpolate_site_values(const VertexWeights& W, const Eigen::MatrixXd& values);

}  // namespace heatcvt
