// Per-voxel moments of a streamed cloud and the voxel size chooser (voxel_summary.h).
#include "heatcvt/voxel_summary.h"

#include <Eigen/Eigenvalues>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_set>

#include "heatcvt/errors.h"
#include "heatcvt/grid_cell.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

using Cell = GridCell;
using CellHash = GridCellHash;

// Voxel slots by cell: open addressing with linear probing in a power-of-two table kept at most
// half full. A lookup touches one or two neighbouring entries where a node-based map follows a
// bucket and a node pointer: the binning of points that arrive in random order is bound by these
// cache misses. Slots are handed out by the caller (the voxels' insertion order).
class FlatCellIndex {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  FlatCellIndex() { table_.resize(16); mask_ = 15; }
  // The slot of `key`, or kNone.
  std::uint32_t find(const Cell& key) const {
    for (std::size_t i = CellHash()(key) & mask_;; i = (i + 1) & mask_) {
      const Entry& e = table_[i];
      if (e.slot == kNone) return kNone;
      if (e.key == key) return e.slot;
    }
  }
  // The slot of `key`; where absent, `next` is stored for it and `inserted` set.
  std::uint32_t find_or_insert(const Cell& key, std::uint32_t next, bool& inserted) {
    inserted = false;
    for (std::size_t i = CellHash()(key) & mask_;; i = (i + 1) & mask_) {
      Entry& e = table_[i];
      if (e.slot != kNone && e.key == key) return e.slot;
      if (e.slot == kNone) {
        e = {key, next};
        inserted = true;
        if (2 * ++size_ > table_.size()) grow();
        return next;
      }
    }
  }

 private:
  struct Entry {
    Cell key{};
    std::uint32_t slot = kNone;
  };
  void grow() {
    std::vector<Entry> old(table_.size() * 2);
    old.swap(table_);
    mask_ = table_.size() - 1;
    for (const Entry& e : old)
      if (e.slot != kNone) {
        std::size_t i = CellHash()(e.key) & mask_;
        while (table_[i].slot != kNone) i = (i + 1) & mask_;
        table_[i] = e;
      }
  }
  std::vector<Entry> table_;
  std::size_t size_ = 0, mask_ = 0;
};

// Cells beyond ±2^52 would lose integer exactness in the double → int conversion.
constexpr double kMaxCell = 4503599627370496.0;

// The cell of a point whose cell is known to be in range (cell_of() has seen it).
Cell cell_in_range(double x, double y, double z, double inv_h) {
  return {static_cast<std::int64_t>(std::floor(x * inv_h)), static_cast<std::int64_t>(std::floor(y * inv_h)),
          static_cast<std::int64_t>(std::floor(z * inv_h))};
}

Cell cell_of(double x, double y, double z, double inv_h) {
  for (double v : {x * inv_h, y * inv_h, z * inv_h})
    if (!(std::abs(std::floor(v)) < kMaxCell))
      throw InvalidInputError("VoxelSummary: coordinate / voxel size exceeds the integer cell range (2^52)");
  return cell_in_range(x, y, z, inv_h);
}

// Occupied cells of size h: the cells as 63-bit keys (21 bits per axis, relative to the smallest
// cell) sorted and counted, or a hash set when the cloud spans more than 2^21 cells on an axis.
Eigen::Index occupied_voxels(const Eigen::MatrixX3d& P, double h, int threads) {
  const double inv_h = 1.0 / h;
  const Eigen::Index n = P.rows();
  if (n == 0) return 0;
  const Eigen::RowVector3d lo = P.colwise().minCoeff(), hi = P.colwise().maxCoeff();
  const Cell c0 = cell_of(lo(0), lo(1), lo(2), inv_h), c1 = cell_of(hi(0), hi(1), hi(2), inv_h);
  constexpr std::int64_t kAxis = std::int64_t{1} << 21;
  if (c1[0] - c0[0] < kAxis && c1[1] - c0[1] < kAxis && c1[2] - c0[2] < kAxis) {
    std::vector<std::uint64_t> keys(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Cell c = cell_of(P(i, 0), P(i, 1), P(i, 2), inv_h);
      keys[static_cast<std::size_t>(i)] = static_cast<std::uint64_t>(c[0] - c0[0]) << 42 |
                                          static_cast<std::uint64_t>(c[1] - c0[1]) << 21 |
                                          static_cast<std::uint64_t>(c[2] - c0[2]);
    }
    std::sort(keys.begin(), keys.end());
    return static_cast<Eigen::Index>(std::unique(keys.begin(), keys.end()) - keys.begin());
  }
  std::unordered_set<Cell, CellHash> cells;
  cells.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) cells.insert(cell_of(P(i, 0), P(i, 1), P(i, 2), inv_h));
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
  FlatCellIndex index;
  std::vector<Cell> cell;
  std::vector<Moments> moments;
  mutable std::vector<std::uint32_t> order;
  mutable bool order_valid = false;
};

