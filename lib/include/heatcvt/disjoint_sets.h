#pragma once
/// \file disjoint_sets.h
/// Union-find over 0..n−1 (boost::disjoint_sets: path compression and union by rank), the one
/// union-find of the library: connected components of meshes, vertex links, mesher pieces.
#include <vector>

namespace heatcvt {

/// Disjoint sets of the integers 0..n−1, each initially alone.
class DisjointSets {
 public:
  explicit DisjointSets(int n);
  /// Representative of i's set (the same for every member until the next unite()).
  int find(int i);
  /// Merges the sets of i and j.
  void unite(int i, int j);

 private:
  std::vector<int> rank_, parent_;
};

}  // namespace heatcvt
