// Localized solves (paper §6, Fig. 7): time per localized solve against |I| on a 164k-vertex
// sphere (cotan, t = h̄²), exact forward vs pruned forward, single vs batched sources.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <queue>
#include <vector>

#include "bench_util.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/localized_solve.h"

using namespace heatcvt;

int main(int argc, char** argv) {
  const int level = argc > 1 ? std::atoi(argv[1]) : 7;  // 7 → 163,842 vertices
  TriangleMesh mesh = bench::icosphere(level);
  const int n = static_cast<int>(mesh.V.rows());
  double t0 = bench::now_seconds();
  Laplacian lap = cotan_laplacian(mesh.V, mesh.F);
  HeatSolverOptions so;
  so.threads = 1;
  HeatSolver solver(lap, so);
  std::printf("sphere: %d vertices, factor %.3f s, %zu factor entries (%.1f MB), setup %.2f s\n", n,
              solver.factor_seconds(), solver.factor().nonzeros(), solver.factor().memory_bytes() / 1e6,
              bench::now_seconds() - t0);
  LocalizedSolveOptions eo;
  eo.drop_tolerance = 0.0;
  LocalizedSolver exact(solver, eo);
  LocalizedSolveOptions po;
  po.drop_tolerance = 1e-12;
  LocalizedSolver pruned(solver, po);
  LocalizedWorkspace ws(n);
  auto nbr = vertex_neighbors(n, mesh.F);
  const int sources = 64;
  std::vector<int> src(sources);
  for (int s = 0; s < sources; ++s) src[s] = static_cast<int>((static_cast<long>(s) * 104729) % n);

  // Full solve reference time.
  t0 = bench::now_seconds();
  for (int s = 0; s < 8; ++s) solver.diffuse_from_vertex(src[s]);
  const double full_ms = (bench::now_seconds() - t0) / 8 * 1e3;
  std::printf("full solve (forward+back over all %d columns): %.2f ms\n\n", n, full_ms);
  std::printf("%9s | %9s %9s %9s | %12s %12s %12s | %12s %12s\n", "|I|", "reach", "fwd-entr", "pruned-e", "exact ms",
              "pruned ms", "batch8 ms", "back ms", "ms/1k|I|");
  for (int size : {100, 300, 1000, 3000, 10000, 30000, 100000, n}) {
    std::vector<std::vector<int>> sets(sources);
    std::vector<std::vector<std::pair<int, double>>> rhs(sources);
    std::vector<char> seen(n, 0);
    for (int s = 0; s < sources; ++s) {
      // BFS ball of `size` vertices around the source
      std::queue<int> q;
      q.push(src[s]);
      seen[src[s]] = 1;
      while (!q.empty() && static_cast<int>(sets[s].size()) < size) {
        int v = q.front();
        q.pop();
        sets[s].push_back(v);
        for (int w : nbr[v])
          if (!seen[w]) seen[w] = 1, q.push(w);
      }
      std::fill(seen.begin(), seen.end(), 0);
      rhs[s] = {{src[s], 1.0}};
    }
    std::vector<double> out;
    size_t reach = 0, fwd = 0;
    t0 = bench::now_seconds();
    for (int s = 0; s < sources; ++s) {
      exact.solve(rhs[s], sets[s], out, ws);
      reach += ws.stats().reach;
      fwd += ws.stats().forward_entries;
    }
    const double exact_ms = (bench::now_seconds() - t0) / sources * 1e3;
    t0 = bench::now_seconds();
    size_t pfwd = 0;
    for (int s = 0; s < sources; ++s) {
      pruned.solve(rhs[s], sets[s], out, ws);
      pfwd += ws.stats().forward_entries;
    }
    const double pruned_ms = (bench::now_seconds() - t0) / sources * 1e3;
    std::vector<std::vector<double>> outs;
    t0 = bench::now_seconds();
    pruned.solve_batch(rhs, sets, outs, ws);
    const double batch_ms = (bench::now_seconds() - t0) / sources * 1e3;
    // back solve alone: pruned solve of a source with an empty I minus nothing (forward only)
    t0 = bench::now_seconds();
    for (int s = 0; s < sources; ++s) pruned.solve(rhs[s], {}, out, ws);
    const double fwd_only = (bench::now_seconds() - t0) / sources * 1e3;
    const double back_ms = std::max(0.0, pruned_ms - fwd_only);
    std::printf("%9d | %9zu %9zu %9zu | %12.3f %12.3f %12.3f | %12.3f %12.4f\n", static_cast<int>(sets[0].size()),
                reach / sources, fwd / sources, pfwd / sources, exact_ms, pruned_ms, batch_ms, back_ms,
                back_ms / (sets[0].size() / 1000.0));
  }
  std::printf("\n(exact: full forward over the reach; pruned: forward columns below 1e-12·max skipped;\n"
              " batch8: 8 sources per forward pass, pruned; back ms = pruned − forward-only. Paper Fig. 7:\n"
              " time near linear in |I|.)\n");
  return 0;
}
