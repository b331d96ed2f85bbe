#pragma once
/// \file hole_filling.h
/// Filling the holes the extraction leaves (cells whose dual triangles were rejected, tips of
/// thin parts) while keeping the real boundaries of open scans.
#include <vector>

#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of fill_holes(). h is the mean edge length of a loop.
struct HoleFillingOptions {
  /// Boundary loops of at most this many edges are holes of the extraction: always filled.
  /// Default 8.
  int max_hole_edges = 8;
  /// Loops of up to this many times max_hole_edges edges are filled when their centre is more
  /// than `clearance`·h from every triangle yet within `sample_gap`·h of the sampled surface (a
  /// hole in sampled surface, not the border of a scan). Default 4.
  int sampled_hole_factor = 4;
  double clearance = 0.25;   ///< Default 0.25.
  double sample_gap = 0.5;   ///< Default 0.5.
  /// Loops of up to this many times max_hole_edges edges are filled when, for at least
  /// `surrounded_fraction` of their edges, the surface is sampled within `sample_gap` edge
  /// lengths of the point one edge length outward (in the plane of the edge's triangle): the
  /// surface continues beyond the loop (around the tip of a thin part only the edges facing the
  /// tip find it; across the border of an open scan none does). Default 8.
  int surrounded_hole_factor = 8;
  double surrounded_fraction = 0.3;  ///< Default 0.3.
  /// Rounds of "find loops, fill, make the vertices manifold again". Default 3.
  int passes = 3;
};

/// Max-min-angle triangulation (dynamic programming over the polygon) of the loop of vertices
/// `loop` of `mesh`, avoiding diagonals that are already edges of the mesh. The triangles are
/// oriented against the loop's direction (a boundary loop followed along its faces' half-edges
/// is closed by triangles facing the same way as those faces). Returns false when no such
/// triangulation exists.
bool triangulate_loop(const WorkingMesh& mesh, const std::vector<int>& loop, std::vector<MeshFace>& out);

/// Boundary loops of the mesh (followed along the faces' half-edges) that are simple and pass
/// the tests above are triangulated; then make_vertices_manifold(). Returns the loops filled;
/// faces removed by make_vertices_manifold() are added to `removed`.
int fill_holes(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& options,
               const ManifoldOptions& manifold, int& removed);

}  // namespace heatcvt
