#pragma once
/// \file validate.h
/// Checks of a triangle mesh as a surface (the dual triangulation of a CVT, a reconstruction):
/// manifold edges and vertices, consistent orientation, closedness, genus, self-intersections.
/// The geometric and mesh-structure checks use CGAL (Surface_mesh + Polygon_mesh_processing);
/// CGAL is an implementation detail (not included by this header). Nothing is repaired: every
/// check reports pass/fail and where it failed.
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace heatcvt {

/// Options of validate_triangle_mesh().
struct ValidationOptions {
  /// Require no border edges. Default true (set it to whether the input surface is closed).
  bool require_closed = true;
  /// Expected genus (handles, summed over components); −1 = do not check. Default −1.
  int expected_genus = -1;
  /// Expected number of connected components; −1 = do not check. Default −1.
  int expected_components = -1;
  /// Expected number of boundary loops (a remesh keeps its input's); −1 = do not check. Default −1.
  int expected_boundary_loops = -1;
  /// Run PMP::does_self_intersect / self_intersections (the expensive check); when false the
  /// check is not reported at all. Default true.
  bool check_self_intersections = true;
  /// At most this many offending elements (edges, vertices, face pairs) are listed per check. Default 10.
  int max_listed = 10;
  /// Accept non-orientable surfaces (Klein bottle, Möbius strip, their duals): when the edge
  /// manifold admits no consistent orientation (ValidationReport::orientable == 0), the
  /// "consistent_orientation" check passes with a detail saying so, and the CGAL checks run on
  /// the surface cut open along an orientation seam (PMP::orient_polygon_soup; face pairs that
  /// share a vertex of the uncut surface are not reported as intersecting). An orientable surface
  /// with flipped faces still fails. Default false (orientation inconsistencies are failures).
  bool allow_non_orientable = false;
};

/// One check: its name, the verdict, a one-line explanation and the offending elements.
struct MeshCheck {
  std::string name;     ///< "manifold_edges", "manifold_vertices", "consistent_orientation", "closed",
                        ///< "all_vertices_used", "genus", "components", "no_self_intersections", "cgal_polygon_mesh"
  bool passed = false;
  bool ran = true;      ///< false when a prerequisite failed (e.g. self-intersections need a polygon mesh)
  std::string detail;   ///< e.g. "3 edges with more than two faces" or "ok"
  std::vector<std::vector<int>> where;  ///< up to max_listed items: edges {a,b}, vertices {v}, face pairs {f,g}
};

/// All checks plus the topological numbers they were derived from.
struct ValidationReport {
  std::vector<MeshCheck> checks;
  int vertices = 0;        ///< referenced vertices
  int edges = 0;
  int faces = 0;
  int components = 0;
  int boundary_loops = 0;
  int euler_characteristic = 0;
  int genus = -1;          ///< Σ over components of (2 − χ_c − b_c)/2; −1 when not an oriented manifold
  /// Orientability of the surface as a property (not a check): 1 when the faces can be flipped
  /// so that every interior edge is traversed once in each direction, 0 when no such choice
  /// exists (non-orientable, e.g. a Klein bottle), −1 when not determined (non-manifold edges).
  int orientable = -1;
  /// Non-orientable genus (number of cross-caps, Σ over non-orientable components of 2 − χ_c − b_c;
  /// a Klein bottle has 2, a Möbius strip 1); 0 for orientable surfaces, −1 when not determined.
  int crosscaps = -1;
  long self_intersecting_pairs = -1;  ///< number of intersecting face pairs (−1 = not computed)
  /// True when every check that ran passed and none was skipped.
  bool ok() const;
  /// The check with this name, or nullptr.
  const MeshCheck* find(const std::string& name) const;
  /// Multi-line human-readable summary ("PASS manifold_edges ok", "FAIL closed 4 border edges: ...").
  std::string summary() const;
};

/// Runs the checks on (V, F).
///   V #V by 3, F #F by 3 zero-based. Unreferenced vertices are reported by "all_vertices_used".
/// \throw InvalidInputError on empty F, indices out of range or non-finite coordinates.
ValidationReport validate_triangle_mesh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                        const ValidationOptions& options = {});

/// Genus of a closed or bordered orientable 2-manifold triangle mesh from its Euler characteristic,
/// components and boundary loops (as in ValidationReport::genus); −1 if not a manifold.
int mesh_genus(const Eigen::MatrixX3i& F, int num_vertices);

}  // namespace heatcvt
