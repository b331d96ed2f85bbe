#include "heatcvt/parallel.h"

#include <omp.h>

#include <thread>

namespace heatcvt {
int resolve_threads(int requested) {
  if (requested > 0) return requested;
  unsigned hw = std::thread::hardware_concurrency();
  return hw > 0 ? static_cast<int>(hw) : 1;
}
}  // namespace heatcvt
