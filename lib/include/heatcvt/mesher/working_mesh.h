#pragma once
/// \file working_mesh.h
/// The working mesh of the surface mesher: the triangle soup every post-CVT stage edits
/// (positions, faces, per-vertex normal and projector anchor) with an edge index that its own
/// operations keep up to date, and a checkpoint / rollback for "try an operation, undo it if the
/// result self-intersects".
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "heatcvt/disjoint_sets.h"

namespace heatcvt {

/// A triangle as three vertex indices; its orientation is the order of the corners.
using MeshFace = std::array<int, 3>;

/// Hash of a face's three vertex indices in their order, for sets of faces.
struct MeshFaceHash {
  std::size_t operator()(const MeshFace& f) const noexcept {
    std::uint64_t h = static_cast<std::uint32_t>(f[0]) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint32_t>(f[1]) * 0xC2B2AE3D27D4EB4FULL + (h >> 29);
    h ^= static_cast<std::uint32_t>(f[2]) * 0x165667B19E3779F9ULL + (h >> 32);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

/// Positions, faces and per-vertex attributes of the surface being meshed.
///
/// Faces are kept in a vector whose order is part of the state: stages visit faces in that order
/// (so results are deterministic), removal keeps the order of the remaining faces, additions go
/// to the end. The edge index (per-vertex stars, a few entries each, so a lookup scans a short
/// contiguous list) maps each directed edge (half-edge) a→b to the face that holds it
/// (when several do, an orientation conflict, the one indexed last) and each undirected edge to the number of faces on it;
/// the valence of a vertex is the number of distinct undirected edges at it. Every face operation
/// below updates the index; positions and normals are public and may be written directly.
class WorkingMesh {
 public:
  Eigen::MatrixX3d V;       ///< #V by 3 vertex positions
  Eigen::MatrixX3d N;       ///< #V by 3 unit vertex normals (of the surface the projector fits)
  std::vector<int> anchor;  ///< #V projector hints (SurfaceProjector::project), −1 = none

  WorkingMesh() = default;
  /// Vertices with their normals and anchors (same row count), no faces yet.
  WorkingMesh(Eigen::MatrixX3d positions, Eigen::MatrixX3d normals, std::vector<int> anchors);

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  bool empty() const { return faces_.empty(); }
  const std::vector<MeshFace>& faces() const { return faces_; }
  const MeshFace& face(int f) const { return faces_[f]; }

  /// Appends a vertex; returns its index.
  int add_vertex(const Eigen::Vector3d& position, const Eigen::Vector3d& normal, int anchor_hint);
  /// Appends the rows of `positions` with their normals and anchor hints (one copy of the vertex
  /// arrays for all of them); the first gets index num_vertices() before the call.
  void add_vertices(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& normals, const std::vector<int>& anchor_hints);
  /// Appends a face; returns its index.
  int add_face(const MeshFace& f);
  /// Removes the last face (undoes add_face).
  void pop_face();
  /// Removes the last vertex (undoes add_vertex); no face may use it.
  void pop_vertex();
  /// Replaces face f by g (same index).
  void replace_face(int f, const MeshFace& g);
  /// Removes the faces with drop[f] != 0 (drop has one entry per face); the others keep their
  /// order. Returns the number removed.
  int remove_faces(const std::vector<char>& drop);
  /// Replaces every face (the index is rebuilt).
  void set_faces(std::vector<MeshFace> faces);

  /// Flips the edge between corners k and k+1 of face f1 = (a, b, c) and the face f2 = (b, a, d)
  /// on its other side: f1 becomes (c, a, d) and f2 (d, b, c).
  void flip(int f1, int k, int f2);

  /// Face holding the half-edge a→b, or −1.
  int half_edge_face(int a, int b) const;
  bool has_half_edge(int a, int b) const { return half_edge_face(a, b) >= 0; }
  /// Number of faces on the undirected edge {a, b}.
  int edge_face_count(int a, int b) const;
  /// Distinct undirected edges at v.
  int valence(int v) const { return v < static_cast<int>(valence_.size()) ? valence_[v] : 0; }
  /// The faces at each vertex (#V lists, ascending face indices).
  std::vector<std::vector<int>> vertex_faces() const;
  /// Vertices on a boundary half-edge (one whose opposite half-edge is missing).
  std::vector<char> boundary_vertices() const;

  /// Everything a rollback restores: vertices, attributes, faces.
  struct Checkpoint {
    Eigen::MatrixX3d V, N;
    std::vector<int> anchor;
    std::vector<MeshFace> faces;
  };
  Checkpoint checkpoint() const { return {V, N, anchor, faces_}; }
  /// Restores the state saved by checkpoint() exactly (vertices added since are dropped). With
  /// `keep_anchors` (only when no vertex was added since) the projector hints found since are
  /// kept: they are warm starts near the same surface, not geometry.
  void rollback(const Checkpoint& c, bool keep_anchors = false);

  /// Key of the directed edge a→b (a, b < 2³¹).
  static long long edge_key(int a, int b) { return (static_cast<long long>(a) << 32) | static_cast<unsigned>(b); }

 private:
  /// One entry of a vertex's star: the other end of an edge and a value (the face holding the
  /// half-edge, or the number of faces on the undirected edge).
  struct StarEntry {
    int to, value;
  };
  using Star = std::vector<StarEntry>;
  void index_face(int f);
  void unindex_face(int f);
  void grow_stars();
  static StarEntry* find(Star& star, int to);
  static const StarEntry* find(const Star& star, int to);
  std::vector<MeshFace> faces_;
  std::vector<Star> out_;    // out_[a]: half-edges a→b with the face holding each
  std::vector<Star> edges_;  // edges_[min(a, b)]: undirected edges to max(a, b) with their face counts
  std::vector<int> valence_;
};

/// Number of vertices referenced by the mesh's faces.
int vertices_in_faces(const WorkingMesh& mesh);

/// What an edit changed in a mesh since the state `before` (a checkpoint of it).
struct MeshChanges {
  std::vector<char> moved;        ///< #V: moved or added
  std::vector<char> rehinted;     ///< #V: in place, with another normal or projector hint
  std::vector<char> new_face;     ///< #F: a face (corners in order) that `before` did not have
  std::vector<MeshFace> removed;  ///< faces of `before` that the mesh no longer has
};
/// The changes of `mesh` since `before` (faces compared by their corners, so that renumbered
/// faces are not changes; no face search where the face list is as it was).
MeshChanges changes_since(const WorkingMesh::Checkpoint& before, const WorkingMesh& mesh);

/// Smallest interior angle (radians) of the triangle (a, b, c): the one opposite its shortest
/// edge; 0 for a degenerate triangle.
double triangle_min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);
/// Smallest angle of face f of the mesh.
double face_min_angle(const WorkingMesh& mesh, const MeshFace& f);
/// φm of the mesh: the mean over its faces of their smallest angle (radians; 0 without faces).
double mean_min_angle(const WorkingMesh& mesh);
/// Mean length of the faces' edges, each interior edge counted from both of its faces (0 without faces).
double mean_edge_length(const WorkingMesh& mesh);
/// Angle (radians) of face f at its corner k; 0 where an edge there has zero length.
double corner_angle(const WorkingMesh& mesh, const MeshFace& f, int k);
/// Sum of the corner angles (radians) at each vertex, over its faces; 0 for an unused vertex.
std::vector<double> vertex_angle_sums(const WorkingMesh& mesh);

/// The border of a mesh: along each border half-edge a→b (one without its opposite b→a),
/// next[a] = b and prev[b] = a. −1 where a vertex has no such half-edge, −2 where it has several
/// (a pinched vertex where two border arcs meet).
struct BorderLinks {
  std::vector<int> next, prev;
  /// Whether v is on a border.
  bool on(int v) const { return next[v] != -1 || prev[v] != -1; }
  /// Whether v is on a single border arc (one next, one previous vertex).
  bool simple(int v) const { return next[v] >= 0 && prev[v] >= 0; }
};
BorderLinks border_links(const WorkingMesh& mesh);

/// Turning angle (radians) of the border at the simple border vertex v: 0 where the border goes
/// straight on, π where it turns back; π for a vertex that is not simple.
double border_turn(const WorkingMesh& mesh, const BorderLinks& border, int v);

/// Connected components of the faces (through shared vertices when `by_vertex`, else through
/// shared edges): component id of each face, ids numbered by first face, and the number of faces
/// of each component.
struct FaceComponents {
  std::vector<int> of_face;
  std::vector<int> size;
};
FaceComponents face_components(const WorkingMesh& mesh, bool by_vertex);

/// 1 for each piece of `pieces` (face_components() of `mesh`) that has a border vertex.
std::vector<char> open_pieces(const WorkingMesh& mesh, const FaceComponents& pieces);

}  // namespace heatcvt
