#pragma once
/// \file dual_candidates.h
/// Candidate triangles of the dual of a Voronoi diagram on a surface (paper §8, METHOD.md §7):
/// triples of sites witnessed by the diagram, oriented by the sites' normals and split into
/// those that span one sheet of the surface and "loose" ones (rims of thin parts).
#include <Eigen/Core>
#include <vector>

#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Options of dual_candidates().
struct DualCandidateOptions {
  /// A Voronoi vertex where more than this many cells meet is ignored (every triple of its cells
  /// would be a candidate). Default 6.
  int max_cells_per_voronoi_vertex = 6;
  /// A candidate spans one sheet when its normal has a dot product above this with the unit
  /// normal of each of its three sites (about 75°): one whose sites disagree bridges a thin gap
  /// or folds the surface. Default 0.25.
  double coherent_min_dot = 0.25;
  /// Candidates failing that test but above this dot (about 107°) are kept aside as "loose":
  /// the dual triangles that turn around the rim of a part thinner than the site spacing, tried
  /// only to close holes (add_compatible_candidates()). Default −0.3.
  double loose_min_dot = -0.3;
};

/// A candidate triangle, oriented so that its normal agrees with the sum of its sites' normals.
struct DualCandidate {
  MeshFace f;
  int witnesses = 0;     ///< local triangles + Voronoi vertices that witness it
  int vv_witnesses = 0;  ///< of which Voronoi vertices
  double quality = 0;    ///< smallest angle (radians)
};

/// Candidates by category, each ordered for greedy extraction: most witnesses first, then best
/// smallest angle, then by vertex triple.
struct DualCandidates {
  std::vector<DualCandidate> coherent;
  std::vector<DualCandidate> loose;
};

/// Cell of each of the first `num_points` vertices of the tessellated mesh (−1 when none).
std::vector<int> cell_labels(const VoronoiDiagram& D, int num_points);

/// Candidates of the dual of the diagram D on a triangulated point set: every triangle of T
/// (#T by 3 point indices) whose three corners have three different labels (`label`, one per
/// point), and every triple of cells at each Voronoi vertex of D, witnesses the triangle of those
/// three sites. Sites are the vertices of `mesh` (positions and normals; no faces needed).
DualCandidates dual_candidates(const Eigen::MatrixX3i& T, const std::vector<int>& label, const VoronoiDiagram& D,
                               const WorkingMesh& mesh, const DualCandidateOptions& options = {});

/// Candidates from a ready-made dual triangulation F (#F by 3 vertex indices of `mesh`; e.g.
/// CvtResult::dual): each distinct triangle is witnessed once per occurrence.
DualCandidates dual_candidates_from_faces(const Eigen::MatrixX3i& F, const WorkingMesh& mesh,
                                          const DualCandidateOptions& options = {});

}  // namespace heatcvt
