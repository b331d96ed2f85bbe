#pragma once
/// \file parallel.h
/// Thread-count convention shared by every options struct: 0 means "all hardware threads".
namespace heatcvt {
/// Resolves a requested thread count (0 = all available) to a positive number.
int resolve_threads(int requested);
}  // namespace heatcvt