VoxelSummary::VoxelSummary(double voxel_size, int threads)
    : h_(voxel_size), inv_h_(1.0 / voxel_size), threads_(resolve_threads(threads)), impl_(std::make_unique<Impl>()) {
  if (!(std::isfinite(voxel_size) && voxel_size > 0))
    throw InvalidInputError("VoxelSummary: voxel_size must be finite and > 0 (got " + std::to_string(voxel_size) + ")");
}
VoxelSummary::~VoxelSummary() = default;
VoxelSummary::VoxelSummary(VoxelSummary&&) noexcept = default;
VoxelSummary& VoxelSummary::operator=(VoxelSummary&&) noexcept = default;

void VoxelSummary::add(const CloudChunk& chunk) { add(chunk.P, chunk.has_colours() ? chunk.C : Eigen::MatrixX3d(0, 3)); }

void VoxelSummary::add(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C) { add_weighted(P, C, 1); }

namespace {

// Chunks of at least this many points are binned on all threads.
constexpr Eigen::Index kParallelBinning = 16384;

// Adds `weight` copies of point (x, y, z) of cell `key` (corner key·h) with colour (3 values or
// null) to the voxel's moments.
void accumulate(Moments& v, const Cell& key, double h, double x, double y, double z, const double* colour,
                std::int64_t weight) {
  const double w = static_cast<double>(weight);
  const double d[3] = {x - static_cast<double>(key[0]) * h, y - static_cast<double>(key[1]) * h,
                       z - static_cast<double>(key[2]) * h};
  v.count += weight;
  for (int k = 0; k < 3; ++k) v.s[k] += w * d[k];
  v.ss[0] += w * d[0] * d[0];
  v.ss[1] += w * d[0] * d[1];
  v.ss[2] += w * d[0] * d[2];
  v.ss[3] += w * d[1] * d[1];
  v.ss[4] += w * d[1] * d[2];
  v.ss[5] += w * d[2] * d[2];
  if (colour)
    for (int k = 0; k < 3; ++k) v.c[k] += w * colour[k];
}

}  // namespace

std::uint32_t VoxelSummary::slot_of(const Cell& key) {
  Impl& m = *impl_;
  bool inserted = false;
  const std::uint32_t slot = m.index.find_or_insert(key, static_cast<std::uint32_t>(m.moments.size()), inserted);
  if (inserted) {
    m.cell.push_back(key);
    m.moments.emplace_back();
  }
  return slot;
}

// In two steps: the voxel of each point, in input order (new voxels are numbered as they appear),
// then the moments, each thread taking the voxels of one residue class of their numbers and the
// points of each voxel in input order. Every voxel's sums are those of one loop over the points,
// whatever the number of threads.
void VoxelSummary::add_weighted(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& C, std::int64_t weight) {
  const bool colours = C.rows() == P.rows() && P.rows() > 0;
  Impl& m = *impl_;
  m.order_valid = false;
  const Eigen::Index n = P.rows();
  std::vector<std::uint32_t> slot(static_cast<std::size_t>(n), FlatCellIndex::kNone);
  std::int64_t finite = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(std::isfinite(P(i, 0)) && std::isfinite(P(i, 1)) && std::isfinite(P(i, 2)))) continue;
    slot[static_cast<std::size_t>(i)] = slot_of(cell_of(P(i, 0), P(i, 1), P(i, 2), inv_h_));
    ++finite;
  }
