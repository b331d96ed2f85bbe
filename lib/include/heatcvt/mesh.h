#pragma once
/// \file mesh.h
/// Plain triangle-mesh value type and the geometric quantities every module needs.
#include <Eigen/Core>
#include <utility>
#include <vector>

namespace heatcvt {

/// A triangle mesh as plain Eigen arrays (libigl convention).
///   V  #V by 3 vertex positions
///   F  #F by 3 zero-based vertex indices, counter-clockwise seen from outside
struct TriangleMesh {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
};

/// A point on the surface: a face and barycentric coordinates (sum 1) w.r.t. F.row(face).
struct SurfacePoint {
  int face = -1;
  Eigen::Vector3d bary = Eigen::Vector3d(1.0 / 3, 1.0 / 3, 1.0 / 3);
};

/// Position of a surface point, `Σ_k bary_k V(F(face,k))`.
Eigen::Vector3d position(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const SurfacePoint& p);

/// Mean length of the (undirected, each counted once per incident face-side) edges: h̄.
double mean_edge_length(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Per-face areas (#F).
Eigen::VectorXd face_areas(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Total surface area.
double surface_area(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// Area-weighted per-vertex normals (#V by 3, unit; zero for isolated vertices).
Eigen::MatrixX3d vertex_normals(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);

/// For every vertex the list of incident faces.
std::vector<std::vector<int>> vertex_faces(int num_vertices, const Eigen::MatrixX3i& F);

/// For every vertex the sorted list of neighbouring vertices (one-ring via edges).
std::vector<std::vector<int>> vertex_neighbors(int num_vertices, const Eigen::MatrixX3i& F);

/// The edges with one incident face (each as its two vertices, smaller first), sorted: the
/// border of an open mesh.
std::vector<std::pair<int, int>> boundary_edges(const Eigen::MatrixX3i& F);

/// Boundary loops: loop[v] is the loop (connected set of border edges, boundary_edges()) vertex
/// v is on, ids 0..count-1, or −1 for a vertex on no border edge. Returns the number of loops
/// (ValidationReport::boundary_loops counts the same).
int boundary_loop_labels(int num_vertices, const Eigen::MatrixX3i& F, Eigen::VectorXi& loop);

/// Connected components of the vertex graph: component id per vertex, ids 0..count-1.
/// Returns the number of components.
int connected_components(int num_vertices, const Eigen::MatrixX3i& F, Eigen::VectorXi& component);

/// Topological summary of a triangle mesh (via its edges).
struct MeshTopology {
  int vertices = 0;           ///< referenced vertices
  int edges = 0;              ///< undirected edges
  int faces = 0;
  int boundary_edges = 0;     ///< edges with one incident face
  int boundary_loops = 0;     ///< connected sets of boundary edges (boundary_loop_labels())
  int nonmanifold_edges = 0;  ///< edges with more than two incident faces
  int inconsistent_edges = 0; ///< manifold interior edges traversed twice in the same direction
  int components = 0;
  int euler_characteristic() const { return vertices - edges + faces; }
};
/// Counts of mesh_topology(): F #F by 3 indices into [0, num_vertices); unreferenced vertices are
/// not counted, components are edge-connected sets of faces.
MeshTopology mesh_topology(const Eigen::MatrixX3i& F, int num_vertices);

/// Throws InvalidInputError when V has NaN/inf, F is empty or indexes out of range, or every face
/// has zero area (coincident or collinear vertices: no surface to diffuse heat on).
/// `what` names the mesh (usually its file name) in the message.
void validate_mesh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const std::string& what = "mesh");

}  // namespace heatcvt
