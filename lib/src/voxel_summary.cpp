// Per-voxel moments of a streamed cloud and the voxel size chooser (voxel_summary.h).
#include "heatcvt/voxel_summary.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace {

using Cell = std::array<std::int64_t, 3>;

struct CellHash {
  std::size_t operator()(const Cell& c) const {
    // Multiplicative mixing of the three integers (large odd constants, then xor-shift).
    std::uint64_t h = static_cast<std::uint64_t>(c[0]) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(c[1]) * 0xC2B2AE3D27D4EB4FULL + (h >> 29);
    h ^= static_cast<std::uint64_t>(c[2]) * 0x165667B19E3779F9ULL + (h >> 32);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

// Cells beyond ±2^52 would lose integer exactness in the double → int conversion.
constexpr double kMaxCell = 4503599627370496.0;

Cell cell_of(double x, double y, double z, double inv_h) {
  const double c[3] = {std::floor(x * inv_h), std::floor(y * inv_h), std::floor(z * inv_h)};
  for (double v : c)
    if (!(std::abs(v) < kMaxCell))
      throw InvalidInputError("VoxelSummary: coordinate / voxel size exceeds the integer cell range (2^52)");
  return {static_cast<std::int64_t>(c[0]), static_cast<std::int64_t>(c[1]), static_cast<std::int64_t>(c[2])};
}

Eigen::Index occupied_voxels(const Eigen::MatrixX3d& P, double h) {
  std::unordered_set<Cell, CellHash> cells;
  cells.reserve(static_cast<std::size_t>(P.rows()));
  const double inv_h = 1.0 / h;
  for (Eigen::Index i = 0; i < P.rows(); ++i) cells.insert(cell_of(P(i, 0), P(i, 1), P(i, 2), inv_h));
  return static_cast<Eigen::Index>(cells.size());
}

// Bisection steps of the rebinning size of surface_points (ratio 2^(2^-12) at the end).
constexpr int kRebinBisections = 12;

// Moments of one voxel, relative to its corner.
struct Moments {
  std::int64_t count = 0;
  double s[3] = {0, 0, 0};                // Σ (p − corner)
  double ss[6] = {0, 0, 0, 0, 0, 0};      // Σ (p − corner)(p − corner)ᵀ: xx xy xz yy yz zz
  double c[3] = {0, 0, 0};                // Σ colour
};

}  // namespace

struct VoxelSummary::Impl {
  std::unordered_map<Cell, std::uint32_t, CellHash> index;
  std::vector<Cell> cell;
  std::vector<Moments> moments;
  mutable std::vector<std::uint32_t> order;
  mutable bool order_valid = false;
};

VoxelSummary::VoxelSummary(double voxel_size) : h_(voxel_size), impl_(std::make_unique<Impl>()) {
  if (!(std::isfinite(voxel_size) && voxel_size > 0))
    throw InvalidInputError("VoxelSummary: voxel_size must be finite and > 0 (got " + std::to_string(voxel_size) + ")");
}
VoxelSummary::~VoxelSummary() = default;
VoxelSummary::VoxelSummary(VoxelSummary&&) noexcept = default;
VoxelSummary& VoxelSummary::operator=(VoxelSummary&&) noexcept = default;

void VoxelSummary::add(const CloudChunk& chunk) { add(chunk.P, chunk.has_colours() ? chunk.C : Eigen::MatrixX3d(0, 3)); }

void VoxelSummary::add(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C) { add_weighted(P, C, 1); }

void VoxelSummary::add_weighted(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C, std::int64_t weight) {
  const bool colours = C.rows() == P.rows() && P.rows() > 0;
  const double w = static_cast<double>(weight);
  const double inv_h = 1.0 / h_;
  Impl& m = *impl_;
  m.order_valid = false;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double x = P(i, 0), y = P(i, 1), z = P(i, 2);
    if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z))) {
      skipped_ += weight;
      continue;
    }
    const Cell key = cell_of(x, y, z, inv_h);
    auto [it, inserted] = m.index.try_emplace(key, static_cast<std::uint32_t>(m.moments.size()));
    if (inserted) {
      m.cell.push_back(key);
      m.moments.emplace_back();
    }
    Moments& v = m.moments[it->second];
    const double d[3] = {x - static_cast<double>(key[0]) * h_, y - static_cast<double>(key[1]) * h_,
                         z - static_cast<double>(key[2]) * h_};
    v.count += weight;
    for (int k = 0; k < 3; ++k) v.s[k] += w * d[k];
    v.ss[0] += w * d[0] * d[0];
    v.ss[1] += w * d[0] * d[1];
    v.ss[2] += w * d[0] * d[2];
    v.ss[3] += w * d[1] * d[1];
    v.ss[4] += w * d[1] * d[2];
    v.ss[5] += w * d[2] * d[2];
    if (colours) {
      for (int k = 0; k < 3; ++k) v.c[k] += w * C(i, k);
      coloured_ += weight;
    }
    added_ += weight;
  }
}

