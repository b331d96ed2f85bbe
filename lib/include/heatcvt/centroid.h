#pragma once
/// \file centroid.h
/// Heat centroids (paper §5): diffuse heat from the whole cell (area source, eq. 10–11); the
/// hottest point is the centroid. Sub-vertex accuracy by the quadratic fit of §7.1
/// ("Centroids on faces").
#include <Eigen/Core>
#include <vector>

#include "heatcvt/heat_solver.h"
#include "heatcvt/mesh.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {

/// Options of heat_centroids().
struct CentroidOptions {
  /// Implicit steps (h ← u, repeated) to mimic a larger time (Fig. 4). Default 1.
  int steps = 1;
  /// Refine the hottest vertex by the local quadratic fit of §7.1. Default true.
  bool quadratic_refinement = true;
  /// Threads (parallel over cells); 0 = all. Default 0.
  int threads = 0;
  /// Cells whose diffusions are solved together (columns of one multi-right-hand-side solve).
  /// Default 64.
  int solve_block = 64;
};

/// Given heat values at the vertices (dense #V; only the neighbourhood of `hottest_vertex`
/// is read), refines the hottest vertex to a surface point: project the one-ring (incident
/// faces) to the tangent plane of the area-weighted normal, fit a bivariate quadratic to the
/// heat, take its maximiser, locate it in the incident faces (closest point if outside).
/// Falls back to the vertex itself when the fit has no interior maximum. Where the incident faces
/// are not consistently oriented (the orientation seam of a non-orientable surface such as the
/// Klein bottle), the normal of the locally re-oriented fan replaces `vertex_normals.row(v)`.
SurfacePoint refine_hottest_vertex(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                   const std::vector<std::vector<int>>& vertex_faces,
                                   const Eigen::MatrixX3d& vertex_normals, const Eigen::VectorXd& heat,
                                   int hottest_vertex);

/// Heat centroid of every cell of the diagram with full solves: one area-source diffusion per
/// cell (load vector of its refined pieces, cell_load_vectors(); solved in blocks of solve_block columns
/// with solver.solve(MatrixXd); `steps` > 1 repeats h ← u, i.e. rhs = M u), hottest vertex among
/// the vertices of the cell's parent faces, optional refinement (refine_hottest_vertex).
///   F is the original mesh of the diagram (diagram.face_parent indexes it).
///   returns #cells points; a cell without refined faces (empty) gets face = −1.
/// \throw InvalidInputError if the solver or the diagram do not match the mesh, steps < 1.
std::vector<SurfacePoint> heat_centroids(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                         const HeatSolver& solver, const VoronoiDiagram& diagram,
                                         const CentroidOptions& options = {});

/// Heat centroid of an arbitrary set of whole faces (area source on them), e.g. the polygons of
/// the Fig. 4 experiment. The hottest vertex is searched over all vertices.
/// \throw InvalidInputError if `faces` is empty or has an index out of range, steps < 1, or the
/// solver does not match the mesh.
SurfacePoint heat_centroid_of_faces(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatSolver& solver,
                                    const std::vector<int>& faces, const CentroidOptions& options = {});

}  // namespace heatcvt
