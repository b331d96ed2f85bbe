#include "heatcvt/localized_solve.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "heatcvt/errors.h"

namespace heatcvt {

void LocalizedWorkspace::resize(int n) {
  if (static_cast<int>(mark_.size()) == n) return;
  forward_.assign(n, 0.0);
  back_.assign(n, 0.0);
  mark_.assign(n, 0);
  local_.assign(n, -1);
  reach_.clear();
  path_.clear();
  positions_.clear();
}

LocalizedSolver::LocalizedSolver(const CholeskyFactor& factor, const LocalizedSolveOptions& options)
    : L_(&factor), options_(options) {
  const int n = factor.n;
  if (n <= 0) throw InvalidInputError("LocalizedSolver: empty factor");
  if (static_cast<int>(factor.parent.size()) != n || static_cast<int>(factor.perm.size()) != n ||
      static_cast<int>(factor.inverse_perm.size()) != n || static_cast<int>(factor.col_ptr.size()) != n + 1)
    throw InvalidInputError("LocalizedSolver: factor arrays have inconsistent sizes");
  for (int j = 0; j < n; ++j)
    if (factor.parent[j] != -1 && factor.parent[j] <= j)
      throw InvalidInputError("LocalizedSolver: elimination tree parent of column " + std::to_string(j) +
                              " is not above it");
  if (!(options.drop_tolerance >= 0) || !std::isfinite(options.drop_tolerance))
    throw InvalidInputError("LocalizedSolver: drop_tolerance must be finite and >= 0");
}

LocalizedSolver::LocalizedSolver(const HeatSolver& solver, const LocalizedSolveOptions& options)
    : LocalizedSolver(solver.factor(), options) {}

void LocalizedSolver::check_rhs(const std::vector<std::pair<int, double>>& rhs) const {
  for (const auto& [i, v] : rhs) {
    if (i < 0 || i >= L_->n)
      throw InvalidInputError("LocalizedSolver: right-hand side vertex " + std::to_string(i) + " out of range [0, " +
                              std::to_string(L_->n) + ")");
    (void)v;
  }
}

// Reach of the non-zeros in a topological order (CSparse's ereach idea): walk up from each start
// until a marked column, then put that path segment in front of everything collected so far.
// Every column ends up before its ancestors. Marks stay set (the caller clears them).
void LocalizedSolver::collect_reach(const std::vector<std::pair<int, double>>& rhs, LocalizedWorkspace& ws) const {
  const int* parent = L_->parent.data();
  auto& stack = ws.path_;  // reach built in reverse, segments appended reversed
  stack.clear();
  for (const auto& entry : rhs) {
    int j = L_->inverse_perm[entry.first];
    const size_t segment_start = stack.size();
    while (j != -1 && !ws.mark_[j]) {
      ws.mark_[j] = 1;
      stack.push_back(j);
      j = parent[j];
    }
    std::reverse(stack.begin() + segment_start, stack.end());
  }
  // stack = seg1(top→bottom), seg2(top→bottom), ...; reading it backwards gives
  // segk(bottom→top), ..., seg1(bottom→top): a topological order.
  ws.reach_.assign(stack.rbegin(), stack.rend());
}

void LocalizedSolver::sort_positions(const std::vector<int>& indices, LocalizedWorkspace& ws) const {
  ws.order_.resize(indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    const int v = indices[i];
    if (v < 0 || v >= L_->n)
      throw InvalidInputError("LocalizedSolver: requested vertex " + std::to_string(v) + " out of range [0, " +
                              std::to_string(L_->n) + ")");
    ws.order_[i] = {L_->inverse_perm[v], static_cast<int>(i)};
  }
  std::sort(ws.order_.begin(), ws.order_.end(),
            [](const std::pair<int, int>& a, const std::pair<int, int>& b) { return a.first > b.first; });
  for (size_t i = 1; i < ws.order_.size(); ++i)
    if (ws.order_[i].first == ws.order_[i - 1].first)
      throw InvalidInputError("LocalizedSolver: vertex " + std::to_string(L_->perm[ws.order_[i].first]) +
                              " requested twice");
}

// Algorithm 1: y_k = (a_k − Σ_{p} T_{row p, k} y_{row p}) / T_kk for k ∈ I in decreasing order,
// with y = 0 outside I (ws.back_ is zero there). `a` is the dense forward vector.
void LocalizedSolver::back_restricted(const double* a, const std::vector<int>& indices, std::vector<double>& values,
                                      LocalizedWorkspace& ws) const {
  const int64_t* cp = L_->col_ptr.data();
  const int* row = L_->row.data();
  const double* val = L_->value.data();
  double* y = ws.back_.data();
  size_t entries = 0;
  for (const auto& [k, slot] : ws.order_) {
    const int64_t b = cp[k], e = cp[k + 1];
    double s = a[k];
    for (int64_t p = b + 1; p < e; ++p) s -= val[p] * y[row[p]];
    y[k] = s / val[b];
    entries += static_cast<size_t>(e - b);
    (void)slot;
  }
  values.resize(indices.size());
  for (const auto& [k, slot] : ws.order_) {
    values[slot] = y[k];
    y[k] = 0.0;  // reset only what we touched
  }
  ws.stats_.back_rows = indices.size();
  ws.stats_.back_entries = entries;
}

void LocalizedSolver::solve(const std::vector<std::pair<int, double>>& rhs, const std::vector<int>& indices,
                            std::vector<double>& values, LocalizedWorkspace& ws) const {
  ws.resize(L_->n);
  check_rhs(rhs);
  sort_positions(indices, ws);
  ws.stats_ = {};

  // Forward solve over the reach.
  collect_reach(rhs, ws);
  double* a = ws.forward_.data();
  for (const auto& [i, v] : rhs) a[L_->inverse_perm[i]] += v;
  const int64_t* cp = L_->col_ptr.data();
  const int* row = L_->row.data();
  const double* val = L_->value.data();
  const double tol = options_.drop_tolerance;
  double amax = 0.0;
  size_t entries = 0;
  for (int j : ws.reach_) {
    // Most of the reach is the path up the elimination tree to its root, where nothing arrives
    // once the drop tolerance has cut the heat off: such a node is passed over without loading
    // its column.
    if (a[j] == 0.0) continue;
    const int64_t b = cp[j], e = cp[j + 1];
    const double aj = (a[j] /= val[b]);
    const double mag = std::abs(aj);
    if (mag > amax) amax = mag;
    if (aj == 0.0 || mag <= tol * amax) continue;
    for (int64_t p = b + 1; p < e; ++p) a[row[p]] -= val[p] * aj;
    entries += static_cast<size_t>(e - b);
  }
  ws.stats_.reach = ws.reach_.size();
  ws.stats_.forward_entries = entries;

  back_restricted(a, indices, values, ws);
  for (int j : ws.reach_) {
    a[j] = 0.0;
    ws.mark_[j] = 0;
  }
}

std::vector<double> LocalizedSolver::solve(const std::vector<std::pair<int, double>>& rhs,
                                           const std::vector<int>& indices, LocalizedWorkspace& ws) const {
  std::vector<double> values;
  solve(rhs, indices, values, ws);
  return values;
}

void LocalizedSolver::solve_batch(const std::vector<std::vector<std::pair<int, double>>>& rhs,
                                  const std::vector<std::vector<int>>& indices,
                                  std::vector<std::vector<double>>& values, LocalizedWorkspace& ws) const {
  if (rhs.size() != indices.size())
    throw InvalidInputError("LocalizedSolver::solve_batch: " + std::to_string(rhs.size()) +
                            " right-hand sides but " + std::to_string(indices.size()) + " index sets");
  ws.resize(L_->n);
  for (const auto& r : rhs) check_rhs(r);
  for (const auto& I : indices) sort_positions(I, ws);  // validates ranges and duplicates up front
  values.resize(rhs.size());
  const int64_t* cp = L_->col_ptr.data();
  const int* row = L_->row.data();
  const double* val = L_->value.data();
  const double tol = options_.drop_tolerance;
  constexpr int B = kMaxBatch;
  std::vector<std::pair<int, double>> all;
  LocalizedSolveStats total;
  for (size_t first = 0; first < rhs.size(); first += B) {
    const int width = static_cast<int>(std::min<size_t>(B, rhs.size() - first));
    all.clear();
    for (int s = 0; s < width; ++s) all.insert(all.end(), rhs[first + s].begin(), rhs[first + s].end());
    collect_reach(all, ws);
    const int r = static_cast<int>(ws.reach_.size());
    for (int q = 0; q < r; ++q) ws.local_[ws.reach_[q]] = q;
    ws.block_.assign(static_cast<size_t>(r) * B, 0.0);
    double* blk = ws.block_.data();
    for (int s = 0; s < width; ++s)
      for (const auto& [i, v] : rhs[first + s]) blk[static_cast<size_t>(ws.local_[L_->inverse_perm[i]]) * B + s] += v;
    double amax = 0.0;
    size_t entries = 0;
    for (int q = 0; q < r; ++q) {
      const int j = ws.reach_[q];
      const int64_t b = cp[j], e = cp[j + 1];
      const double d = 1.0 / val[b];
      double aj[B];
      double mag = 0.0;
      for (int s = 0; s < B; ++s) {
        aj[s] = (blk[static_cast<size_t>(q) * B + s] *= d);
        mag = std::max(mag, std::abs(aj[s]));
      }
      if (mag > amax) amax = mag;
      if (mag == 0.0 || mag <= tol * amax) continue;
      for (int64_t p = b + 1; p < e; ++p) {
        double* target = blk + static_cast<size_t>(ws.local_[row[p]]) * B;
        const double v = val[p];
        for (int s = 0; s < B; ++s) target[s] -= v * aj[s];
      }
      entries += static_cast<size_t>(e - b);
    }
    total.reach += static_cast<size_t>(r);
    total.forward_entries += entries;
    // One restricted back solve per source on its own set.
    double* a = ws.forward_.data();
    for (int s = 0; s < width; ++s) {
      for (int q = 0; q < r; ++q) a[ws.reach_[q]] = blk[static_cast<size_t>(q) * B + s];
      sort_positions(indices[first + s], ws);
      back_restricted(a, indices[first + s], values[first + s], ws);
      total.back_rows += ws.stats_.back_rows;
      total.back_entries += ws.stats_.back_entries;
    }
    for (int j : ws.reach_) {
      a[j] = 0.0;
      ws.mark_[j] = 0;
      ws.local_[j] = -1;
    }
  }
  ws.stats_ = total;
}

}  // namespace heatcvt
