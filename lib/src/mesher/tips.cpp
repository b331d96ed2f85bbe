// Tips of thin parts, by their angle defect.
#include "heatcvt/mesher/tips.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace heatcvt {

std::vector<char> tip_vertices(const WorkingMesh& mesh, const TipOptions& options) {
  const int nv = mesh.num_vertices();
  std::vector<char> tips(nv, 0);
  if (!(options.min_defect_deg > 0)) return tips;
  std::vector<double> angle_sum(nv, 0.0);
  std::vector<char> used(nv, 0);
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = mesh.V.row(f[k]), b = mesh.V.row(f[(k + 1) % 3]), c = mesh.V.row(f[(k + 2) % 3]);
      const Eigen::Vector3d u = b - a, w = c - a;
      const double denom = u.norm() * w.norm();
      if (denom > 0) angle_sum[f[k]] += std::acos(std::clamp(u.dot(w) / denom, -1.0, 1.0));
      used[f[k]] = 1;
    }
  const std::vector<char> border = mesh.boundary_vertices();
  const double min_defect = options.min_defect_deg * M_PI / 180.0;
  for (int v = 0; v < nv; ++v)
    tips[v] = used[v] && !border[v] && 2.0 * M_PI - angle_sum[v] > min_defect;
  return tips;
}

}  // namespace heatcvt
