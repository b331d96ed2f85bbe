// Small pieces and outward orientation of closed pieces.
#include "heatcvt/mesher/orientation.h"

#include <Eigen/Geometry>

#include <utility>

namespace heatcvt {

int remove_small_pieces(WorkingMesh& mesh, int min_faces) {
  const FaceComponents pieces = face_components(mesh, true);
  std::vector<char> drop(mesh.num_faces(), 0);
  int dropped = 0;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (pieces.size[pieces.of_face[f]] < min_faces) drop[f] = 1, ++dropped;
  if (dropped == mesh.num_faces()) return 0;
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
