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

/// Options of star_candidates().
struct StarCandidateOptions {
  /// Compute them at all. Default true.
  bool enabled = true;
  /// Sites around each site whose tangent-plane Delaunay triangulation gives its star. Default 12
  /// (two rings of a centroidal tessellation).
  int neighbors = 12;
  /// Only neighbours whose normal has at least this dot product with the site's take part (the
  /// other side of a thin part, or a surface crossing at a steep angle, stays out). Default 0.5.
  double min_normal_dot = 0.5;
};

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
  /// The sites' own tangent-plane Delaunay stars, tried after the diagram's candidates
  /// (star_candidates()).
  StarCandidateOptions stars;
  /// Threads of the star computation; 0 = all cores. Default 0.
  int threads = 0;
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
  std::vector<DualCandidate> star;  ///< star_candidates() (with options.stars.enabled)
};

/// Cell of each of the first `num_points` vertices of the tessellated mesh (−1 when none).
std::vector<int> cell_labels(const VoronoiDiagram& D, int num_points);

/// Candidates of the dual of the diagram D on a triangulated point set: every triangle of T
/// (#T by 3 point indices) whose three corners have three different labels (`label`, one per
/// point), and every triple of cells at each Voronoi vertex of D, witnesses the triangle of those
/// three sites. Sites are the vertices of `mesh` (positions and normals; no faces needed).
DualCandidates dual_candidates(const Eigen::MatrixX3i& T, const std::vector<int>& label, const VoronoiDiagram& D,
                               const WorkingMesh& mesh, const DualCandidateOptions& options = {});

/// Candidates from the sites alone: the star of each site in the Delaunay triangulation of it
/// and its nearest sites, projected onto its tangent plane (normal mesh.N). A triangle is
/// witnessed once by each of its corners whose star holds it. Where the diagram's own witnesses
/// are missing or were rejected (noisy or cluttered scans: cells torn by depth jumps, flying
/// pixels, layered depth), these are the triangles of the sites' local Delaunay triangulation,
/// which a centroidal site set makes about equilateral. Only coherent ones (as in
/// dual_candidates()) are returned, ordered like them.
std::vector<DualCandidate> star_candidates(const WorkingMesh& mesh, const StarCandidateOptions& options,
                                           const DualCandidateOptions& coherence, int threads = 0);

/// Candidates from a ready-made dual triangulation F (#F by 3 vertex indices of `mesh`; e.g.
/// CvtResult::dual): each distinct triangle is witnessed once per occurrence.
DualCandidates dual_candidates_from_faces(const Eigen::MatrixX3i& F, const WorkingMesh& mesh,
                                          const DualCandidateOptions& options = {});

}  // namespace heatcvt
