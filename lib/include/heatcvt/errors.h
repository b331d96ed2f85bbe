#pragma once
/// \file errors.h
/// The small exception hierarchy of heatcvt. Every error carries a message that says what
/// was wrong (and, for files, which file); tools print it as one line and exit non-zero.
#include <stdexcept>
#include <string>
#include <string_view>

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

/// Quotes an excerpt of file content for an error message: at most `max_chars` characters of
/// `text` between single quotes ("..." appended when cut), every byte that is not printable ASCII
/// (control bytes such as ESC, BEL, CR, form feed, and non-ASCII bytes) replaced by '?', so that
/// a message stays one harmless line whatever the file holds.
std::string quote_excerpt(std::string_view text, std::size_t max_chars = 40);

/// The message of an error raised inside the library, with a leading internal function or class
/// name ("some_function: ...", "SomeClass: ...") removed, for a tool to
/// prefix with the file or option at fault.
std::string without_function_prefix(const std::string& message);

}  // namespace heatcvt
