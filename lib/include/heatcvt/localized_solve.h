#pragma once
/// \file localized_solve.h
/// Localized solves on the heat solver's Cholesky factor (paper §6, Algorithm 1).
///
/// With `P A Pᵀ = T Tᵀ` (A = M − t L, see heat_solver.h) a diffusion is `T a = P b` followed by
/// `Tᵀ y = a`, `u = Pᵀ y`.
///  - Forward: for a sparse b only the columns on the elimination-tree paths from the non-zeros
///    of b to the roots (the *reach*) can become non-zero. We visit exactly those columns, in a
///    topological order of the tree (every column before its ancestors).
///  - Back: heat is global, but far values are negligible. Algorithm 1 computes y only at the
///    elimination positions of a caller-given index set I, in decreasing position order, and
///    treats every y outside I as 0. With I = all vertices this is the exact solve; for a
///    local I the error concentrates at the border of I (Fig. 6). Cost ∝ Σ_{k∈I} |column k|.
///
/// Optional pruning (`drop_tolerance`): the forward vector a = T⁻¹ P b of a well-conditioned
/// heat matrix decays quickly away from the source; columns whose value is below
/// `drop_tolerance · max|a|` are not scattered. This keeps the work local even though every
/// reach contains the top separators of the nested-dissection ordering.
///
/// Workspaces are reused (one per thread); they are never cleared in O(n): only the entries
/// a solve touched are reset afterwards.
#include <cstddef>
#include <utility>
#include <vector>

#include "heatcvt/heat_solver.h"

namespace heatcvt {

/// Options of the localized solves.
struct LocalizedSolveOptions {
  /// Forward columns with |a_j| ≤ drop_tolerance · max_k |a_k| (max over the columns visited so
  /// far) are not scattered into their ancestors. 0 = exact forward solve. Default 1e-12: a
  /// single-source forward solve then visits a small part of the factor, with results equal to
  /// the exact solve to about 1e-12 relative (bench_localized; docs/benchmarks.md).
  double drop_tolerance = 1e-12;
};

/// Work counters of the last localized solve (for benchmarks and tests).
struct LocalizedSolveStats {
  size_t reach = 0;            ///< elimination-tree columns visited by the forward solve
  size_t forward_entries = 0;  ///< factor entries read by the forward solve
  size_t back_rows = 0;        ///< rows computed by the back solve (= |I|)
  size_t back_entries = 0;     ///< factor entries read by the back solve
};

/// Reusable scratch memory of a localized solve for a factor with n columns: dense arrays of
/// length n that are zero between solves, plus small stacks. Not thread-safe: use one per thread.
class LocalizedWorkspace {
 public:
  LocalizedWorkspace() = default;
  explicit LocalizedWorkspace(int n) { resize(n); }
  /// Sizes the workspace for a factor with n columns (no-op if already that size).
  void resize(int n);
  int size() const { return static_cast<int>(mark_.size()); }
  /// Counters of the last solve done with this workspace.
  const LocalizedSolveStats& stats() const { return stats_; }

 private:
  friend class LocalizedSolver;
  std::vector<double> forward_;       ///< a (forward values), zero outside the touched reach
  std::vector<double> back_;          ///< y on I, zero elsewhere
  std::vector<unsigned char> mark_;   ///< reach membership, zero between solves
  std::vector<int> reach_;            ///< reach in topological order
  std::vector<int> path_;             ///< scratch for one tree path
  std::vector<int> positions_;        ///< elimination positions of I, sorted decreasingly
  std::vector<std::pair<int, int>> order_;  ///< (position, index into I) pairs
  std::vector<double> block_;         ///< interleaved values of a batch (reach-local numbering)
  std::vector<int> local_;            ///< position → slot in the batch (−1 outside), reset after use
  LocalizedSolveStats stats_;
};

/// Localized forward/back substitution on a Cholesky factor (does not own it; the factor must
/// outlive the solver). Thread-safe const: concurrent solves with distinct workspaces.
class LocalizedSolver {
 public:
  /// \throw InvalidInputError if the factor is empty or its parent/perm arrays are inconsistent.
  explicit LocalizedSolver(const CholeskyFactor& factor, const LocalizedSolveOptions& options = {});
  /// Convenience: the factor of the heat solver (which must outlive this object).
  explicit LocalizedSolver(const HeatSolver& solver, const LocalizedSolveOptions& options = {});

  int num_vertices() const { return L_->n; }
  const LocalizedSolveOptions& options() const { return options_; }

  /// Solves `(M − t L) u = b` for a sparse load vector b given as (original vertex, value) pairs
  /// (repeated vertices are summed) and returns u at the original vertices `indices` (any order,
  /// no duplicates): values[i] = u[indices[i]] (Algorithm 1). `values` is resized to |indices|.
  /// \throw InvalidInputError on out-of-range vertices or duplicated indices.
  void solve(const std::vector<std::pair<int, double>>& rhs, const std::vector<int>& indices,
             std::vector<double>& values, LocalizedWorkspace& workspace) const;

  /// Same, allocating the result.
  std::vector<double> solve(const std::vector<std::pair<int, double>>& rhs, const std::vector<int>& indices,
                            LocalizedWorkspace& workspace) const;

  /// Batch of k sources: one forward pass over the union of their reaches (the shared top of the
  /// elimination tree is read once for all of them, up to `kMaxBatch` at a time), then one
  /// restricted back solve per source on its own index set. values[s][i] = u_s[indices[s][i]].
  /// Results are identical to k calls of solve() up to rounding in the last bits.
  void solve_batch(const std::vector<std::vector<std::pair<int, double>>>& rhs,
                   const std::vector<std::vector<int>>& indices, std::vector<std::vector<double>>& values,
                   LocalizedWorkspace& workspace) const;

  /// Largest number of right-hand sides processed together by solve_batch().
  static constexpr int kMaxBatch = 8;

 private:
  void check_rhs(const std::vector<std::pair<int, double>>& rhs) const;
  void sort_positions(const std::vector<int>& indices, LocalizedWorkspace& ws) const;
  // Marks the reach of the given elimination positions into ws.reach_ (topological order).
  void collect_reach(const std::vector<std::pair<int, double>>& rhs, LocalizedWorkspace& ws) const;
  void back_restricted(const double* a, const std::vector<int>& indices, std::vector<double>& values,
                       LocalizedWorkspace& ws) const;

  const CholeskyFactor* L_;
  LocalizedSolveOptions options_;
};

}  // namespace heatcvt
