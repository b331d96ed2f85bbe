#pragma once
/// \file dual_mesh.h
/// The dual triangulation of a (heat) Voronoi diagram (paper §7.1): one vertex per site, one
/// triangle per Voronoi vertex where three cells meet. This is the remeshed surface of a CVT.
#include <Eigen/Core>
#include <vector>

#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Options of dual_mesh().
struct DualMeshOptions {
  /// A Voronoi vertex where k > 3 cells meet becomes a fan of k − 2 triangles over the cells in
  /// their cyclic order. When true the fan apex is chosen to maximise the smallest angle of the
  /// fan (site positions); when false the first cell of the cycle is the apex. Default true.
  bool best_fan = true;
};

/// Result of dual_mesh(). Nothing is repaired silently: everything unusual is counted here and
/// the triangles are left as constructed (validate_triangle_mesh() reports the consequences).
struct DualMesh {
  Eigen::MatrixX3d V;           ///< #sites by 3: the given site positions (vertex i = site i)
  Eigen::MatrixX3i F;           ///< #T by 3 triangles, oriented like the input surface
  Eigen::VectorXi face_source;  ///< #T: refined-mesh vertex (row of VoronoiDiagram::V) each triangle is dual to
  int voronoi_vertices = 0;     ///< refined vertices where ≥ 3 cells meet
  int split_vertices = 0;       ///< of those, with > 3 cells (split into fans)
  int repeated_cell_vertices = 0;  ///< Voronoi vertices where a cell appears twice in the cyclic order
  int open_fans = 0;            ///< Voronoi vertices on a boundary / non-manifold spot (fan order not a cycle)
  int duplicate_triangles = 0;  ///< triangles with the same three sites emitted by several Voronoi vertices (kept once)
  int flipped_against_input = 0;  ///< triangles whose normal points against the input face normal there
  std::vector<int> unused_sites;  ///< sites that are in no triangle (cell without Voronoi vertex)
};

/// Dual triangulation of `diagram`.
///   site_positions  #sites by 3 (usually the generators' 3D positions; any embedding works)
/// The cyclic order of the cells around a Voronoi vertex is read from the refined mesh's
/// connectivity (faces counter-clockwise around the vertex), so the triangles inherit the
/// orientation of the input surface; faces with cell −1 (unreached) are ignored. The walk around
/// a Voronoi vertex follows shared edges, not their directions, so it also works where the input
/// is not consistently oriented (non-orientable surfaces such as the Klein bottle: there each
/// triangle takes the orientation of one refined face at its Voronoi vertex, and the dual is
/// non-orientable too; validate_triangle_mesh() reports it with `orientable == 0`). Triangles with
/// three identical sites (kept once) are counted in `duplicate_triangles`.
/// \throw InvalidInputError if site_positions has fewer rows than the diagram has cells.
DualMesh dual_mesh(const VoronoiDiagram& diagram, const Eigen::MatrixX3d& site_positions,
                   const DualMeshOptions& options = {});

/// Smallest interior angle (radians) of every triangle (#F), the paper's quality measure
/// (φmin = minimum, φm = mean, Table 1). Degenerate triangles give 0.
Eigen::VectorXd smallest_angles(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Summary of smallest_angles() in degrees.
struct TriangleQuality {
  double min_angle_deg = 0;      ///< φmin
  double mean_min_angle_deg = 0; ///< φm
  double below_30_fraction = 0;  ///< share of triangles whose smallest angle is < 30°
  int triangles = 0;
  /// φmin of the triangles with an edge on the boundary (an edge of one triangle only); 180
  /// when there are none.
  double boundary_min_angle_deg = 180;
  int boundary_triangles = 0;
};
/// φmin, φm, the share below 30° and the φmin of boundary triangles of the triangles (V, F);
/// V #V by 3, F #F by 3. An empty F gives all zeros (boundary φmin 180).
TriangleQuality triangle_quality(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

}  // namespace heatcvt
