#pragma once
/// \file surface_refinement.h
/// Refinement of a triangle mesh that keeps its surface (as a point set) and its border: long
/// edges split at their midpoints, longest first, and, where the two faces of an edge lie in one
/// plane, the edge flipped to the Delaunay diagonal. It gives the heat CVT a working mesh with
/// enough vertices under every cell and, on meshes exported from CAD (fans of needles on flat
/// caps, strips of slivers along cylinders), well-shaped triangles: there the cotan weights of
/// eq. 5 are no longer dominated by the angles near 180° and the heat distances follow the surface.
/// Midpoint subdivision (subdivision.h) keeps every triangle's shape, slivers included.
#include "heatcvt/mesh.h"

namespace heatcvt {

/// Options of refine_surface().
struct SurfaceRefinementOptions {
  /// Refine until the mesh has at least this many vertices (it may end with up to about twice
  /// as many: the splits even out the edge lengths). Default 0: no split, only the flips.
  double target_vertices = 0;
  /// Edges longer than this times the target edge length (that of an equilateral mesh of
  /// target_vertices vertices on the same area) are split. Default 4/3, as in isotropic
  /// remeshing (Botsch & Kobbelt 2004).
  double split_ratio = 4.0 / 3.0;
  /// An edge is flipped only where the normals of its two faces, before and after the flip,
  /// differ by less than this: faces in one plane up to the rounding of the file's coordinates
  /// (a float STL's are within 0.001°). Default 0.01°.
  double flat_angle_deg = 0.01;
  /// While the mesh has fewer than target_vertices vertices with no edge left to split, the
  /// target length is multiplied by this and the splits go on. Default 0.85.
  double length_step = 0.85;
  /// The splits stop once the mesh has its input's vertices plus this times target_vertices. In
  /// a region that is flat only pair by pair (a finely faceted curve under a flat angle wider
  /// than its facets' bends) the flips can make long edges as fast as the splits remove them;
  /// this bounds the work there. Must be >= 1. Default 40: a cylinder faceted into 2,048 strips
  /// under the default flat angle keeps its strips, whose bends split to the target length need
  /// up to about 27.
  double max_vertex_factor = 40.0;
};

/// What refine_surface() made.
struct SurfaceRefinement {
  TriangleMesh mesh;               ///< the refined mesh: the input's vertices first, then the new ones
  int splits = 0;                  ///< edges split
  int flips = 0;                   ///< edges flipped
  double target_edge_length = 0;   ///< the last target length (0 when target_vertices is 0)
};

/// Splits and flat Delaunay flips of an edge-manifold, consistently oriented mesh (see the
/// file comment). Deterministic (edges visited by length, ties by vertex index).
/// \throw InvalidInputError where the mesh has an edge with more than two faces or an interior
/// edge traversed twice in the same direction (use midpoint_subdivide() there).
SurfaceRefinement refine_surface(const TriangleMesh& mesh, const SurfaceRefinementOptions& options);

}  // namespace heatcvt
