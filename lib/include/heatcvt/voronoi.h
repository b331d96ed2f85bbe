#pragma once
/// \file voronoi.h
/// Heat Voronoi diagrams (paper §4): labels from the largest heat, tie-break of eq. 19, exact
/// tessellation by recursive cutting along the bisectors of eq. 20 (Fig. 1–2).
#include <Eigen/Core>
#include <utility>
#include <vector>

#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh.h"

namespace heatcvt {

/// Heat of the sites at the vertices where it is known, in compressed rows: the pairs of
/// vertex v are `site[offsets[v] .. offsets[v+1])` / `heat[...]`, sorted by decreasing heat.
/// A site absent from a vertex's row has heat 0 there (far away, or outside a localized set);
/// the builders below therefore store no exact zeros (e.g. the heat of a site on another
/// connected component), so a vertex with an empty row is one no site reached.
struct HeatField {
  int num_sites = 0;
  std::vector<int> offsets;  ///< #V + 1
  std::vector<int> site;
  std::vector<double> heat;
  int num_vertices() const { return offsets.empty() ? 0 : static_cast<int>(offsets.size()) - 1; }
};

/// Keeps, for every vertex, the `keep` hottest sites of the dense #V by #sites matrix U.
HeatField heat_field_from_dense(const Eigen::MatrixXd& U, int keep = 8);

/// Builds a field from per-site sparse heat: `indices[s]`/`values[s]` are the vertices where
/// site s's heat is known and the values there (e.g. from localized solves). Keeps the `keep`
/// hottest sites per vertex (exact zeros are not stored). `threads`: for the per-vertex sorts
/// (0 = all); the result does not depend on it.
/// \throw InvalidInputError on keep < 1, mismatched sizes, a vertex out of range or a non-finite value.
HeatField heat_field_from_sparse(int num_vertices, const std::vector<std::vector<int>>& indices,
                                 const std::vector<std::vector<double>>& values, int keep = 8, int threads = 0);

/// Options of tessellate() / heat_voronoi().
struct VoronoiOptions {
  /// Cut faces exactly along bisectors (eq. 20). When false, every face takes a single cell
  /// (the label of its centroid): cheap, used inside Lloyd iterations far from Voronoi vertices.
  bool exact = true;
  /// Sites kept per vertex in the heat field built by heat_voronoi(). Default 8.
  int keep_sites_per_vertex = 8;
  /// Guard of the exact cutting: at most this many candidate sites of a face (the ones with the
  /// largest heat at its corners) take part in the bisector cuts of that face. Default 24
  /// (= 3 corners × the default 8 sites per vertex, i.e. no truncation by default).
  /// \note The cutting is implemented as clipping the face by the half-planes u_s ≥ u_r of every
  /// candidate pair (the same pieces as the recursive cut of Fig. 2: every u_s is linear on a
  /// face, so each cell ∩ face is convex); it terminates by construction.
  int max_cut_depth = 24;
  /// Threads for the per-face work; 0 = all. Default 0.
  int threads = 0;
  /// heat_voronoi(): point-source solves per batch (columns of one multi-right-hand-side solve).
  /// Default 64.
  int solve_block = 64;

