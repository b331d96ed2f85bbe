#pragma once
/// \file cancellation.h
/// Cooperative cancellation of the post-CVT stages: a caller that runs the stages ahead, before it
/// knows whether it needs their result (remesh_cvt() on another thread), asks them to stop once
/// it does not. The stages ask between their steps and stop by throwing StagesCancelled.
#include <exception>
#include <functional>

namespace heatcvt {

/// Returns true once the result of the stages is no longer needed. Empty: never.
using CancelQuery = std::function<bool()>;

/// Thrown by the stages where their CancelQuery returns true. Not an Error: no input is at fault,
/// and whoever set the query expects it.
class StagesCancelled : public std::exception {
 public:
  const char* what() const noexcept override { return "surface mesher: cancelled"; }
};

/// Throws StagesCancelled where `cancelled` is set and returns true.
inline void throw_if_cancelled(const CancelQuery& cancelled) {
  if (cancelled && cancelled()) throw StagesCancelled();
}

}  // namespace heatcvt
