#pragma once
/// \file tangential_relaxation.h
/// Tangential relaxation: every vertex towards the area-weighted centroid of its one-ring, in its
/// tangent plane, projected back to the surface.
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// How tangential_relaxation() moves the vertices on a border.
struct RelaxationBorder {
  /// false: like interior vertices (towards the ring's centroid, which draws the border in).
  /// true: along the chord of their two border neighbours, to the middle of the two (the
  /// border keeps its course and is resampled evenly); corners stay. Default false.
  bool slide = false;
  /// With `slide` or `follow_sample_border`: a border vertex where the border turns by more than
  /// this is a corner. Default 40°.
  double corner_turn_deg = 40;
  /// A border vertex with border points of the samples within its border edges' mean length
  /// (SurfaceProjector::sample_border_mean(), the edge of a scan) moves along the chord of its
  /// two border neighbours to their middle, and across it onto the mean of those border points:
  /// the border follows the scan's edge, smoothed over one edge length, instead of being drawn
  /// in towards the ring's centroid. Border vertices with no border point that near (a hole of
  /// the mesh in sampled surface, a surface that is a mesh) move as `slide` says; corners (see
  /// corner_turn_deg) with one stay. The move across is at most half the radius. Default false.
  bool follow_sample_border = false;
  /// With `follow_sample_border`: the radius is at most this many mean edge lengths of the mesh.
  /// Default 1.5.
  double max_follow_radius = 1.5;
  /// A face with a corner on the border whose smallest angle falls below this and below its own
  /// smallest angle before the step has the moves of its corners undone: the ring check sees
  /// orientation only, so corners moving together (on two border stretches closer than a
  /// spacing) can narrow a face to a sliver without turning it over, and no later flip or polish
  /// can widen it along the border. Interior faces are left to the flips. 0 = off, as in the
  /// sizing's and the creases' relaxations, where it measured worse (docs/benchmarks.md).
  /// Default 0; the relaxation polish passes PolishOptions::spoiled_border_angle_deg.
  double spoiled_angle_deg = 0;
};

/// One step of tangential relaxation: every vertex's move computed from the old positions (in
/// parallel), then kept, in index order, only if none of its triangles faces against its new
/// normal with the moves kept so far; last, the moves that spoil a face are undone
/// (RelaxationBorder::spoiled_angle_deg). Vertices v with (*fixed)[v] stay. `threads`: 0 = all
/// cores; the result does not depend on it.
void tangential_relaxation(WorkingMesh& mesh, const SurfaceProjector& surface, int threads = 0,
                           const RelaxationBorder& border = {}, const std::vector<char>* fixed = nullptr);

}  // namespace heatcvt