  // --- numerical tolerances of the exact cutting (barycentric units of a face) ---
  /// Switch points of an edge's upper envelope closer than this (in the edge parameter) to the
  /// previous one or to the edge's end are merged into it. Default 1e-12.
  double edge_merge_tolerance = 1e-12;
  /// A triple point (three cells meeting) within this of the face boundary is snapped to the
  /// edge's canonical point, and one within this of an existing point is welded to it. Default 1e-10.
  double weld_tolerance = 1e-10;
  /// A polygon vertex whose two neighbours span less than this (twice the barycentric area) is
  /// flat: the polygon is fanned from its centroid. Default 1e-13.
  double flat_tolerance = 1e-13;
  /// Validity check of a cut face: every piece's (doubled barycentric) area must exceed
  /// −orientation_tolerance (default 1e-14) and the pieces must sum to the face within
  /// tiling_tolerance (default 1e-9); otherwise the face is fanned from its centroid.
  double orientation_tolerance = 1e-14;
  double tiling_tolerance = 1e-9;
};

/// A point of the refined mesh that lies inside (or on the boundary of) an original face.
struct VoronoiVertex {
  Eigen::Vector3d position;
  SurfacePoint location;        ///< original face + barycentric coordinates
  std::vector<int> cells;       ///< ≥ 3 distinct cells meeting here, sorted
};

/// A Voronoi edge between two cells, as a polyline of refined-mesh vertex indices.
struct VoronoiEdge {
  int cell_a = -1, cell_b = -1;  ///< cell_a < cell_b
  std::vector<int> polyline;     ///< indices into VoronoiDiagram::V, in order along the edge
};

/// Result of the tessellation: a refined triangle mesh whose faces each belong to one cell.
struct VoronoiDiagram {
  Eigen::MatrixX3d V;               ///< #RV by 3 refined vertices (original vertices first, same indices)
  Eigen::MatrixX3i F;               ///< #RF by 3 refined faces
  Eigen::VectorXi face_cell;        ///< #RF cell (site) index per refined face, −1 if no site reached it
  Eigen::VectorXi face_parent;      ///< #RF original face per refined face
  Eigen::MatrixX3d face_bary;       ///< #RF·3 rows: barycentric coords (in the parent face) of refined corner k of face r at row 3r+k
  Eigen::VectorXd face_area;        ///< #RF area of each refined face (parent area × bary determinant)
  Eigen::VectorXd cell_area;        ///< #sites
  std::vector<std::vector<int>> cell_adjacency;  ///< sorted neighbouring cells per cell
  std::vector<VoronoiVertex> voronoi_vertices;
  std::vector<VoronoiEdge> edges;
  std::vector<int> unreached_components;  ///< connected components of the input with no site
  int num_cells() const { return static_cast<int>(cell_area.size()); }
};

/// Tessellates the mesh (V, F) given the heat field of the sites.
///   V #V by 3, F #F by 3, field.num_vertices() == #V.
/// Corner labels: largest heat, ties by eq. 19 (heat at the face's other two corners, then the
/// smaller site). Faces whose corners agree keep one cell; the others are cut exactly along the
/// bisectors (eq. 20). Points on original edges depend only on the edge (canonical orientation,
/// 1D upper envelope of the sites known at its ends) and are shared by both faces, so the
/// refined mesh is conforming (same Euler characteristic and boundary as the input).
/// A site absent from a vertex's row counts as heat 0 there; faces whose corners know no site
/// get cell −1, and components without any known heat are listed in unreached_components.
/// Parallel over faces; the output does not depend on the thread count.
/// \throw InvalidInputError if the mesh is invalid or the field does not match it.
VoronoiDiagram tessellate(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatField& field,
                          const VoronoiOptions& options = {});

/// One diffusion per site with the solver (point sources, eq. 8: rhs = barycentric vector),
/// batched in blocks of options.solve_block columns whose `keep_sites_per_vertex` hottest sites per vertex are
/// merged (memory #V·(keep + 64), result identical to heat_field_from_dense of the full
/// matrix), then tessellate().
/// \throw InvalidInputError if a site's face index is out of range, its barycentric
/// coordinates are not finite, there are no sites, or the solver does not match the mesh.
VoronoiDiagram heat_voronoi(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatSolver& solver,
                            const std::vector<SurfacePoint>& sites, const VoronoiOptions& options = {});

/// Load vector of a cell as an area source (eq. 10–11) computed exactly on its refined pieces:
/// pairs (original vertex, ∫_cell φ_vertex). Summing the values gives the cell area.
std::vector<std::pair<int, double>> cell_load_vector(const VoronoiDiagram& diagram, const Eigen::MatrixX3i& F,
                                                      int cell);

/// Load vectors of all cells at once (one pass over the refined faces): result[c] is what
/// cell_load_vector(diagram, F, c) returns, pairs sorted by vertex.
std::vector<std::vector<std::pair<int, double>>> cell_load_vectors(const VoronoiDiagram& diagram,
                                                                    const Eigen::MatrixX3i& F);

/// The refined faces around every refined vertex, compressed rows: the faces of vertex v are
/// `faces[offsets[v] .. offsets[v+1])`, in increasing order.
void refined_vertex_faces(const VoronoiDiagram& diagram, std::vector<int>& offsets, std::vector<int>& faces);

/// The refined faces of every cell: result[c] lists indices into diagram.F.
std::vector<std::vector<int>> cell_faces(const VoronoiDiagram& diagram);

}  // namespace heatcvt
