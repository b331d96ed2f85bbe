#pragma once
/// \file atomic_file.h
/// All-or-nothing file output: content is written to a temporary file in the target's directory
/// and renamed over the target only after everything was written and flushed successfully.
/// A failing writer (exception in the callback, full disk, missing directory) never leaves a
/// partial target file and never leaves the temporary behind.
#include <functional>
#include <iosfwd>
#include <string>

namespace heatcvt {

/// Writes `path` atomically: `write` receives a binary-mode output stream on a temporary file
/// `<dir>/.<name>.tmp-<pid>-<n>` in the same directory, which is renamed to `path` afterwards
/// (rename within one directory is atomic on POSIX file systems). An existing `path` is replaced
/// only on success.
/// \throw IOError "<path>: <problem>" when the directory does not exist or is not writable,
///        or the stream reports a write failure. Exceptions thrown by `write` propagate unchanged
///        after the temporary file has been removed.
void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Formats a double with the shortest representation that reads back exactly (locale
/// independent, "nan"/"inf" for non-finite values). Shared by all text writers.
std::string format_double(double x);

}  // namespace heatcvt
