#pragma once
/// \file manifold_extraction.h
/// A manifold, consistently oriented surface out of candidate triangles: greedy acceptance,
/// non-manifold vertices resolved, tiny pieces dropped, and a second pass over what was left out
/// (the shape of Co3Ne's manifold extraction, geogram points/co3ne.cpp).
#include <vector>

#include "heatcvt/mesher/dual_candidates.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// Options of make_vertices_manifold().
struct ManifoldOptions {
  /// Rounds of "keep the largest fan of each non-manifold vertex" (a round can create new
  /// non-manifold vertices). Default 10.
  int max_fan_rounds = 10;
  /// Edge-connected pieces of at most this many faces are dropped (all kept when every piece is
  /// that small). Default 4.
  int max_dropped_piece_faces = 4;
};

/// Groups the faces `faces` (indices into mesh.faces(), all containing v) into fans: sets
/// connected through edges at v. Fans are ordered by their first face in `faces`.
std::vector<std::vector<int>> vertex_fans(const WorkingMesh& mesh, int v, const std::vector<int>& faces);

/// Greedy extraction: each candidate in order is added to `mesh` when none of its directed edges
/// exists yet and none of its edges has two faces already (so every edge stays shared by at
/// most two faces traversed in opposite directions). Returns the number of candidates rejected.
int extract_manifold(WorkingMesh& mesh, const std::vector<DualCandidate>& candidates);

/// Non-manifold vertices: of the fans around each, the largest is kept and the others removed
/// (repeated up to max_fan_rounds); then the small pieces are dropped. Returns the faces removed.
int make_vertices_manifold(WorkingMesh& mesh, const ManifoldOptions& options = {});

/// Second pass: every candidate of `first` and then of `second` not yet in the mesh is added
/// when it keeps every edge manifold and consistently oriented and its three vertices manifold.
/// Returns the number added.
int add_compatible_candidates(WorkingMesh& mesh, const std::vector<DualCandidate>& first,
                              const std::vector<DualCandidate>& second);

}  // namespace heatcvt
