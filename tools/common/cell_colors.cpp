#include "cell_colors.h"

#include <cmath>

namespace heatcvt::cli {
Eigen::MatrixX3d cell_colors(const Eigen::VectorXi& labels) {
  Eigen::MatrixX3d C(labels.size(), 3);
  for (Eigen::Index i = 0; i < labels.size(); ++i) {
    if (labels[i] < 0) {
      C.row(i) << 0.5, 0.5, 0.5;
      continue;
    }
    const double h = std::fmod(labels[i] * 0.618033988749895, 1.0) * 6.0;
    const double s = 0.65, v = 0.95 - 0.25 * (labels[i] % 3) / 2.0;
    const int sector = static_cast<int>(h) % 6;
    const double f = h - std::floor(h), p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    const double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    C.row(i) << rgb[sector][0], rgb[sector][1], rgb[sector][2];
  }
  return C;
}
}  // namespace heatcvt::cli