#pragma omp parallel num_threads(n >= kParallelBinning ? threads_ : 1)
  {
    const auto t = static_cast<std::uint32_t>(omp_get_thread_num());
    const auto threads = static_cast<std::uint32_t>(omp_get_num_threads());
    for (Eigen::Index i = 0; i < n; ++i) {
      const std::uint32_t s = slot[static_cast<std::size_t>(i)];
      if (s == FlatCellIndex::kNone || s % threads != t) continue;
      const double c[3] = {colours ? C(i, 0) : 0.0, colours ? C(i, 1) : 0.0, colours ? C(i, 2) : 0.0};
      accumulate(m.moments[s], cell_in_range(P(i, 0), P(i, 1), P(i, 2), inv_h_), h_, P(i, 0), P(i, 1), P(i, 2),
                 colours ? c : nullptr, weight);
    }
  }
  skipped_ += (n - finite) * weight;
  added_ += finite * weight;
  if (colours) coloured_ += finite * weight;
}

void VoxelSummary::add_point(double x, double y, double z, const double* colour, std::int64_t weight) {
  if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z))) {
    skipped_ += weight;
    return;
  }
  impl_->order_valid = false;
  const Cell key = cell_of(x, y, z, inv_h_);
  accumulate(impl_->moments[slot_of(key)], key, h_, x, y, z, colour, weight);
  if (colour) coloured_ += weight;
  added_ += weight;
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

// Moments of a neighbourhood, relative to one origin `o` (a cell corner).
struct MergedMoments {
  double n = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  // Adds moments (k points, Σ(p − c), Σ(p − c)(p − c)ᵀ) taken relative to a corner c displaced
  // by d from o: p − o = (p − c) + d.
  void add(double k, const Eigen::Vector3d& vs, const Eigen::Matrix3d& vss, const Eigen::Vector3d& d) {
    n += k;
    s += vs + k * d;
    ss += vss + vs * d.transpose() + d * vs.transpose() + k * d * d.transpose();
  }
  void add(const Moments& v, const Eigen::Vector3d& d) {
    Eigen::Matrix3d vss;
    vss << v.ss[0], v.ss[1], v.ss[2], v.ss[1], v.ss[3], v.ss[4], v.ss[2], v.ss[4], v.ss[5];
    add(static_cast<double>(v.count), Eigen::Vector3d(v.s[0], v.s[1], v.s[2]), vss, d);
  }
  void add(const MergedMoments& v, const Eigen::Vector3d& d) { add(v.n, v.s, v.ss, d); }
};

// The cell of `c` at a level with cells 2^level times larger (floor division).
Cell coarse_cell(const Cell& c, int level) { return {c[0] >> level, c[1] >> level, c[2] >> level}; }

// The plane fitted to merged moments: mean μ and unit normal (smallest-eigenvalue eigenvector),
// with λ0/λ1 as `ratio`. False when there are < 3 points or they lie on a line.
bool fit_plane(const MergedMoments& nb, Eigen::Vector3d& mu, Eigen::Vector3d& normal, double& ratio) {
  if (nb.n < 3) return false;
  mu = nb.s / nb.n;
  const Eigen::Matrix3d cov = nb.ss / nb.n - mu * mu.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d lambda = eig.eigenvalues();
  if (!(lambda(1) > kCollinearRatio * lambda(2))) return false;
  normal = eig.eigenvectors().col(0);
  ratio = std::max(0.0, lambda(0)) / lambda(1);
  return true;
}

// Moments of the 3×3×3 voxels around cell `centre`, relative to the corner of cell `origin`.
MergedMoments voxel_neighbourhood(const FlatCellIndex& index, const std::vector<Moments>& moments, double h,
                                  const Cell& centre, const Cell& origin) {
  MergedMoments nb;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        const Cell n = {centre[0] + dx, centre[1] + dy, centre[2] + dz};
        const std::uint32_t slot = index.find(n);
        if (slot == FlatCellIndex::kNone) continue;
        const Eigen::Vector3d d(static_cast<double>(n[0] - origin[0]), static_cast<double>(n[1] - origin[1]),
                                static_cast<double>(n[2] - origin[2]));
        nb.add(moments[slot], h * d);
      }
  return nb;
}

