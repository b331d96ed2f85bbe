// Small pieces and outward orientation of closed pieces.
#include "heatcvt/mesher/orientation.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>

namespace heatcvt {

int remove_small_pieces(WorkingMesh& mesh, int min_faces, double min_vertex_fraction, int* pieces_removed) {
  const FaceComponents pieces = face_components(mesh, true);
  const int np = static_cast<int>(pieces.size.size());
  // Vertices of each piece (a vertex belongs to the piece of any of its faces).
  std::vector<int> piece_of_vertex(mesh.num_vertices(), -1), vertices(np, 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f))
      if (piece_of_vertex[v] < 0) piece_of_vertex[v] = pieces.of_face[f], ++vertices[pieces.of_face[f]];
  int total = 0;
  for (int c : vertices) total += c;
  std::vector<char> small(np, 0);
  for (int c = 0; c < np; ++c) small[c] = pieces.size[c] < min_faces || vertices[c] < min_vertex_fraction * total;
  std::vector<char> drop(mesh.num_faces(), 0);
  int dropped = 0;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (small[pieces.of_face[f]]) drop[f] = 1, ++dropped;
  if (dropped == mesh.num_faces()) return 0;
  if (pieces_removed) *pieces_removed += static_cast<int>(std::count(small.begin(), small.end(), 1));
  return mesh.remove_faces(drop);
}

int orient_closed_pieces_outward(WorkingMesh& mesh) {
  // The normals' global sign comes from the normal orientation's root, which a noisy tip can get
  // wrong: a closed piece with negative enclosed volume is turned inside out.
  const FaceComponents pieces = face_components(mesh, true);
  const int nc = static_cast<int>(pieces.size.size());
  std::vector<double> volume(nc, 0.0);
  std::vector<char> open(nc, 0);
  const Eigen::RowVector3d centre = mesh.V.colwise().mean();
  for (int id = 0; id < mesh.num_faces(); ++id) {
    const MeshFace& f = mesh.face(id);
    const int c = pieces.of_face[id];
    const Eigen::RowVector3d a = mesh.V.row(f[0]) - centre, b = mesh.V.row(f[1]) - centre, d = mesh.V.row(f[2]) - centre;
    volume[c] += a.dot(b.cross(d)) / 6.0;
    for (int k = 0; k < 3; ++k)
      if (!mesh.has_half_edge(f[(k + 1) % 3], f[k])) open[c] = 1;
  }
  int turned = 0;
  for (int id = 0; id < mesh.num_faces(); ++id)
    if (const int c = pieces.of_face[id]; !open[c] && volume[c] < 0) {
      MeshFace f = mesh.face(id);
      std::swap(f[1], f[2]);
      mesh.replace_face(id, f);
      ++turned;
    }
  return turned;
}

}  // namespace heatcvt
