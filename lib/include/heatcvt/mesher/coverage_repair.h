#pragma once
/// \file coverage_repair.h
/// Coverage repair: vertices moved back onto the parts of the surface that the mesh no longer
/// reaches. Tangential relaxation and the angle polish move each vertex towards the middle of its
/// ring and project it back onto the surface; at a tip, a ridge sharper than the vertex spacing
/// or the bottom of a narrow cavity that pulls the vertices off the extreme point, and the mesh
/// then cuts the tip off (the one-sided distance from the surface to the mesh grows). This step
/// takes the surface's samples farthest from the mesh and moves the nearest mesh vertex onto each
/// (or part of the way), where its triangles keep their shape and orientation.
#include <Eigen/Core>
#include <vector>

#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of repair_coverage().
struct CoverageRepairOptions {
  /// A sample farther than this many vertex spacings from the mesh is uncovered. Default 0.5.
  double max_gap = 0.5;
  /// A move is kept only where the smallest angle of the moved vertex's triangles stays at least
  /// min(this, its value before the move). Default 30°.
  double min_angle_deg = 30;
  /// ... and none of these triangles turns by more than this. Default 45°.
  double max_turn_deg = 45;
  /// Fractions of the way to the sample tried for a vertex, first to last (the first kept wins).
  /// Default {1, 0.75, 0.5}.
  std::vector<double> fractions{1.0, 0.75, 0.5};
  /// Where no fraction keeps the vertex's triangles within the bounds (a tip sharper than the
  /// vertex's ring can follow alone), the fractions are tried again with the vertex's ring
  /// neighbours (those not fixed) moved by this fraction of its displacement, each projected to
  /// the surface; the bounds then hold for every face of a moved vertex. 0 = the vertex alone.
  /// Default 0.5.
  double ring_drag = 0.5;
  /// Rounds (distances measured again after each). Default 4.
  int rounds = 4;
  /// A round can widen the largest gap (a dragged ring uncovers samples next to the one it
  /// reaches): with this, the mesh is left as it was after the round with the narrowest largest
  /// gap (as given, where none narrowed it); without, as the last round left it. Default false:
  /// neither path turns it on. On the cloud path the samples are noisy CVT points, and the round
  /// whose farthest point is nearest measured worse against the true surface. In meshcvt it
  /// changed two rows of 30 at 500 sites (one better, one worse), and its narrower start left the
  /// crease snap on a thin plate beyond max_crease_gap_growth (docs/benchmarks.md).
  bool keep_narrowest_round = false;
  /// Growth: a sample still farther than this many vertex spacings after the move rounds lies on
  /// a part longer than moving vertices can reach (a finger or a claw a few spacings long, cut
  /// off whole). The edge of its nearest face nearest to it is split, the new vertex moved
  /// towards it (the largest of `fractions`, by at most grow_step, that keeps the faces around at
  /// or above min(min_angle_deg, their smallest angle before) after max-min-angle flips there,
  /// with no face at it folded over its neighbour: a dihedral angle above 120°), and the move
  /// rounds run again, so the new vertices walk out along the part.
  /// 0 = no growth. Default 0: ReconstructionOptions::coverage turns it on (1 spacing); meshcvt
  /// keeps it off (at 1,000 sites it cost two shared meshes their φmin of 30° and no row gained a
  /// target: docs/benchmarks.md).
  double grow_gap = 0;
  /// ... adding at most this fraction of the vertices in faces in all (the count stays within
  /// the 2 % the tools allow). Default 0.005.
  double max_grown_fraction = 0.005;
  /// ... moving each new vertex by at most this many spacings (a long part grows over several
  /// rounds, each new vertex a step beyond the last). On the 50k acceptance clouds armadillo's
  /// longest claw came within 0.0226 / 0.0210 / 0.0178 of the diagonal at 0.75 / 1 / 1.5, every
  /// other row the same (docs/benchmarks.md). Default 1.5.
  double grow_step = 1.5;
  /// ... in at most this many growth rounds (each followed by the move rounds). Default 8.
  int grow_rounds = 8;
  /// Where more than this fraction of the samples is uncovered before the repair, the mesh
  /// misses whole sheets or pieces (the two faces of a thin plate meshed as one, a part the
  /// extraction left out), not tips: no move can reach them, and every such sample would be
  /// tried in every round (the cost grows with their number, the gain is none). The repair then
  /// leaves the mesh as it is (CoverageRepairStats::skipped). Default 0.2 (docs/benchmarks.md).
  double max_uncovered_fraction = 0.2;
};

/// What repair_coverage() did.
struct CoverageRepairStats {
  int uncovered_before = 0;  ///< samples farther than max_gap spacings before the repair
  int uncovered_after = 0;   ///< and after it
  int moves = 0;             ///< vertex moves kept (a dragged ring neighbour counts as one)
  int inserted = 0;          ///< vertices added by the growth (CoverageRepairOptions::grow_gap)
  double gap_before = 0;     ///< largest distance from a sample to the mesh, before and after
  double gap_after = 0;
  /// No move was tried: more than max_uncovered_fraction of the samples was uncovered.
  bool skipped = false;
  /// The largest distance after each round that moved a vertex, in order.
  std::vector<double> round_gaps;
};

/// Moves vertices of `mesh` towards the samples farther than options.max_gap · `spacing` from it
/// (farthest first, each vertex at most once per round): the corner of the sample's nearest face
/// that is nearest the sample goes onto it (projected through `surface`), or the largest of
/// options.fractions of the way that keeps the vertex's triangles within the angle and turn
/// bounds and facing along its normal; failing that, the same with its ring dragged along
/// (options.ring_drag). Border vertices and vertices with (*fixed)[v] stay. The rounds run
/// until none moves a vertex or options.rounds; the result is the last round's state or, with
/// options.keep_narrowest_round, the narrowest one's, and the stats describe that state.
/// `samples` are points on the surface (an input mesh's vertices).
CoverageRepairStats repair_coverage(WorkingMesh& mesh, const SurfaceProjector& surface,
                                    const Eigen::MatrixX3d& samples, double spacing,
                                    const CoverageRepairOptions& options = {},
                                    const std::vector<char>* fixed = nullptr);

}  // namespace heatcvt