// Calls visit(i, j) for every i in [begin, end) and every j whose cell lies in the 3×3×3 block
// around cells[i]. `cells` is sorted lexicographically and unique: the block's 9 (dx, dy) columns
// are contiguous runs, and as i advances each column's start only moves forward (lexicographic
// order is translation invariant), so one forward pointer per column replaces 27 hash lookups.
template <class Visit>
void for_each_block_neighbour(const std::vector<Cell>& cells, std::size_t begin, std::size_t end, Visit&& visit) {
  const std::size_t n = cells.size();
  if (begin >= end) return;
  std::size_t ptr[9];
  for (int q = 0; q < 9; ++q) {
    const Cell& c = cells[begin];
    const Cell lo = {c[0] + q / 3 - 1, c[1] + q % 3 - 1, c[2] - 1};
    ptr[q] = static_cast<std::size_t>(std::lower_bound(cells.begin(), cells.end(), lo) - cells.begin());
  }
  for (std::size_t i = begin; i < end; ++i) {
    const Cell& c = cells[i];
    for (int q = 0; q < 9; ++q) {
      const Cell lo = {c[0] + q / 3 - 1, c[1] + q % 3 - 1, c[2] - 1};
      const Cell hi = {lo[0], lo[1], c[2] + 1};
      while (ptr[q] < n && cells[ptr[q]] < lo) ++ptr[q];
      for (std::size_t j = ptr[q]; j < n && !(hi < cells[j]); ++j) visit(i, j);
    }
  }
}

// The plane fit of every cell's 3×3×3 block of `merged` moments (each relative to its own cell's
// corner, cells of size `size`), in the order of `cells`; normal and λ0/λ1 per cell, ok = false
// where fit_plane() fails. Also the block mean relative to the cell's corner (where it has points).
struct BlockFits {
  std::vector<Eigen::Vector3d> mu, normal;
  std::vector<double> ratio;
  std::vector<char> ok;
};
// `moments_of(j)`: the moments of cell j (Moments or MergedMoments).
template <class MomentsOf>
BlockFits block_fits(const std::vector<Cell>& cells, const MomentsOf& moments_of, double size, int threads) {
  const std::size_t n = cells.size();
  BlockFits out;
  out.mu.assign(n, Eigen::Vector3d::Zero());
  out.normal.assign(n, Eigen::Vector3d::Zero());
  out.ratio.assign(n, 0.0);
  out.ok.assign(n, 0);
  constexpr std::size_t kChunk = 4096;
  const auto chunks = static_cast<std::int64_t>((n + kChunk - 1) / kChunk);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::int64_t k = 0; k < chunks; ++k) {
    const std::size_t begin = static_cast<std::size_t>(k) * kChunk, end = std::min(n, begin + kChunk);
    MergedMoments nb;
    std::size_t current = begin;
    auto finish = [&](std::size_t i) {
      out.ok[i] = fit_plane(nb, out.mu[i], out.normal[i], out.ratio[i]);
      if (!out.ok[i] && nb.n > 0) out.mu[i] = nb.s / nb.n;
      nb = MergedMoments();
    };
    for_each_block_neighbour(cells, begin, end, [&](std::size_t i, std::size_t j) {
      if (i != current) finish(current), current = i;
      const Eigen::Vector3d d(static_cast<double>(cells[j][0] - cells[i][0]), static_cast<double>(cells[j][1] - cells[i][1]),
                              static_cast<double>(cells[j][2] - cells[i][2]));
      nb.add(moments_of(j), size * d);
    });
    finish(current);
  }
  return out;
}

