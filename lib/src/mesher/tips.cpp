// Tips of thin parts, by their angle defect.
#include "heatcvt/mesher/tips.h"

#include <cmath>

namespace heatcvt {

std::vector<char> tip_vertices(const WorkingMesh& mesh, const TipOptions& options) {
  const int nv = mesh.num_vertices();
  std::vector<char> tips(nv, 0);
  if (!(options.min_defect_deg > 0)) return tips;
  const std::vector<double> angle_sum = vertex_angle_sums(mesh);
  const std::vector<char> border = mesh.boundary_vertices();
  const double min_defect = options.min_defect_deg * M_PI / 180.0;
  for (int v = 0; v < nv; ++v)
    tips[v] = mesh.valence(v) > 0 && !border[v] && 2.0 * M_PI - angle_sum[v] > min_defect;
  return tips;
}

}  // namespace heatcvt
