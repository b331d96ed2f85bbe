// Localized solves (paper §6, Algorithm 1) against full solves of the heat solver.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <queue>
#include <random>
#include <set>

#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/localized_solve.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Graph-geodesic cells of the given site vertices (multi-source Dijkstra on edge lengths) and the
// cell adjacency (cells sharing an edge). Built here independently of voronoi.cpp.
struct GraphCells {
  std::vector<int> label;
  std::vector<std::set<int>> adjacency;
  std::vector<std::vector<int>> vertices;
};

GraphCells graph_cells(const TriangleMesh& m, const std::vector<int>& sites) {
  const int n = static_cast<int>(m.V.rows());
  auto nbr = vertex_neighbors(n, m.F);
  GraphCells c;
  c.label.assign(n, -1);
  std::vector<double> dist(n, 1e300);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (size_t s = 0; s < sites.size(); ++s) {
    dist[sites[s]] = 0;
    c.label[sites[s]] = static_cast<int>(s);
    queue.push({0.0, sites[s]});
  }
  while (!queue.empty()) {
    auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    for (int w : nbr[v]) {
      const double nd = d + (m.V.row(v) - m.V.row(w)).norm();
      if (nd < dist[w]) {
        dist[w] = nd;
        c.label[w] = c.label[v];
        queue.push({nd, w});
      }
    }
  }
  c.adjacency.resize(sites.size());
  c.vertices.resize(sites.size());
  for (int v = 0; v < n; ++v) {
    c.vertices[c.label[v]].push_back(v);
    for (int w : nbr[v])
      if (c.label[w] != c.label[v]) c.adjacency[c.label[v]].insert(c.label[w]);
  }
  return c;
}

std::vector<int> random_vertices(int n, int k, unsigned seed) {
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(all.begin(), all.end(), rng);
  all.resize(k);
  return all;
}

}  // namespace

TEST(LocalizedSolve, AllVerticesEqualsFullSolve) {
  auto mesh = test::icosphere(4);
  Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
  HeatSolver solver(lap);
  LocalizedSolver local(solver);
  LocalizedWorkspace ws;
  const int n = solver.num_vertices();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::shuffle(all.begin(), all.end(), std::mt19937(3));  // any order of I
  // point source, 3-vertex barycentric source, and an area-like source on many vertices
  std::vector<std::vector<std::pair<int, double>>> sources = {
      {{17, 1.0}}, {{5, 0.2}, {100, 0.5}, {101, 0.3}}, {}};
  for (int v = 0; v < n; v += 7) sources[2].push_back({v, lap.M[v]});
  for (const auto& rhs : sources) {
    Eigen::VectorXd full = solver.solve_sparse(rhs);
    std::vector<double> u = local.solve(rhs, all, ws);
    double err = 0;
    for (int i = 0; i < n; ++i) err = std::max(err, std::abs(u[i] - full[all[i]]));
    EXPECT_LE(err, 1e-10 * full.cwiseAbs().maxCoeff());
    EXPECT_EQ(ws.stats().back_rows, static_cast<size_t>(n));
  }
  // A workspace reused many times gives the same numbers (touched entries were reset).
  std::vector<double> again = local.solve(sources[0], all, ws);
  std::vector<double> fresh_ws;
  LocalizedWorkspace fresh;
  local.solve(sources[0], all, fresh_ws, fresh);
  EXPECT_EQ(again, fresh_ws);
}

TEST(LocalizedSolve, ForwardVisitsOnlyTheReach) {
  auto mesh = test::icosphere(5);  // 10k vertices
  HeatSolver solver(cotan_laplacian(mesh.V, mesh.F));
  LocalizedSolveOptions exact_options;
  exact_options.drop_tolerance = 0.0;
  LocalizedSolver local(solver, exact_options);
  LocalizedWorkspace ws;
  const CholeskyFactor& L = solver.factor();
  const int v = 1234;
  local.solve({{v, 1.0}}, {v}, ws);
  // the reach is exactly the elimination-tree path from the source to its root
  size_t path = 0;
  for (int j = L.inverse_perm[v]; j != -1; j = L.parent[j]) ++path;
  EXPECT_EQ(ws.stats().reach, path);
  EXPECT_LT(ws.stats().reach, static_cast<size_t>(solver.num_vertices()) / 5);
  EXPECT_LT(ws.stats().forward_entries, L.nonzeros() / 2);
  EXPECT_EQ(ws.stats().back_rows, 1u);
}

