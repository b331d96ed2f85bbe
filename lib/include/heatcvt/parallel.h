#pragma once
/// \file parallel.h
/// Thread-count convention shared by every options struct: 0 means "all hardware threads".
namespace heatcvt {
/// Most worker threads any step starts: a request above it is reduced to it. Every result is the
/// same for any thread count, so the bound changes only the time; it keeps a mistyped count
/// (10⁶) from asking the OS for a million threads and their stacks.
constexpr int kMaxThreads = 1024;

/// Resolves a requested thread count (0 = all available) to a number in [1, kMaxThreads].
int resolve_threads(int requested);
}  // namespace heatcvt