// Second eigenvalue / largest at or below which a voxel's points count as collinear (no normal).
constexpr double kCollinearRatio = 1e-12;

Eigen::Index VoxelSummary::voxels() const { return static_cast<Eigen::Index>(impl_->moments.size()); }

const std::vector<std::uint32_t>& VoxelSummary::order() const {
  Impl& m = *impl_;
  if (!m.order_valid) {
    m.order.resize(m.cell.size());
    std::iota(m.order.begin(), m.order.end(), 0u);
    std::sort(m.order.begin(), m.order.end(), [&](std::uint32_t a, std::uint32_t b) { return m.cell[a] < m.cell[b]; });
    m.order_valid = true;
  }
  return m.order;
}

Eigen::MatrixX3d VoxelSummary::points() const {
  const auto& ord = order();
  Eigen::MatrixX3d P(static_cast<Eigen::Index>(ord.size()), 3);
  for (std::size_t r = 0; r < ord.size(); ++r) {
    const Moments& v = impl_->moments[ord[r]];
    const Cell& c = impl_->cell[ord[r]];
    for (int k = 0; k < 3; ++k)
      P(static_cast<Eigen::Index>(r), k) = static_cast<double>(c[k]) * h_ + v.s[k] / static_cast<double>(v.count);
  }
  return P;
}

Eigen::VectorXi VoxelSummary::counts() const {
  const auto& ord = order();
  Eigen::VectorXi n(static_cast<Eigen::Index>(ord.size()));
  for (std::size_t r = 0; r < ord.size(); ++r)
    n(static_cast<Eigen::Index>(r)) = static_cast<int>(std::min<std::int64_t>(impl_->moments[ord[r]].count, INT32_MAX));
  return n;
}

Eigen::MatrixX3d VoxelSummary::normals(std::vector<bool>* valid, int min_points) const {
  const auto& ord = order();
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(ord.size()), 3);
  if (valid) valid->assign(ord.size(), false);
  for (std::size_t r = 0; r < ord.size(); ++r) {
    const Moments& v = impl_->moments[ord[r]];
    if (v.count < std::max(min_points, 1)) continue;
    const double n = static_cast<double>(v.count);
    const Eigen::Vector3d mean(v.s[0] / n, v.s[1] / n, v.s[2] / n);
    Eigen::Matrix3d cov;
    cov << v.ss[0], v.ss[1], v.ss[2], v.ss[1], v.ss[3], v.ss[4], v.ss[2], v.ss[4], v.ss[5];
    cov = cov / n - mean * mean.transpose();
    if (!(cov.norm() > 0)) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (!(eig.eigenvalues()(1) > kCollinearRatio * eig.eigenvalues()(2))) continue;  // points on a line
    N.row(static_cast<Eigen::Index>(r)) = eig.eigenvectors().col(0).transpose();  // smallest eigenvalue
    if (valid) (*valid)[r] = true;
  }
  return N;
}

Eigen::MatrixX3d VoxelSummary::colours() const {
  if (!has_colours()) return Eigen::MatrixX3d(0, 3);
  const auto& ord = order();
  Eigen::MatrixX3d C(static_cast<Eigen::Index>(ord.size()), 3);
  for (std::size_t r = 0; r < ord.size(); ++r) {
    const Moments& v = impl_->moments[ord[r]];
    for (int k = 0; k < 3; ++k) C(static_cast<Eigen::Index>(r), k) = v.c[k] / static_cast<double>(v.count);
  }
  return C;
}

Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3> VoxelSummary::cells() const {
  const auto& ord = order();
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, 3> K(static_cast<Eigen::Index>(ord.size()), 3);
  for (std::size_t r = 0; r < ord.size(); ++r)
    for (int k = 0; k < 3; ++k) K(static_cast<Eigen::Index>(r), k) = impl_->cell[ord[r]][static_cast<std::size_t>(k)];
  return K;
}

namespace {

// Moments of a neighbourhood, relative to one origin `o` (the centre voxel's corner).
struct MergedMoments {
  double n = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  // Adds voxel moments taken relative to a corner displaced by d from o: p − o = (p − c) + d.
  void add(const Moments& v, const Eigen::Vector3d& d) {
    const double k = static_cast<double>(v.count);
    const Eigen::Vector3d vs(v.s[0], v.s[1], v.s[2]);
    Eigen::Matrix3d vss;
    vss << v.ss[0], v.ss[1], v.ss[2], v.ss[1], v.ss[3], v.ss[4], v.ss[2], v.ss[4], v.ss[5];
    n += k;
    s += vs + k * d;
    ss += vss + vs * d.transpose() + d * vs.transpose() + k * d * d.transpose();
  }
};

}  // namespace

