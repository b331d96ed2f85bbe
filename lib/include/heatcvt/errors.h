#pragma once
/// \file errors.h
/// The small exception hierarchy of heatcvt. Every error carries a message that says what
/// was wrong (and, for files, which file); tools print it as one line and exit non-zero.
#include <stdexcept>
#include <string>

namespace heatcvt {

/// Base class of every exception thrown by heatcvt.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input violates a documented precondition (empty mesh, NaN coordinates, bad option).
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

/// A file could not be read or written (missing, truncated, malformed, unknown format).
class IOError : public Error {
 public:
  using Error::Error;
};

/// A numerical failure (the heat matrix is not positive definite, a factorisation failed).
class SolverError : public Error {
 public:
  using Error::Error;
};

}  // namespace heatcvt
