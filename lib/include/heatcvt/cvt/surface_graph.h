#pragma once
/// \file cvt/surface_graph.h
/// The edge graph of a triangle mesh and the small surface walks the CVT steps share: graph
/// Voronoi cells (multi-source Dijkstra), sites at vertices, greedy closest-point walks.
#include <Eigen/Core>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt {

/// Vertex adjacency with Euclidean edge lengths, compressed rows: the neighbours of v are
/// `nbr[off[v] .. off[v+1])` with lengths `len[...]`.
struct EdgeGraph {
  std::vector<int> off, nbr;
  std::vector<double> len;
  int num_vertices() const { return off.empty() ? 0 : static_cast<int>(off.size()) - 1; }
};

/// Edge graph of (V, F): V #V by 3, F #F by 3.
EdgeGraph edge_graph(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Multi-source Dijkstra on the graph: per vertex the index of the nearest source (−1 when
/// unreachable). Ties: the smaller (distance, source, vertex) is settled first. Deterministic.
std::vector<int> graph_voronoi(const EdgeGraph& g, const std::vector<int>& sources);

/// The corner of p's face with the largest barycentric coordinate.
int nearest_corner(const Eigen::MatrixX3i& F, const SurfacePoint& p);

/// Vertex v as a surface point (on its first face in `vfaces`, vertex_faces()). \pre v is used by a face.
SurfacePoint vertex_point(const Eigen::MatrixX3i& F, const std::vector<std::vector<int>>& vfaces, int v);

/// Lumped vertex areas: a third of the area of each incident face.
Eigen::VectorXd lumped_vertex_areas(const Eigen::MatrixX3i& F, const Eigen::VectorXd& face_area, int num_vertices);

/// Closest point to p on the surface by a greedy walk from `start` over the faces sharing a
/// corner with the current face: each move must lower the squared distance by a relative
/// `min_gain`, at most `max_steps` moves (local: meant for short steps).
SurfacePoint project_local(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                           const std::vector<std::vector<int>>& vfaces, const SurfacePoint& start,
                           const Eigen::Vector3d& p, int max_steps = 256, double min_gain = 1e-12);

/// The surface data every CVT step reads: the mesh (by reference: it must outlive this), its
/// edge graph, faces per vertex, face areas and lumped vertex areas, and the CVT's density.
struct CvtSurface {
  /// `vertex_density`: optional #V densities ρ > 0 of a CVT with density (empty = uniform); a
  /// face's density is the mean of its corners'.
  CvtSurface(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
             const Eigen::VectorXd& vertex_density = Eigen::VectorXd());
  const Eigen::MatrixX3d& V;
  const Eigen::MatrixX3i& F;
  EdgeGraph graph;
  std::vector<std::vector<int>> vfaces;
  Eigen::VectorXd face_area, vertex_area;
  /// face_area × the face's density: the mass of a face in the centroids (= face_area without
  /// a density).
  Eigen::VectorXd face_mass;
  /// The #V densities given (empty = uniform).
  Eigen::VectorXd vertex_density;
  bool has_density() const { return vertex_density.size() > 0; }
  int num_vertices() const { return static_cast<int>(V.rows()); }
};

}  // namespace heatcvt
