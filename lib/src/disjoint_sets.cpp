#include "heatcvt/disjoint_sets.h"

#include <boost/pending/disjoint_sets.hpp>

namespace heatcvt {

DisjointSets::DisjointSets(int n) : rank_(n, 0), parent_(n) {
  for (int i = 0; i < n; ++i) parent_[i] = i;
}

int DisjointSets::find(int i) {
  boost::disjoint_sets<int*, int*> sets(rank_.data(), parent_.data());
  return sets.find_set(i);
}

void DisjointSets::unite(int i, int j) {
  boost::disjoint_sets<int*, int*> sets(rank_.data(), parent_.data());
  sets.union_set(i, j);
}

}  // namespace heatcvt
