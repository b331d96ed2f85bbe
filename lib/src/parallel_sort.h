#pragma once
// Sorting on several threads (libstdc++'s parallel mode, OpenMP multiway mergesort). Only for
// strict total orders, or where equal elements are indistinguishable: then the sorted sequence is
// unique, and the result does not depend on the thread count.
#include <algorithm>
#include <functional>
#include <parallel/algorithm>

namespace heatcvt {

// Below this many elements one thread sorts: the parallel merge would cost more than it saves.
constexpr long kParallelSortMinElements = 1 << 16;

template <class It, class Less = std::less<>>
void parallel_sort(It first, It last, int threads, Less less = Less()) {
  if (threads > 1 && last - first > kParallelSortMinElements)
    __gnu_parallel::sort(first, last, less, __gnu_parallel::multiway_mergesort_tag(threads));
  else
    std::sort(first, last, less);
}

}  // namespace heatcvt
