#include "heatcvt/vertex_attributes.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

Eigen::MatrixX3d transfer_colours(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C, const Eigen::MatrixX3d& V,
                                  const ColourTransferOptions& options) {
  if (C.rows() != P.rows())
    throw InvalidInputError("transfer_colours: " + std::to_string(C.rows()) + " colours for " + std::to_string(P.rows()) +
                            " points");
  if (P.rows() < 1) throw InvalidInputError("transfer_colours: the cloud is empty");
  if (options.neighbors < 1 || !(options.power >= 0))
    throw InvalidInputError("transfer_colours: neighbors must be >= 1 and power >= 0");
  const int k = static_cast<int>(std::min<Eigen::Index>(options.neighbors, P.rows()));
  const Eigen::MatrixXi nb = nearest_neighbors_of(P, V, k, options.threads);
  Eigen::MatrixX3d out(V.rows(), 3);
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(static)
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    // Weights relative to the nearest distance d0: (d0 / d_j)^power, the same ratios as
    // 1 / d_j^power without overflow for tiny distances (any unit of length).
    const double d0 = (V.row(v) - P.row(nb(v, 0))).norm();
    if (d0 == 0) {  // the vertex is an input point: its colour, exactly
      out.row(v) = C.row(nb(v, 0));
      continue;
    }
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    double wsum = 0;
    for (int j = 0; j < k; ++j) {
      const double w = std::pow(d0 / (V.row(v) - P.row(nb(v, j))).norm(), options.power);
      sum += w * C.row(nb(v, j));
      wsum += w;
    }
    out.row(v) = sum / wsum;
  }
  return out;
}

}  // namespace heatcvt
