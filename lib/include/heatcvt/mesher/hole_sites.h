#pragma once
/// \file hole_sites.h
/// Closing a hole with the sites inside it. Where the extraction (or a later repair) leaves a
/// hole, the sites of the cells there are still on the surface, in no triangle. A hole is closed
/// by a constrained Delaunay triangulation of its boundary loop and those sites, in the plane of
/// the loop's site normals: the hole gets the triangles the dual should have had there (about
/// equilateral, since the sites are centroidal), instead of a few long triangles across it that
/// leave the sites out and cut through the surface.
#include <vector>

#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of triangulate_hole_with_sites(). h is the mean edge length of the loop.
struct HoleSiteOptions {
  /// Use the unused sites inside holes at all. Default true.
  bool enabled = true;
  /// The loop has a plane to be seen from when the mean of its sites' unit normals is at least
  /// this long. Default 0.5.
  double min_mean_normal = 0.5;
  /// A site is inside the hole when its normal has at least this dot product with the loop's
  /// mean normal (the far side of a thin part faces away). Default 0.5 (60°).
  double min_normal_dot = 0.5;
  /// The triangulation is used only when each triangle's normal has more than this dot product
  /// with each of its corners' normals, the coherence rule of the dual's candidates (a plane
  /// across a depth jump would lift to steep slivers). Default 0.25.
  double min_triangle_dot = 0.25;
  /// ... and it lies within this many loop radii (largest distance of a loop vertex from the
  /// loop's centroid) of the loop's mean plane. Default 0.5.
  double max_height = 0.5;
  /// ... and, in that plane, at least this many h from every loop edge and from the sites
  /// already taken (closer ones would only give slivers). Default 0.3.
  double min_clearance = 0.3;
  /// A loop counts as sampled surface, to be closed whatever the hole policy, when it holds at
  /// least this fraction of the sites a hole of its area has at spacing h (area / (√3/2 h²)).
  /// Default 0.5.
  double sampled_fraction = 0.5;
};

/// How a boundary loop looks from the side its sites' normals point to.
enum class LoopShape {
  unknown,           ///< the normals cancel out (the open end of a tube): no plane to look from
  hole,              ///< a simple clockwise polygon: surface all around, the hole on its right
  outer_border,      ///< a simple counter-clockwise polygon: the border of a piece, nothing to fill
  not_simple         ///< the projection crosses itself (a hole across a fold or a thin part)
};

/// Inside sites of the loop and the hole's triangulation.
struct HoleTriangulation {
  LoopShape shape = LoopShape::unknown;
  std::vector<MeshFace> faces;      ///< oriented like the faces around the hole
  std::vector<int> interior_sites;  ///< candidate sites used inside the hole
  double expected_sites = 0;        ///< sites a hole of this area holds at spacing h
};

/// Triangulates the hole bounded by `loop` (vertices of `mesh` in the order of the faces'
/// half-edges: the hole lies on their right) together with those of `candidates` (vertices in
/// no face) that are inside it, by a constrained Delaunay triangulation in the plane
/// perpendicular to the loop's mean site normal. Returns false (with out.faces empty) when the
/// loop's projection is not a simple clockwise polygon (out.shape says what it is), or when a
/// triangle would use an edge the mesh already has between two loop vertices.
bool triangulate_hole_with_sites(const WorkingMesh& mesh, const std::vector<int>& loop, const std::vector<int>& candidates,
                                 const HoleSiteOptions& options, HoleTriangulation& out);

}  // namespace heatcvt
