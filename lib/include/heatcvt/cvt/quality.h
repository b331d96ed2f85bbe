#pragma once
/// \file cvt/quality.h
/// Quality control of a CVT (CvtOptions::quality_every and what hangs on it): evaluation of the
/// current sites (exact diagram, dual, φmin/φm, non-manifold spots), the quality targets and the
/// patience test, splitting of cells too big for thin parts, and refinement at Voronoi vertices
/// dual to small-angle triangles.
#include <Eigen/Core>
#include <vector>

#include "heatcvt/cvt.h"
#include "heatcvt/cvt/lloyd.h"
#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Cells at non-manifold spots of a dual triangulation with `num_sites` vertices: an edge with
/// more than two triangles (or, when `closed`, a boundary edge), a vertex whose triangles do not
/// form one fan, a site without triangles (dual.unused_sites). Sorted; `spots` receives the
/// number of spots.
std::vector<int> nonmanifold_cells(const DualMesh& dual, int num_sites, bool closed, int* spots);

/// Edge topology of a triangle mesh: closed (every edge has ≥ 2 faces) and manifold edges
/// (every edge has ≤ 2 faces).
struct EdgeTopology {
  bool closed = true;
  bool manifold_edges = true;
};
EdgeTopology edge_topology(const Eigen::MatrixX3i& F, int num_vertices);

/// New sites splitting the `bad` cells of a field's diagram: each at the cell's vertex farthest
/// from its site (P: #sites by 3 positions; cells = hottest site per vertex), skipped when closer
/// than `min_distance`.
std::vector<SurfacePoint> split_cells(const CvtSurface& surface, const HeatField& field, const Eigen::MatrixX3d& P,
                                      const std::vector<int>& bad, double min_distance);

/// New sites at the Voronoi vertices dual to the triangles of `dual` whose smallest angle is
/// below `phi_min_deg` (circumcentre insertion of Delaunay refinement, placed where the three
/// heat cells meet in `diagram`, snapped to the nearest input vertex): worst triangles first
/// (ties: triangle index), at most `count` Voronoi vertices, duplicates merged.
std::vector<SurfacePoint> small_angle_sites(const CvtSurface& surface, const VoronoiDiagram& diagram,
                                            const DualMesh& dual, double phi_min_deg, int count);

/// The quality control of one centroidal_voronoi() run: keeps the last evaluation, the heat field
/// it computed (the next iteration's Voronoi step), the safeguard of the splitting and the
/// patience bookkeeping.
class CvtQualityControl {
 public:
  CvtQualityControl(const CvtSurface& surface, const CvtOptions& options, int initial_sites, double spacing,
                    int threads);

  /// Evaluates the current sites of `lloyd` after iteration `it` (0 = the start sites): exact
  /// diagram + dual, φmin/φm and spots into `st`, the target test, and (split_nonmanifold_cells,
  /// it < options.iterations, within the budget) splitting of the cells at non-manifold spots
  /// into `lloyd` (st.inserted_sites, result.inserted_sites). Returns true when the targets are
  /// met; the evaluated diagram and dual are then result.diagram / result.dual.
  bool evaluate(LloydState& lloyd, CvtIterationStats& st, int it, CvtResult& result);

  /// refine_small_angles after a start evaluation that only missed φmin: adds small_angle_sites()
  /// of the last evaluation to `lloyd` (at most refine_fraction_per_round of the sites, within
  /// the budget). Returns the number added.
  int refine_small_angles(LloydState& lloyd, CvtResult& result);

  /// True when the last evaluation only missed φmin (φm met, no spot) and refinement is on.
  bool only_phi_min_missed(const CvtIterationStats& st) const;

  /// The heat field the last evaluation computed for the current sites, if still valid (moved out).
  bool take_field(HeatField& field, double& seconds, double& mean_index_set);
  bool has_field() const { return have_field_; }
  void drop_field() { have_field_ = false; }

  /// quality_patience: evaluations since φm last improved by more than patience_gain_deg.
  void reset_patience() { evaluations_since_best_ = 0; }
  bool patience_exhausted() const {
    return options_.quality_patience > 0 && evaluations_since_best_ >= options_.quality_patience;
  }
  /// No more cells split from here on (split_nonmanifold_cells): the next evaluation adds no site.
  void stop_splitting() { split_enabled_ = false; }

 private:
  int budget(const CvtResult& result) const;

  const CvtSurface& surface_;
  const CvtOptions& options_;
  int initial_sites_;
  double spacing_;
  int threads_;
  bool closed_input_ = false, split_enabled_ = false, check_spots_ = false;
  int fewest_spots_;
  double best_phi_mean_ = -1;
  int evaluations_since_best_ = 0;
  int last_bad_spots_ = 0;
  VoronoiDiagram last_diagram_;  // the last evaluation's diagram and dual when it missed the targets
  DualMesh last_dual_;
  HeatField field_;
  bool have_field_ = false;
  double field_seconds_ = 0, field_index_ = 0;
};

}  // namespace heatcvt