// Level `level` of the voxels (cells 2^level voxels wide): the coarse cells (sorted, unique),
// their merged moments (relative to their own corner) and the coarse cell of each voxel.
struct CoarseGrid {
  std::vector<Cell> cells;
  std::vector<MergedMoments> merged;
  std::vector<std::uint32_t> of_voxel;  // by position in the sorted voxel order
};
template <class MomentsOf>
CoarseGrid coarse_grid(const std::vector<Cell>& voxels, const MomentsOf& moments_of, double h, int level) {
  const std::size_t n = voxels.size();
  std::vector<std::uint32_t> by_coarse(n);
  std::iota(by_coarse.begin(), by_coarse.end(), 0u);
  std::vector<Cell> coarse(n);
  for (std::size_t r = 0; r < n; ++r) coarse[r] = coarse_cell(voxels[r], level);
  // stable: voxels of one coarse cell are merged in their sorted order, whatever the sort does
  std::stable_sort(by_coarse.begin(), by_coarse.end(), [&](std::uint32_t a, std::uint32_t b) { return coarse[a] < coarse[b]; });
  CoarseGrid g;
  g.of_voxel.resize(n);
  const std::int64_t scale = std::int64_t{1} << level;
  for (const std::uint32_t r : by_coarse) {
    const Cell& cc = coarse[r];
    if (g.cells.empty() || g.cells.back() != cc) g.cells.push_back(cc), g.merged.emplace_back();
    const Cell& c = voxels[r];
    const Eigen::Vector3d d(static_cast<double>(c[0] - cc[0] * scale), static_cast<double>(c[1] - cc[1] * scale),
                            static_cast<double>(c[2] - cc[2] * scale));
    g.merged.back().add(moments_of(r), h * d);
    g.of_voxel[r] = static_cast<std::uint32_t>(g.cells.size() - 1);
  }
  return g;
}

}  // namespace

// Each voxel mean projected on the plane fitted to its 3×3×3 neighbourhood (with the normal of
// the finest level where the neighbourhood is a plane), then mean-shifted along that normal where
// the noise band is thick; absolute coordinates, with its point count and mean colour.
void VoxelSummary::project_means(const VoxelSurfaceFit& fit, Eigen::MatrixX3d& P, Eigen::VectorXd& w,
                                 Eigen::MatrixX3d& C) const {
  const Impl& m = *impl_;
  const auto& ord = order();
  const std::size_t n = ord.size();
  const auto rows = static_cast<Eigen::Index>(n);
  const bool with_colours = has_colours();
  P.resize(rows, 3);
  w.resize(rows);
  C.resize(with_colours ? rows : 0, 3);
  // The voxels in sorted order (position r), and r of each voxel index.
  std::vector<Cell> cells(n);
  std::vector<std::uint32_t> rank(n);
  for (std::size_t r = 0; r < n; ++r) {
    cells[r] = m.cell[ord[r]];
    rank[ord[r]] = static_cast<std::uint32_t>(r);
  }
  const auto voxel_moments = [&](std::size_t r) -> const Moments& { return m.moments[ord[r]]; };
  const BlockFits local = block_fits(cells, voxel_moments, h_, threads_);
  // Widen only in a noise regime: where most neighbourhoods are no plane. Where few are, they are
  // edges, clutter and depth steps, which a wider plane does not describe.
  std::size_t thick_voxels = 0;
  for (std::size_t r = 0; r < n; ++r) thick_voxels += local.ok[r] && local.ratio[r] > fit.planarity;
  const int levels =
      static_cast<double>(thick_voxels) >= fit.min_thick_fraction * static_cast<double>(n) ? fit.max_levels : 0;
  std::vector<CoarseGrid> grids;
  std::vector<BlockFits> wide;
  for (int level = 1; level <= levels; ++level) {
    grids.push_back(coarse_grid(cells, voxel_moments, h_, level));
    const CoarseGrid& g = grids.back();
    wide.push_back(block_fits(g.cells, [&](std::size_t j) -> const MergedMoments& { return g.merged[j]; },
                              h_ * static_cast<double>(std::int64_t{1} << level), threads_));
  }
#pragma omp parallel for schedule(dynamic, 4096) num_threads(threads_)
  for (Eigen::Index ri = 0; ri < rows; ++ri) {
    const auto r = static_cast<std::size_t>(ri);
    const Cell& c = cells[r];
    const Moments& v = m.moments[ord[r]];
    const double k = static_cast<double>(v.count);
    Eigen::Vector3d mean(v.s[0] / k, v.s[1] / k, v.s[2] / k);  // relative to the corner
    const bool have = local.ok[r] != 0;
    Eigen::Vector3d normal = local.normal[r];
    const bool thick = have && local.ratio[r] > fit.planarity;
    // Only the wide normal is taken: μ stays local (a wide plane's μ would merge the two sides of
    // a thin part).
    bool widened = false;
    for (int level = 1; thick && level <= levels; ++level) {
      const BlockFits& f = wide[static_cast<std::size_t>(level - 1)];
      const std::uint32_t g = grids[static_cast<std::size_t>(level - 1)].of_voxel[r];
      if (f.ok[g] && f.ratio[g] <= fit.planarity) {
        normal = f.normal[g];
        widened = true;
        break;
      }
    }
    if (have) mean -= (mean - local.mu[r]).dot(normal) * normal;
    // In a thick noise band on a surface that is a plane at the wider scale, the local μ still
    // leans to the voxel's side of the band: shift along the normal to the mean of the voxel
    // neighbourhood around the projected point, which moves it towards the middle of the band (a
    // mean shift with a box kernel 3 voxels wide). Not where no wider level is a plane (tips,
    // thin parts, creases): there the neighbourhood mean lies inside the bend and the shift
    // would shrink the part.
    for (int step = 0; widened && step < fit.shift_steps; ++step) {
      const Cell off = {static_cast<std::int64_t>(std::floor(mean(0) / h_)),
                        static_cast<std::int64_t>(std::floor(mean(1) / h_)),
                        static_cast<std::int64_t>(std::floor(mean(2) / h_))};
      const Cell at = {c[0] + off[0], c[1] + off[1], c[2] + off[2]};
      Eigen::Vector3d around;  // neighbourhood mean of `at`, relative to c's corner
      const std::uint32_t slot = m.index.find(at);
      if (slot != FlatCellIndex::kNone) {
        around = local.mu[rank[slot]] + h_ * Eigen::Vector3d(static_cast<double>(off[0]),
                                                                  static_cast<double>(off[1]),
                                                                  static_cast<double>(off[2]));
      } else {
        const MergedMoments nb = voxel_neighbourhood(m.index, m.moments, h_, at, c);
        if (nb.n < 3) break;
        around = nb.s / nb.n;
      }
      mean -= (mean - around).dot(normal) * normal;
    }
    for (int a = 0; a < 3; ++a) P(ri, a) = static_cast<double>(c[static_cast<std::size_t>(a)]) * h_ + mean(a);
    w(ri) = k;
    if (with_colours)
      for (int a = 0; a < 3; ++a) C(ri, a) = v.c[a] / k;
  }
}

