#pragma once
/// \file cvt/lloyd.h
/// The state of the heat Lloyd iteration of §7.1 (localized as in §6): per site a point-source
/// diffusion over its cell and a few rings of neighbouring cells → heat field → cells of the
/// faces (face_clipper.h) → per cell an area-source diffusion (eq. 10–11) → hottest vertex →
/// quadratic refinement → over-relaxed or Anderson-mixed step; empty cells are revived and
/// sites can be inserted between iterations (quality control, cvt/quality.h).
#include <Eigen/Core>
#include <limits>
#include <utility>
#include <vector>

#include "heatcvt/cvt.h"
#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/localized_solve.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Population variance of x (0 when empty): the energy proxy of the over-relaxation safeguard
/// when x holds the cell areas.
double population_variance(const Eigen::VectorXd& x);

/// Neighbourhoods of a diagram: per cell its vertices (sorted) and its neighbouring cells (sorted).
struct CellNeighbourhoods {
  std::vector<std::vector<int>> vertices;
  std::vector<std::vector<int>> adjacency;
};

/// Neighbourhoods of vertex labels (e.g. graph_voronoi() or restricted_labels()): cells are
/// neighbours when an edge joins them. Labels < 0 are ignored.
CellNeighbourhoods cells_from_labels(const EdgeGraph& g, const std::vector<int>& label, int num_cells);

/// What a Lloyd iteration needs from the diagram of a heat field: neighbourhoods (a cell's
/// vertices are the corners of the faces it touches), areas and load vectors (eq. 10–11, exact on
/// the clipped pieces of each face).
struct IterationCells {
  CellNeighbourhoods cells;
  std::vector<std::vector<std::pair<int, double>>> loads;  ///< per cell (vertex, ∫ φ_vertex), sorted
  Eigen::VectorXd area;                                    ///< per cell
};

/// Cells of the field's diagram, every face clipped by clip_face() (the tie rule of eq. 19).
///   face_area #F; face_scale #F metric / Euclidean area (empty = 1: loads in the Euclidean
///   metric; areas are always Euclidean). blocks_per_thread: load balance only.
IterationCells iteration_cells(const HeatField& field, const Eigen::MatrixX3i& F, const Eigen::VectorXd& face_area,
                               const Eigen::VectorXd& face_scale, int num_sites, int threads,
                               int blocks_per_thread = 64);

/// The sites of a heat Lloyd iteration with everything carried from one iteration to the next.
class LloydState {
 public:
  /// `cells`: neighbourhoods of the start sites (graph or restricted cells); `rings`: Voronoi
  /// rings to start with. The surface, solver and options must outlive the state.
  LloydState(const CvtSurface& surface, const LocalizedSolver& local, const CvtOptions& options,
             const Eigen::VectorXd& face_scale, double spacing, int threads, std::vector<SurfacePoint> sites,
             CellNeighbourhoods cells, int rings);

  int num_sites() const { return static_cast<int>(sites_.size()); }
  const std::vector<SurfacePoint>& sites() const { return sites_; }
  Eigen::MatrixX3d positions() const;
  int rings() const { return rings_; }

  /// Localized point-source diffusion of every site over its cell and `rings` rings of cells
  /// (voronoi_rings_settled for settled sites; a graph ball for an empty cell), eq. 8, then the
  /// keep_sites_per_vertex hottest sites per vertex (heat_field_from_sparse()). `mean_index_set`
  /// receives the mean |I|.
  HeatField heat_field(double* mean_index_set);

  /// One Lloyd step from the field of the current sites: cells, heat centroids, revival of empty
  /// cells, accelerated step, settled flags; fills the timing-free fields of `st` (area variance,
  /// moves, revived sites, ω, Anderson columns, residual) and tessellate_seconds/centroid_seconds.
  void step(const HeatField& field, CvtIterationStats& st);

  /// Appends sites (inserted by quality control): the new ones have empty neighbourhoods, every
  /// site becomes unsettled, the over-relaxation safeguard restarts, and with `full_rings` the
  /// Voronoi diffusions go back to voronoi_rings (else the ring count is kept).
  void add_sites(const std::vector<SurfacePoint>& added, bool full_rings);

  /// Replaces the sites (same count) and their neighbourhoods (e.g. after a surface Lloyd).
  void reset_sites(std::vector<SurfacePoint> sites, CellNeighbourhoods cells, int rings);

  /// Prepares the final diagram: returns true when the last heat_field() already used
  /// voronoi_rings for every site; afterwards every site gets voronoi_rings.
  bool full_rings_field_ready();

 private:
  void heat_centroids(const IterationCells& ic, std::vector<SurfacePoint>& moved);
  int revive_empty_cells(IterationCells& ic, std::vector<SurfacePoint>& moved) const;
  void accelerated_step(const IterationCells& ic, std::vector<SurfacePoint>& moved, CvtIterationStats& st);
  void finish_step(std::vector<SurfacePoint>& moved, CvtIterationStats& st);
  void resize_scratch();

  struct ThreadScratch {
    LocalizedWorkspace ws;
    std::vector<unsigned char> mark;   // vertex marks (zero between uses)
    std::vector<unsigned char> cmark;  // cell marks
    std::vector<int> cells, frontier, next;
    Eigen::VectorXd heat;              // dense heat, zero between uses
    std::vector<double> dist;          // Dijkstra, +inf between uses
    std::vector<int> touched;
    std::vector<std::pair<int, double>> rhs;
    std::vector<double> values;
  };
  void ring_cells(int cell, int rings, ThreadScratch& t) const;
  void union_vertices(ThreadScratch& t, std::vector<int>& out) const;
  void dijkstra_ball(int face, double radius, ThreadScratch& t, std::vector<int>& out) const;

  const CvtSurface& surface_;
  const LocalizedSolver& local_;
  const CvtOptions& options_;
  Eigen::VectorXd face_scale_;
  Eigen::MatrixX3d normals_;
  double spacing_;
  int threads_;
  std::vector<SurfacePoint> sites_;
  CellNeighbourhoods cells_;
  int rings_;
  std::vector<char> settled_;
  std::vector<ThreadScratch> scratch_;
  std::vector<std::vector<int>> indices_;
  std::vector<std::vector<double>> values_;
  double omega_;
  double previous_variance_ = std::numeric_limits<double>::infinity();
  struct Anderson {
    std::vector<Eigen::VectorXd> dF, dG;
    Eigen::VectorXd f_prev, g_prev;
    double residual_prev = std::numeric_limits<double>::infinity();
  } aa_;
};

}  // namespace heatcvt
