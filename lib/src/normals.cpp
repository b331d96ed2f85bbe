#include "heatcvt/normals.h"

#include <flann/flann.hpp>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/parallel.h"
#include "heatcvt/spatial_order.h"

namespace heatcvt {
namespace {

void check_cloud(const Eigen::MatrixX3d& P, int k, int min_k, const char* what) {
  if (k < min_k)
    throw InvalidInputError(std::string(what) + ": k = " + std::to_string(k) + " is too small (need k >= " +
                            std::to_string(min_k) + ")");
  if (P.rows() < static_cast<Eigen::Index>(k) + 1)
    throw InvalidInputError(std::string(what) + ": the cloud has " + std::to_string(P.rows()) +
                            " points, need at least k + 1 = " + std::to_string(k + 1));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (!P.row(i).allFinite())
      throw InvalidInputError(std::string(what) + ": point " + std::to_string(i) +
                              " has a NaN or infinite coordinate");
}

std::vector<double> row_major(const Eigen::MatrixX3d& P) {
  std::vector<double> data(static_cast<size_t>(P.rows()) * 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) data[static_cast<size_t>(i) * 3 + c] = P(i, c);
  return data;
}

// Exact kNN with FLANN: a single kd-tree (KDTreeSingleIndex) over P searched exhaustively
// (checks = unlimited, eps = 0), squared L2 distances in double precision, for every row of Q.
// Each row of results is then re-sorted by (distance, index) so that ties are ordered
// deterministically. Returns #Q × kq indices, row-major.
// The queries are searched in Morton order (spatial_order.h): consecutive queries then walk the
// same branches of the tree, which stay in cache. The results are exact, so the order does not
// change them; they are returned in the rows' own order.
std::vector<int> flann_knn(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& Q, int kq, int threads) {
  std::vector<double> data = row_major(P);
  const std::vector<int> order = morton_order(Q);
  std::vector<double> query(static_cast<size_t>(Q.rows()) * 3);
  for (size_t r = 0; r < order.size(); ++r)
    for (int c = 0; c < 3; ++c) query[r * 3 + c] = Q(order[r], c);
  const flann::Matrix<double> dataset(data.data(), static_cast<size_t>(P.rows()), 3);
  const flann::Matrix<double> queries(query.data(), static_cast<size_t>(Q.rows()), 3);
  flann::Index<flann::L2<double>> index(dataset, flann::KDTreeSingleIndexParams(10));
  index.buildIndex();
  const int n = static_cast<int>(Q.rows());
  std::vector<int> idx(static_cast<size_t>(n) * kq, -1);
  std::vector<double> dist(static_cast<size_t>(n) * kq, 0.0);
  flann::Matrix<int> indices(idx.data(), static_cast<size_t>(n), static_cast<size_t>(kq));
  flann::Matrix<double> dists(dist.data(), static_cast<size_t>(n), static_cast<size_t>(kq));
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0.0f, true);
  params.cores = resolve_threads(threads);
  if (n > 0) index.knnSearch(queries, indices, dists, static_cast<size_t>(kq), params);
  std::vector<int> out(idx.size(), -1);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (int r = 0; r < n; ++r) {
    std::vector<std::pair<double, int>> row(kq);
    for (int q = 0; q < kq; ++q)
      row[q] = {dist[static_cast<size_t>(r) * kq + q], idx[static_cast<size_t>(r) * kq + q]};
    std::sort(row.begin(), row.end());
    const size_t i = static_cast<size_t>(order[r]);
    for (int q = 0; q < kq; ++q) out[i * kq + q] = row[q].second;
  }
  return out;
}

}  // namespace

Eigen::MatrixXi nearest_neighbors_of(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& Q, int k, int threads) {
  if (k < 1) throw InvalidInputError("nearest_neighbors_of: k = " + std::to_string(k) + " is too small (need k >= 1)");
  if (P.rows() < k)
    throw InvalidInputError("nearest_neighbors_of: the cloud has " + std::to_string(P.rows()) + " points, need at least k = " +
                            std::to_string(k));
  if (!P.allFinite() || !Q.allFinite()) throw InvalidInputError("nearest_neighbors_of: a NaN or infinite coordinate");
  const std::vector<int> idx = flann_knn(P, Q, k, threads);
  Eigen::MatrixXi out(Q.rows(), k);
  for (Eigen::Index i = 0; i < Q.rows(); ++i)
    for (int c = 0; c < k; ++c) out(i, c) = idx[static_cast<size_t>(i) * k + c];
  return out;
}

