// Edge flips of the working mesh.
#include "heatcvt/mesher/edge_flips.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace heatcvt {

int flip_edges(WorkingMesh& mesh, const FlipOptions& options, const std::vector<char>* only_at,
               const std::vector<int>* target_valence) {
  const Eigen::MatrixX3d& V = mesh.V;
  auto normal = [&](int a, int b, int c) -> Eigen::Vector3d {
    return (V.row(b) - V.row(a)).cross(V.row(c) - V.row(a)).transpose();
  };
  auto min_angle = [&](int a, int b, int c) { return face_min_angle(mesh, {a, b, c}); };
  const double flat_cos = std::cos(options.flat_dihedral_deg * M_PI / 180.0);
  const double valence_angle = options.valence_min_angle_deg * M_PI / 180.0;
  const double cos_limit = std::cos(options.max_normal_deviation_deg * M_PI / 180.0);
  int flips = 0;
  for (int pass = 0; pass < options.max_passes; ++pass) {
    int pass_flips = 0;
    for (int f1 = 0; f1 < mesh.num_faces(); ++f1)
      for (int k = 0; k < 3; ++k) {
        const MeshFace& t = mesh.face(f1);
        const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        const int f2 = mesh.half_edge_face(b, a);
        if (f2 < 0) continue;
        int d = -1;
        for (int v : mesh.face(f2))
          if (v != a && v != b) d = v;
        if (d < 0 || d == c) continue;
        if (only_at && !(*only_at)[a] && !(*only_at)[b]) continue;
        if (mesh.edge_face_count(c, d) > 0) continue;
        if (mesh.valence(a) <= 3 || mesh.valence(b) <= 3) continue;
        const double before = std::min(min_angle(a, b, c), min_angle(b, a, d));
        const double after = std::min(min_angle(c, a, d), min_angle(d, b, c));
        if (options.valence_mode) {
          auto dev = [&](int v, int x) {
            const int t = target_valence ? (*target_valence)[v] : 6;
            return (x - t) * (x - t);
          };
          const int va = mesh.valence(a), vb = mesh.valence(b), vc = mesh.valence(c), vd = mesh.valence(d);
          const int dv_before = dev(a, va) + dev(b, vb) + dev(c, vc) + dev(d, vd);
          const int dv_after = dev(a, va - 1) + dev(b, vb - 1) + dev(c, vc + 1) + dev(d, vd + 1);
          if (dv_after >= dv_before) continue;
          // Never across creases or thin parts, where a valence flip can fold the surface
          // through itself.
          const Eigen::Vector3d o1 = normal(a, b, c).normalized(), o2 = normal(b, a, d).normalized();
          if (!(o1.dot(o2) > flat_cos)) continue;
          if (!(after > before || after > valence_angle)) continue;
        } else if (!(after > before + 1e-9)) {
          continue;
        }
        const Eigen::Vector3d n1 = normal(a, b, c), n2 = normal(b, a, d);
        const Eigen::Vector3d m1 = normal(c, a, d), m2 = normal(d, b, c);
        const Eigen::Vector3d avg = (n1.normalized() + n2.normalized()).normalized();
        if (!(m1.norm() > 0) || !(m2.norm() > 0) || !avg.allFinite()) continue;
        if (m1.normalized().dot(avg) < cos_limit || m2.normalized().dot(avg) < cos_limit) continue;
        mesh.flip(f1, k, f2);
        ++pass_flips;
        break;  // face f1 changed: move on to the next face
      }
    flips += pass_flips;
    if (pass_flips == 0) break;
  }
  return flips;
}

}  // namespace heatcvt
