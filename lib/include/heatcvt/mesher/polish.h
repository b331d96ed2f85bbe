#pragma once
/// \file polish.h
/// The polish stages of the surface mesher: tangential relaxation alternating with edge flips
/// (with a fallback when valence flips fold a thin part through itself), then the angle polish
/// alternating with max-min-angle flips, each undone where it makes the mesh self-intersect.
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/tips.h"
#include "heatcvt/mesher/untangle.h"
#include "heatcvt/mesher/valence3_removal.h"

namespace heatcvt {

/// Options of relaxation_polish() and angle_polish_stage().
struct PolishOptions {
  /// Iterations of tangential relaxation, each followed by flips (valence-equalising in all but
  /// the last two, max-min-angle in the last two). 0 = no polish at all (angle polish, sliver
  /// collapse and long-edge split are skipped too). Default 10.
  int relaxation_iterations = 10;
  /// Passes of max-min-angle flips on the extracted mesh before the polish. Default 20.
  int initial_flip_passes = 20;
  /// Passes of each flip step inside the polish. Default 5.
  int flip_passes = 5;
  FlipOptions flips;  ///< angles of the flip rules (max_passes and valence_mode are set per call)
  /// In the relaxation, border vertices near the edge of the samples follow it
  /// (RelaxationBorder::follow_sample_border): the border of an open scan is not drawn in.
  /// Surfaces without sample borders (an input mesh, a closed scan) are not affected. false =
  /// border vertices move like the others. Default true.
  bool follow_sample_border = true;
  /// In the relaxation, the moves that narrow a face with a corner on the border below this
  /// angle (and below its angle before the step) are undone (RelaxationBorder::spoiled_angle_deg):
  /// a triangle bridging two border stretches closer than a spacing is otherwise laid flat, and
  /// no flip can widen it. 0 = off. Default 0: on the shared scans, whose borders follow the
  /// samples' noisy edge, it measured no better (docs/benchmarks.md); RemeshOptions (an input
  /// mesh's exact border) sets 20°.
  double spoiled_border_angle_deg = 0;
  /// Angle polish: attempts (each after the previous one self-intersected, with the vertices of
  /// the intersecting faces and their neighbours held fixed). Default 3.
  int angle_attempts = 3;
  int angle_cycles = 4;        ///< angle polish + flips cycles per attempt. Default 4.
  int angle_rounds = 2;        ///< angle_polish() rounds per cycle. Default 2.
  AnglePolishOptions angle;
  Valence3Options valence3;
  /// Tips of thin parts (tip_vertices(), found once at the start of each stage) stay where they
  /// are: not moved by the relaxation or the angle polish, not removed as valence-3 vertices.
  TipOptions tips;
  int threads = 0;  ///< 0 = all cores; results do not depend on it. Default 0.
};

/// Tips (PolishOptions::tips) are held in every step below.
/// Removes valence-3 vertices, flips to max-min-angle, then polishes: tangential relaxation +
/// flips. If the result self-intersects it is untangled; if it still does, the polish is redone
/// from the unpolished mesh with max-min-angle flips only (stats.polish_fallback) and untangled.
void relaxation_polish(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& options,
                       const UntangleOptions& untangling, const HoleFillingOptions& holes,
                       const ManifoldOptions& manifold, MesherStats& stats);

/// Angle polish cycles (valence-3 removal, then angle_polish() + max-min-angle flips); where the
/// result self-intersects it is redone from the same start with the vertices of the intersecting
/// faces and their neighbours frozen, and undone after the last attempt
/// (stats.angle_polish_undone).
void angle_polish_stage(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& options,
                        MesherStats& stats);

}  // namespace heatcvt