TEST(LocalizedSolve, CellPlusTwoRingsIsAccurateInsideTheCell) {
  auto mesh = test::icosphere(5);
  test::scale_to_area(mesh, 1.0);
  Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
  HeatSolver solver(lap);  // t = h̄²
  LocalizedSolver local(solver);
  LocalizedWorkspace ws;
  const int n = solver.num_vertices();
  const auto sites = random_vertices(n, 200, 11);
  GraphCells cells = graph_cells(mesh, sites);
  double worst = 0;
  size_t sum_i = 0;
  for (int s = 0; s < 40; ++s) {
    // I = the cell, its neighbours and their neighbours (paper §7.1)
    std::set<int> ring = {s};
    for (int c : cells.adjacency[s]) {
      ring.insert(c);
      for (int c2 : cells.adjacency[c]) ring.insert(c2);
    }
    std::vector<int> I;
    for (int c : ring) I.insert(I.end(), cells.vertices[c].begin(), cells.vertices[c].end());
    sum_i += I.size();
    ASSERT_LT(I.size(), static_cast<size_t>(n) / 2);
    const std::vector<std::pair<int, double>> rhs = {{sites[s], 1.0}};
    Eigen::VectorXd full = solver.solve_sparse(rhs);
    std::vector<double> u = local.solve(rhs, I, ws);
    std::vector<double> at(n, -1.0);
    for (size_t i = 0; i < I.size(); ++i) at[I[i]] = u[i];
    for (int v : cells.vertices[s]) {
      ASSERT_GT(full[v], 0.0);
      worst = std::max(worst, std::abs(at[v] - full[v]) / full[v]);
    }
  }
  EXPECT_LT(worst, 1e-3) << "mean |I| " << sum_i / 40;
}

TEST(LocalizedSolve, BatchAndPruningAgreeWithSingleSolves) {
  auto mesh = test::torus(120, 60);
  Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
  HeatSolver solver(lap);
  LocalizedSolveOptions exact_options;
  exact_options.drop_tolerance = 0.0;
  LocalizedSolver exact(solver, exact_options);
  LocalizedSolveOptions pruned_options;
  pruned_options.drop_tolerance = 1e-12;
  LocalizedSolver pruned(solver, pruned_options);
  LocalizedWorkspace ws;
  const int n = solver.num_vertices();
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::vector<std::vector<std::pair<int, double>>> rhs;
  std::vector<std::vector<int>> sets;
  for (int s = 0; s < 19; ++s) {  // not a multiple of the batch width
    const int v = (s * 379) % n;
    rhs.push_back({{v, 0.7}, {(v + 1) % n, 0.3}});
    sets.push_back(s % 3 == 0 ? all : std::vector<int>(all.begin() + s * 100, all.begin() + s * 100 + 500));
  }
  std::vector<std::vector<double>> batch, batch_pruned;
  exact.solve_batch(rhs, sets, batch, ws);
  pruned.solve_batch(rhs, sets, batch_pruned, ws);
  ASSERT_EQ(batch.size(), rhs.size());
  for (size_t s = 0; s < rhs.size(); ++s) {
    std::vector<double> single = exact.solve(rhs[s], sets[s], ws);
    std::vector<double> single_pruned = pruned.solve(rhs[s], sets[s], ws);
    Eigen::VectorXd full = solver.solve_sparse(rhs[s]);
    const double scale = full.cwiseAbs().maxCoeff();
    ASSERT_EQ(single.size(), sets[s].size());
    for (size_t i = 0; i < single.size(); ++i) {
      EXPECT_NEAR(batch[s][i], single[i], 1e-12 * scale);
      EXPECT_NEAR(single_pruned[i], single[i], 1e-10 * scale);
      EXPECT_NEAR(batch_pruned[s][i], single[i], 1e-10 * scale);
      if (sets[s].size() == static_cast<size_t>(n)) EXPECT_NEAR(single[i], full[sets[s][i]], 1e-10 * scale);
    }
  }
  // pruning saves work on this mesh
  exact.solve(rhs[1], sets[1], ws);
  const size_t exact_entries = ws.stats().forward_entries;
  pruned.solve(rhs[1], sets[1], ws);
  EXPECT_LT(ws.stats().forward_entries, exact_entries);
}

TEST(LocalizedSolve, BadInputThrows) {
  auto mesh = test::icosphere(2);
  HeatSolver solver(cotan_laplacian(mesh.V, mesh.F));
  LocalizedSolver local(solver);
  LocalizedWorkspace ws;
  const int n = solver.num_vertices();
  EXPECT_THROW(local.solve({{n, 1.0}}, {0}, ws), InvalidInputError);
  EXPECT_THROW(local.solve({{-1, 1.0}}, {0}, ws), InvalidInputError);
  EXPECT_THROW(local.solve({{0, 1.0}}, {0, n}, ws), InvalidInputError);
  EXPECT_THROW(local.solve({{0, 1.0}}, {3, 3}, ws), InvalidInputError);
  std::vector<std::vector<double>> out;
  EXPECT_THROW(local.solve_batch({{{0, 1.0}}}, {}, out, ws), InvalidInputError);
  LocalizedSolveOptions bad;
  bad.drop_tolerance = -1;
  EXPECT_THROW(LocalizedSolver(solver, bad), InvalidInputError);
  // after the failures the workspace still gives exact results
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> u = local.solve({{0, 1.0}}, all, ws);
  Eigen::VectorXd full = solver.diffuse_from_vertex(0);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(u[i], full[i], 1e-12 * full.maxCoeff());
}
