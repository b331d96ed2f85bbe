#pragma once
/// \file weld.h
/// Stitching an unwelded mesh: a triangle soup (every triangle with its own three vertices, as
/// OBJ, PLY and OFF exporters write when they split vertices at texture or normal seams) has
/// only boundary edges and one component per piece, so the heat diffusion cannot cross its
/// seams. Welding the boundary vertices that share a position exactly restores the surface.
#include "heatcvt/mesh.h"

namespace heatcvt {

/// What weld_coincident_borders() did.
struct WeldStats {
  int welded = 0;       ///< vertices merged into another at the same position (and removed)
  int refused = 0;      ///< coincident boundary vertices left apart: welding would break the mesh
  int bad_edges = 0;    ///< when refused: edges the weld would give more than two faces
  int bad_faces = 0;    ///< when refused: faces the weld would collapse (two corners merged)
};

/// Merges the boundary vertices of `mesh` (ends of an edge with one face) that have exactly the
/// same coordinates (−0 and +0 equal), then removes the merged vertices; the faces keep their
/// corner order (orientation is repaired, where needed, by the steps that read the mesh). Interior
/// vertices are never merged. The weld is all or nothing: where it would collapse a face or give
/// an edge more than two faces (sheets touching along a seam), `mesh` is left as it was and the
/// counts say why. Deterministic: the merged vertex keeps the smallest index of its group.
WeldStats weld_coincident_borders(TriangleMesh& mesh);

}  // namespace heatcvt
