#include "heatcvt/parallel.h"

#include <algorithm>
#include <thread>

namespace heatcvt {
int resolve_threads(int requested) {
  if (requested > 0) return std::min(requested, kMaxThreads);
  const unsigned hw = std::thread::hardware_concurrency();
  return hw > 0 ? std::min(static_cast<int>(hw), kMaxThreads) : 1;
}
}  // namespace heatcvt
