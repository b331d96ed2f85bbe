// Curvature-adaptive relative sizes. See adaptive_sizing.h.
#include "heatcvt/adaptive_sizing.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/parallel.h"
#include "heatcvt/point_index.h"

namespace heatcvt {
namespace {

// The q-quantile of `values` (reordered): the element of rank floor(q · (size − 1)).
double quantile_of(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = static_cast<size_t>(std::floor(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

void validate_sizing_inputs(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::VectorXd& weight,
                            double spacing, const AdaptiveSizingOptions& o) {
  if (N.rows() != P.rows() || weight.size() != P.rows())
    throw InvalidInputError("relative_sizes: " + std::to_string(P.rows()) + " points but " + std::to_string(N.rows()) +
                            " normals and " + std::to_string(weight.size()) + " weights");
  if (!(spacing > 0) || !std::isfinite(spacing)) throw InvalidInputError("relative_sizes: the spacing must be > 0");
  if (!(o.adaptivity >= 0 && o.adaptivity <= 2))
    throw InvalidInputError("relative_sizes: adaptivity must be in [0, 2], got " + std::to_string(o.adaptivity));
  if (!(o.max_size_ratio >= 1) || !std::isfinite(o.max_size_ratio))
    throw InvalidInputError("relative_sizes: max_size_ratio must be >= 1, got " + std::to_string(o.max_size_ratio));
  if (!(o.radius_spacings > 0) || !std::isfinite(o.radius_spacings) || !(o.smoothing_spacings >= 0) ||
      !std::isfinite(o.smoothing_spacings))
    throw InvalidInputError("relative_sizes: radius_spacings must be > 0 and smoothing_spacings >= 0");
  if (!(o.thin_part_spacings >= 0) || !std::isfinite(o.thin_part_spacings) ||
      !(o.thin_part_angle_deg >= 0 && o.thin_part_angle_deg <= 90))
    throw InvalidInputError("relative_sizes: thin_part_spacings must be >= 0 and thin_part_angle_deg in [0, 90]");
  if (!(o.min_pair_fraction >= 0 && o.min_pair_fraction < 1))
    throw InvalidInputError("relative_sizes: min_pair_fraction must be in [0, 1)");
  if (!(o.curvature_quantile >= 0 && o.curvature_quantile <= 1) ||
      !(o.curvature_cap_quantile >= 0 && o.curvature_cap_quantile <= 1))
    throw InvalidInputError("relative_sizes: the curvature quantiles must be in [0, 1]");
  if (!weight.allFinite() || !(weight.minCoeff() >= 0) || !(weight.sum() > 0))
    throw InvalidInputError("relative_sizes: the weights must be >= 0 with a positive sum");
}

// The points on a thin part: another point within `radius` lies along both points' normal lines
// (the segment within `angle_deg` of each normal, either way: the other side of the part, whatever
// the orientation of the normals). Empty where radius is 0.
std::vector<char> thin_parts(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const PointIndex& index,
                             double radius, double angle_deg, int threads) {
  const int n = static_cast<int>(P.rows());
  std::vector<char> thin(radius > 0 ? n : 0, 0);
  if (!(radius > 0)) return thin;
  const double min_cos = std::cos(angle_deg * M_PI / 180.0);
#pragma omp parallel for schedule(dynamic, 256) num_threads(resolve_threads(threads))
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    for (int j : index.within(p, radius)) {
      const Eigen::Vector3d d = P.row(j).transpose() - p;
      const double length = d.norm();
      if (j == i || !(length > 0)) continue;
      if (std::abs(N.row(i).dot(d)) >= min_cos * length && std::abs(N.row(j).dot(d)) >= min_cos * length) {
        thin[i] = 1;
        break;
      }
    }
  }
  return thin;
}

// Scales g so that Σ w g⁻² = Σ w (the vertex count of the uniform sizing), with the points marked
// in `capped` at most 1: those above are set to 1 and the others scaled again, until none is above
// (each round caps more points, so at most n rounds; a few in practice).
void scale_to_uniform_count(Eigen::VectorXd& g, const Eigen::VectorXd& weight, const std::vector<char>& capped) {
  const Eigen::Index n = g.size();
  std::vector<char> fixed(n, 0);
  for (Eigen::Index round = 0; round <= n; ++round) {
    double free_inverse = 0, fixed_inverse = 0;
    for (Eigen::Index i = 0; i < n; ++i) (fixed[i] ? fixed_inverse : free_inverse) += weight[i] / (g[i] * g[i]);
    const double target = weight.sum() - fixed_inverse;  // Σ w g⁻² the free points must give
    if (!(free_inverse > 0) || !(target > 0)) return;
    const double s = std::sqrt(free_inverse / target);
    bool changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (fixed[i]) continue;
      g[i] *= s;
      if (!capped.empty() && capped[i] && g[i] > 1) g[i] = 1, fixed[i] = 1, changed = true;
    }
    if (!changed) return;
  }
}

}  // namespace

Eigen::VectorXd curvature_estimate(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const PointIndex& index,
                                   double radius, double quantile, double min_distance, int threads) {
  const int n = static_cast<int>(P.rows());
  Eigen::VectorXd kappa = Eigen::VectorXd::Zero(n);
  const double inner2 = min_distance * min_distance;
#pragma omp parallel num_threads(resolve_threads(threads))
  {
    std::vector<double> normal_curvature;
#pragma omp for schedule(dynamic, 256)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = P.row(i).transpose(), ni = N.row(i).transpose();
      normal_curvature.clear();
      for (int j : index.within(p, radius)) {
        const Eigen::Vector3d d = P.row(j).transpose() - p;
        const double d2 = d.squaredNorm();
        if (j == i || !(d2 > 0) || d2 < inner2) continue;
        // Unoriented normals (a cloud's) are turned to agree with n_i first.
        const Eigen::Vector3d nj = N.row(j).transpose();
        const Eigen::Vector3d turned = nj.dot(ni) < 0 ? Eigen::Vector3d(-nj) : nj;
        normal_curvature.push_back(std::abs((turned - ni).dot(d)) / d2);
      }
      kappa[i] = quantile_of(normal_curvature, quantile);
    }
  }
  return kappa;
}

Eigen::VectorXd relative_sizes(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, const Eigen::VectorXd& weight,
                               double spacing, const AdaptiveSizingOptions& o, int threads) {
  validate_sizing_inputs(P, N, weight, spacing, o);
  const int n = static_cast<int>(P.rows());
  Eigen::VectorXd g = Eigen::VectorXd::Ones(n);
  if (!o.enabled() || n == 0) return g;
  const PointIndex index(P);
  const double radius = o.radius_spacings * spacing;
  const Eigen::VectorXd kappa =
      curvature_estimate(P, N, index, radius, o.curvature_quantile, o.min_pair_fraction * radius, threads);
  std::vector<double> sorted(kappa.data(), kappa.data() + n);
  const double cap = quantile_of(sorted, o.curvature_cap_quantile);
  if (!(cap > 0)) return g;  // flat everywhere: uniform
  // Curvatures clamped to [cap · ratio^(-2/a), cap]: g = κ^(-a/2) then spans at most the ratio.
  const double floor = cap * std::pow(o.max_size_ratio, -2.0 / o.adaptivity);
  Eigen::VectorXd log_g(n);
  for (int i = 0; i < n; ++i) log_g[i] = -0.5 * o.adaptivity * std::log(std::clamp(kappa[i], floor, cap));
  // Smoothed (area-weighted mean of log g over smoothing_spacings): the gradation a mesh at this
  // spacing can follow. A mean stays within the range, so the ratio bound holds.
  const double smooth_radius = o.smoothing_spacings * spacing;
#pragma omp parallel for schedule(dynamic, 256) num_threads(resolve_threads(threads))
  for (int i = 0; i < n; ++i) {
    double sum = 0, mass = 0;
    for (int j : index.within(P.row(i).transpose(), smooth_radius)) sum += weight[j] * log_g[j], mass += weight[j];
    g[i] = std::exp(mass > 0 ? sum / mass : log_g[i]);
  }
  scale_to_uniform_count(g, weight, thin_parts(P, N, index, o.thin_part_spacings * spacing, o.thin_part_angle_deg, threads));
  return g;
}

SizingField::SizingField(const Eigen::MatrixX3d& P, const Eigen::VectorXd& sizes) {
  if (P.rows() == 0 || sizes.size() != P.rows())
    throw InvalidInputError("SizingField: " + std::to_string(P.rows()) + " points and " + std::to_string(sizes.size()) +
                            " sizes (need as many, at least one)");
  if (!sizes.allFinite() || !(sizes.minCoeff() > 0)) throw InvalidInputError("SizingField: the sizes must be > 0");
  index_ = std::make_shared<const PointIndex>(P);
  sizes_ = std::make_shared<const Eigen::VectorXd>(sizes);
}

double SizingField::operator()(const Eigen::Vector3d& x) const {
  double distance = 0;
  const int i = index_->nearest(x, distance);
  return i >= 0 ? (*sizes_)[i] : 1.0;
}

SurfaceSizing surface_sizing(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Eigen::MatrixX3d& N, int sites,
                             const AdaptiveSizingOptions& options, int threads) {
  if (sites < 1) throw InvalidInputError("surface_sizing: sites must be >= 1, got " + std::to_string(sites));
  const Eigen::VectorXd face_area = face_areas(V, F);
  if (!(face_area.sum() > 0)) throw InvalidInputError("surface_sizing: the surface has no area");
  const Eigen::VectorXd area = lumped_vertex_areas(F, face_area, static_cast<int>(V.rows()));
  const double spacing = std::sqrt(face_area.sum() / sites);
  // The radius reaches at least 1.5 mean edge lengths; the inner distance of the pairs stays
  // that of the options' radius, so the one-ring of a coarse mesh is measured.
  AdaptiveSizingOptions o = options;
  o.radius_spacings = std::max(o.radius_spacings, 1.5 * mean_edge_length(V, F) / spacing);
  o.min_pair_fraction = options.min_pair_fraction * options.radius_spacings / o.radius_spacings;
  const Eigen::VectorXd g = relative_sizes(V, N, area, spacing, o, threads);
  return {SizingField(V, g), g.maxCoeff() / g.minCoeff()};
}

Eigen::VectorXd SurfaceSizing::density_at(const Eigen::MatrixX3d& P) const {
  // Cells of a CVT with density ρ have a diameter ∝ ρ^(-1/4): ρ = g⁻⁴ gives cells of size ∝ g.
  Eigen::VectorXd density(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) density[i] = std::pow(field(P.row(i).transpose()), -4.0);
  return density;
}

}  // namespace heatcvt
