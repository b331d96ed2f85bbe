#pragma once
/// \file valence3_removal.h
/// Removal of interior vertices of valence 3: a tiny cell squeezed between three others, whose
/// triangles cannot have a smallest angle above 30° and which no flip can remove.
#include <vector>

#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of remove_valence3().
struct Valence3Options {
  int passes = 3;  ///< passes over the vertices (a removal can create new ones). Default 3.
  /// Each ring vertex must have at least this many faces before the removal (valence ≥ 3 after).
  /// Default 4.
  int min_ring_faces = 4;
};

/// Each vertex with exactly three faces forming a closed fan (a, b, c) is removed with its faces
/// and replaced by the triangle (a, b, c) when that triangle is not in the mesh yet, faces the way
/// the three did and the ring keeps enough faces; with `only`, only vertices v with (*only)[v].
/// The vertex stays (unused). Returns the number removed.
int remove_valence3(WorkingMesh& mesh, const Valence3Options& options = {}, const std::vector<char>* only = nullptr);

}  // namespace heatcvt
