#pragma once
/// \file orientation.h
/// Removal of tiny pieces and outward orientation of closed pieces.
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Removes the vertex-connected pieces with fewer than `min_faces` faces (a few sites of a thin
/// tip that closed up on their own) or with fewer vertices than `min_vertex_fraction` of all the
/// vertices in faces (stray bits), unless that would remove every face. Returns the faces
/// removed and, in `pieces_removed` if given, the number of pieces.
int remove_small_pieces(WorkingMesh& mesh, int min_faces = 20, double min_vertex_fraction = 0,
                        int* pieces_removed = nullptr);

/// Every closed vertex-connected piece (no boundary half-edge) with negative enclosed volume
/// (signed tetrahedra from the vertices' centroid) is turned inside out. Open pieces keep their
/// orientation. Returns the faces reversed.
int orient_closed_pieces_outward(WorkingMesh& mesh);

}  // namespace heatcvt
