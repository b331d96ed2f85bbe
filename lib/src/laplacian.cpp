#include "heatcvt/laplacian.h"

#include <algorithm>
#include <cmath>

#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"

namespace heatcvt {

Eigen::MatrixX3d face_edge_lengths(const Eigen::MatrixXd& X, const Eigen::MatrixX3i& F) {
  Eigen::MatrixX3d lengths(F.rows(), 3);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      lengths(f, k) = (X.row(F(f, (k + 1) % 3)) - X.row(F(f, (k + 2) % 3))).norm();
  return lengths;
}

Laplacian cotan_laplacian_from_lengths(const Eigen::MatrixX3d& lengths, const Eigen::MatrixX3i& F,
                                       int num_vertices, const CotanOptions& options) {
  if (F.rows() == 0) throw InvalidInputError("cotan_laplacian: the mesh has no faces");
  if (num_vertices <= 0) throw InvalidInputError("cotan_laplacian: the mesh has no vertices");
  if (F.minCoeff() < 0 || F.maxCoeff() >= num_vertices)
    throw InvalidInputError("cotan_laplacian: a face index is out of range");
  if (!lengths.allFinite()) throw InvalidInputError("cotan_laplacian: an edge length is NaN or infinite");

  Laplacian out;
  out.mean_edge_length = lengths.mean();
  const double h2 = out.mean_edge_length * out.mean_edge_length;
  out.M = Eigen::VectorXd::Zero(num_vertices);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(F.rows() * 12);
  for (int f = 0; f < F.rows(); ++f) {
    // Heron's formula in the numerically stable form (Kahan): sort a ≥ b ≥ c.
    double l[3] = {lengths(f, 0), lengths(f, 1), lengths(f, 2)};
    double s[3] = {l[0], l[1], l[2]};
    std::sort(s, s + 3, std::greater<double>());
    const double a = s[0], b = s[1], c = s[2];
    const double q = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
    const double area = q > 0 ? 0.25 * std::sqrt(q) : 0.0;
    const bool repeated = F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 0) == F(f, 2);
    if (!(area > options.degenerate_area_epsilon * h2) || repeated) {
      out.degenerate_faces.push_back(f);
      continue;
    }
    // cot of the angle at corner k, from the law of cosines: (l_{k+1}² + l_{k+2}² − l_k²) / 4A.
    double cot[3];
    for (int k = 0; k < 3; ++k) {
      const double lk = l[k], l1 = l[(k + 1) % 3], l2 = l[(k + 2) % 3];
      cot[k] = (l1 * l1 + l2 * l2 - lk * lk) / (4.0 * area);
    }
    // A corner so near 180° that its cotangent is below −cot_clamp: the face's corners are
    // collinear to rounding (its area is rounding, not surface). Its weight, clamped or not,
    // would be a large negative one that no mass outweighs (M − tL indefinite): skipped like a
    // zero-area face.
    if (std::min({cot[0], cot[1], cot[2]}) < -options.cot_clamp) {
      out.degenerate_faces.push_back(f);
      continue;
    }
    for (int k = 0; k < 3; ++k) out.M[F(f, k)] += area / 3.0;  // eq. 6: lumped mass
    for (int k = 0; k < 3; ++k) {
      const double c = std::min(cot[k], options.cot_clamp);
      const int i = F(f, (k + 1) % 3), j = F(f, (k + 2) % 3);
      const double w = 0.5 * c;  // eq. 5: ½ (cot α_ij + cot β_ij), one half per face
      triplets.emplace_back(i, j, w);
      triplets.emplace_back(j, i, w);
      triplets.emplace_back(i, i, -w);
      triplets.emplace_back(j, j, -w);
    }
  }
  out.L.resize(num_vertices, num_vertices);
  out.L.setFromTriplets(triplets.begin(), triplets.end());
  out.L.makeCompressed();
  // Vertices touched only by degenerate faces (or none) keep a tiny positive mass so that
  // M − tL stays positive definite; they are effectively decoupled.
  const double positive_mean = out.M.sum() / std::max<Eigen::Index>(1, (out.M.array() > 0).count());
  const double floor_mass = options.min_mass_fraction * positive_mean;
  for (int i = 0; i < num_vertices; ++i)
    if (!(out.M[i] > floor_mass)) out.M[i] = std::max(out.M[i], floor_mass > 0 ? floor_mass : 1e-300);
  return out;
}

Laplacian cotan_laplacian(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const CotanOptions& options) {
  validate_mesh(V, F, "cotan_laplacian");
  return cotan_laplacian_from_lengths(face_edge_lengths(V, F), F, static_cast<int>(V.rows()), options);
}

}  // namespace heatcvt
