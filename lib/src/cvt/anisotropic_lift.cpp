// The R⁶ lift of the anisotropic CVT (paper §7.1). See cvt/anisotropic_lift.h.
#include "heatcvt/cvt/anisotropic_lift.h"

#include <cmath>
#include <string>
#include <utility>

#include "heatcvt/errors.h"

namespace heatcvt {

Laplacian lifted_laplacian(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::MatrixX3i& T,
                           double lambda, Eigen::VectorXd* lifted_face_area) {
  if (!(lambda >= 0) || !std::isfinite(lambda))
    throw InvalidInputError("lifted_laplacian: lambda must be finite and >= 0, got " + std::to_string(lambda));
  if (N.rows() != P.rows())
    throw InvalidInputError("lifted_laplacian: " + std::to_string(N.rows()) + " normals for " +
                            std::to_string(P.rows()) + " points");
  if (T.size() > 0 && (T.minCoeff() < 0 || T.maxCoeff() >= P.rows()))
    throw InvalidInputError("lifted_laplacian: a triangle index is out of range");
  Eigen::MatrixXd X(P.rows(), 6);
  X.leftCols(3) = P;
  X.rightCols(3) = lambda * N;
  const Eigen::MatrixX3d lengths = face_edge_lengths(X, T);
  Laplacian lap = cotan_laplacian_from_lengths(lengths, T, static_cast<int>(P.rows()));
  if (lifted_face_area) {
    lifted_face_area->resize(T.rows());
    for (Eigen::Index f = 0; f < T.rows(); ++f) {  // Heron, stable form
      double a = lengths(f, 0), b = lengths(f, 1), c = lengths(f, 2);
      if (a < b) std::swap(a, b);
      if (a < c) std::swap(a, c);
      if (b < c) std::swap(b, c);
      const double s = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
      (*lifted_face_area)[f] = s > 0 ? 0.25 * std::sqrt(s) : 0.0;
    }
  }
  return lap;
}

}  // namespace heatcvt