Eigen::MatrixX3d VoxelSummary::surface_points(Eigen::Index target_points, Eigen::VectorXi* weights,
                                              Eigen::MatrixX3d* colours, const VoxelSurfaceFit& fit) const {
  if (!(fit.planarity >= 0) || fit.max_levels < 0 || fit.max_levels > 16 || fit.shift_steps < 0 ||
      !(fit.min_thick_fraction >= 0 && fit.min_thick_fraction <= 1))
    throw InvalidInputError("VoxelSummary::surface_points: planarity must be >= 0, max_levels in [0, 16], shift_steps "
                            ">= 0 and min_thick_fraction in [0, 1]");
  Eigen::MatrixX3d P, C;
  Eigen::VectorXd w;
  project_means(fit, P, w, C);
  // The rebinning size: the voxel size, or the smallest multiple of it (bisection in log scale)
  // whose occupied cells are at most target_points.
  double size = h_;
  if (target_points > 0 && P.rows() > target_points) {
    double lo = h_, hi = 2 * h_;
    while (occupied_voxels(P, hi, threads_) > target_points) lo = hi, hi *= 2;
    for (int it = 0; it < kRebinBisections; ++it) {
      const double mid = std::sqrt(lo * hi);
      (occupied_voxels(P, mid, threads_) > target_points ? lo : hi) = mid;
    }
    size = hi;
  }
  VoxelSummary rebinned(size, threads_);
  for (Eigen::Index r = 0; r < P.rows(); ++r) {
    const double c[3] = {C.rows() ? C(r, 0) : 0.0, C.rows() ? C(r, 1) : 0.0, C.rows() ? C(r, 2) : 0.0};
    rebinned.add_point(P(r, 0), P(r, 1), P(r, 2), C.rows() ? c : nullptr, static_cast<std::int64_t>(w(r)));
  }
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
  const int threads = resolve_threads(options.threads);
  Eigen::Index count = occupied_voxels(P, h, threads);
  for (int it = 1; it < options.probe_iterations; ++it) {
    const double next = h * std::sqrt(static_cast<double>(count) / target);
    if (std::abs(next - h) <= 1e-3 * h) break;
    h = next;
    count = occupied_voxels(P, h, threads);
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