// Each voxel mean projected on the plane fitted to its 3×3×3 neighbourhood (absolute
// coordinates), with its point count and mean colour.
void VoxelSummary::project_means(Eigen::MatrixX3d& P, Eigen::VectorXd& w, Eigen::MatrixX3d& C) const {
  const Impl& m = *impl_;
  const auto& ord = order();
  const auto rows = static_cast<Eigen::Index>(ord.size());
  const bool with_colours = has_colours();
  P.resize(rows, 3);
  w.resize(rows);
  C.resize(with_colours ? rows : 0, 3);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const std::uint32_t vi = ord[static_cast<std::size_t>(r)];
    const Cell& c = m.cell[vi];
    const Moments& v = m.moments[vi];
    MergedMoments nb;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = m.index.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it != m.index.end()) nb.add(m.moments[it->second], h_ * Eigen::Vector3d(dx, dy, dz));
        }
    const double k = static_cast<double>(v.count);
    Eigen::Vector3d mean(v.s[0] / k, v.s[1] / k, v.s[2] / k);  // relative to the corner
    if (nb.n >= 3) {
      const Eigen::Vector3d mu = nb.s / nb.n;
      const Eigen::Matrix3d cov = nb.ss / nb.n - mu * mu.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      if (eig.eigenvalues()(1) > kCollinearRatio * eig.eigenvalues()(2)) {
        const Eigen::Vector3d normal = eig.eigenvectors().col(0);
        mean -= (mean - mu).dot(normal) * normal;
      }
    }
    for (int a = 0; a < 3; ++a) P(r, a) = static_cast<double>(c[static_cast<std::size_t>(a)]) * h_ + mean(a);
    w(r) = k;
    if (with_colours)
      for (int a = 0; a < 3; ++a) C(r, a) = v.c[a] / k;
  }
}

Eigen::MatrixX3d VoxelSummary::surface_points(Eigen::Index target_points, Eigen::VectorXi* weights,
                                              Eigen::MatrixX3d* colours) const {
  Eigen::MatrixX3d P, C;
  Eigen::VectorXd w;
  project_means(P, w, C);
  // The rebinning size: the voxel size, or the smallest multiple of it (bisection in log scale)
  // whose occupied cells are at most target_points.
  double size = h_;
  if (target_points > 0 && P.rows() > target_points) {
    double lo = h_, hi = 2 * h_;
    while (occupied_voxels(P, hi) > target_points) lo = hi, hi *= 2;
    for (int it = 0; it < kRebinBisections; ++it) {
      const double mid = std::sqrt(lo * hi);
      (occupied_voxels(P, mid) > target_points ? lo : hi) = mid;
    }
    size = hi;
  }
  VoxelSummary rebinned(size);
  for (Eigen::Index r = 0; r < P.rows(); ++r)
    rebinned.add_weighted(P.row(r), C.rows() ? Eigen::MatrixX3d(C.row(r)) : Eigen::MatrixX3d(0, 3),
                          static_cast<std::int64_t>(w(r)));
  if (weights) *weights = rebinned.counts();
  if (colours) *colours = rebinned.colours();
  return rebinned.points();
}

// ------------------------------------------------------------------------------------------
// Voxel size chooser

SurfaceAreaEstimate estimate_surface_area(const Eigen::MatrixX3d& sample, const VoxelSizeOptions& options) {
  if (!(options.sample_points_per_voxel >= 1) || options.probe_iterations < 1)
    throw InvalidInputError("estimate_surface_area: sample_points_per_voxel must be >= 1 and probe_iterations >= 1");
  Eigen::MatrixX3d P(sample.rows(), 3);
  Eigen::Index n = 0;
  for (Eigen::Index i = 0; i < sample.rows(); ++i)
    if (sample.row(i).allFinite()) P.row(n++) = sample.row(i);
  P.conservativeResize(n, 3);
  if (n < 10) throw InvalidInputError("estimate_surface_area: the sample has fewer than 10 finite points");
  const double diag = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();
  if (!(diag > 0)) throw InvalidInputError("estimate_surface_area: the sample has no extent (all points equal)");
  const double target = std::max(1.0, static_cast<double>(n) / options.sample_points_per_voxel);
  // Start where a flat square of side diag would give the target count, then rescale.
  double h = diag / std::sqrt(target);
  Eigen::Index count = occupied_voxels(P, h);
  for (int it = 1; it < options.probe_iterations; ++it) {
    const double next = h * std::sqrt(static_cast<double>(count) / target);
    if (std::abs(next - h) <= 1e-3 * h) break;
    h = next;
    count = occupied_voxels(P, h);
  }
  return {static_cast<double>(count) * h * h / 1.5, h, count};
}

double choose_voxel_size(const Eigen::MatrixX3d& sample, int sites, const VoxelSizeOptions& options) {
  if (sites < 1) throw InvalidInputError("choose_voxel_size: sites must be >= 1");
  if (!(options.points_per_site > 0 && std::isfinite(options.points_per_site)))
    throw InvalidInputError("choose_voxel_size: points_per_site must be finite and > 0");
  const SurfaceAreaEstimate est = estimate_surface_area(sample, options);
  const double wanted = static_cast<double>(sites) * options.points_per_site;
  return est.probe_voxel_size * std::sqrt(static_cast<double>(est.probe_voxels) / wanted);
}

}  // namespace heatcvt