Eigen::MatrixXi k_nearest_neighbors(const Eigen::MatrixX3d& P, int k, int threads) {
  check_cloud(P, k, 1, "k_nearest_neighbors");
  const int n = static_cast<int>(P.rows());
  const int kq = std::min(k + 1, n);  // the point itself is (normally) its own nearest neighbour
  const std::vector<int> idx = flann_knn(P, P, kq, threads);

  Eigen::MatrixXi out(n, k);
  for (int i = 0; i < n; ++i) {
    const int* row = idx.data() + static_cast<size_t>(i) * kq;
    int c = 0;
    bool skipped = false;
    for (int q = 0; q < kq && c < k; ++q) {
      if (!skipped && row[q] == i) {
        skipped = true;
        continue;
      }
      if (row[q] < 0 || row[q] >= n)
        throw Error("k_nearest_neighbors: the kd-tree returned too few neighbours for point " + std::to_string(i));
      out(i, c++) = row[q];
    }
  }
  return out;
}

Eigen::MatrixX3d estimate_normals(const Eigen::MatrixX3d& P, const Eigen::MatrixXi& neighbors, int threads) {
  if (neighbors.rows() != P.rows())
    throw InvalidInputError("estimate_normals: the neighbour table has " + std::to_string(neighbors.rows()) +
                            " rows but the cloud has " + std::to_string(P.rows()) + " points");
  if (neighbors.cols() < 2) throw InvalidInputError("estimate_normals: need at least 2 neighbours per point");
  const int n = static_cast<int>(P.rows());
  Eigen::MatrixX3d N(n, 3);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (int i = 0; i < n; ++i) {
    const int m = static_cast<int>(neighbors.cols()) + 1;
    Eigen::Vector3d mean = P.row(i).transpose();
    for (int q = 0; q < m - 1; ++q) mean += P.row(neighbors(i, q)).transpose();
    mean /= m;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    Eigen::Vector3d d = P.row(i).transpose() - mean;
    C += d * d.transpose();
    for (int q = 0; q < m - 1; ++q) {
      d = P.row(neighbors(i, q)).transpose() - mean;
      C += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    Eigen::Vector3d nrm = es.eigenvectors().col(0);  // eigenvalues ascending
    if (!nrm.allFinite() || nrm.norm() == 0) nrm = Eigen::Vector3d::UnitZ();
    N.row(i) = nrm.normalized().transpose();
  }
  return N;
}

Eigen::MatrixX3d estimate_normals(const Eigen::MatrixX3d& P, int k, int threads) {
  check_cloud(P, k, 2, "estimate_normals");
  return estimate_normals(P, k_nearest_neighbors(P, k, threads), threads);
}

void orient_normals_mst(const Eigen::MatrixX3d& P, Eigen::MatrixX3d& N, int k, int threads, double offset_penalty) {
  if (N.rows() != P.rows())
    throw InvalidInputError("orient_normals_mst: " + std::to_string(N.rows()) + " normals for " +
                            std::to_string(P.rows()) + " points");
  check_cloud(P, k, 1, "orient_normals_mst");
  for (Eigen::Index i = 0; i < N.rows(); ++i)
    if (!N.row(i).allFinite())
      throw InvalidInputError("orient_normals_mst: normal " + std::to_string(i) + " is NaN or infinite");
  const int n = static_cast<int>(P.rows());
  const Eigen::MatrixXi nb = k_nearest_neighbors(P, k, threads);

  // Symmetrised kNN graph as sorted adjacency lists (deterministic).
  std::vector<std::vector<int>> adj(n);
  for (int i = 0; i < n; ++i)
    for (int q = 0; q < k; ++q) {
      const int j = nb(i, q);
      if (j == i) continue;
      adj[i].push_back(j);
      adj[j].push_back(i);
    }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }

  // Points by decreasing z (ties by index): the next unvisited one seeds the next component.
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return P(a, 2) > P(b, 2); });

  std::vector<char> done(n, 0);
  using Item = std::pair<double, std::pair<int, int>>;  // (weight, (node, parent)), min-heap
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  // The least item pushed so far for each node: an item that does not beat it would only be
  // popped after the node is done, so it is not pushed (the same tree, far fewer heap items).
  std::vector<Item> best(n, Item{std::numeric_limits<double>::infinity(), {0, std::numeric_limits<int>::max()}});
  for (int seed : order) {
    if (done[seed]) continue;
    if (N(seed, 2) < 0) N.row(seed) *= -1.0;
    heap.push({0.0, {seed, -1}});
    while (!heap.empty()) {
      const auto [w, np] = heap.top();
      heap.pop();
      (void)w;
      const int v = np.first, parent = np.second;
      if (done[v]) continue;
      done[v] = 1;
      if (parent >= 0 && N.row(parent).dot(N.row(v)) < 0) N.row(v) *= -1.0;
      for (int u : adj[v])
        if (!done[u]) {
          double w = 1.0 - std::abs(N.row(v).dot(N.row(u)));
          if (offset_penalty > 0) {
            const Eigen::Vector3d d = P.row(u) - P.row(v);
            const double len = d.norm();
            if (len > 0) w += offset_penalty * std::abs(N.row(v).dot(d)) / len;
          }
          const Item item{w, {u, v}};
          if (!(item < best[u])) continue;
          best[u] = item;
          heap.push(item);
        }
    }
  }
}

}  // namespace heatcvt
