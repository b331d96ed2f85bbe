#pragma once
/// \file atomic_file.h
/// All-or-nothing file output: content is written to a temporary file in the target's directory
/// and renamed over the target only after everything was written and flushed successfully.
/// A failing writer (exception in the callback, full disk, missing directory) never leaves a
/// partial target file and never leaves the temporary behind.
///
/// Several outputs of one run are committed together with an OutputTransaction: while one is
/// open on the calling thread, write_atomically (and every writer built on it: write_mesh,
/// write_points_xyz, ...) only writes its temporary file; commit() renames them all at the end,
/// and a transaction destroyed without commit() removes them, so either every output of a run
/// appears or none does.
///
/// An output path that is a symbolic link is written through: the file the link points to is
/// replaced, the link itself stays.
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace heatcvt {

/// Writes `path` atomically: `write` receives a binary-mode output stream on a temporary file
/// `<dir>/.<name>.tmp-<pid>-<n>` in the directory of the (symlink-resolved) target, which is
/// renamed to the target afterwards (rename within one directory is atomic on POSIX file
/// systems), or when the open OutputTransaction of this thread commits. An existing target is
/// replaced only on success.
/// \throw IOError "<path>: <problem>" when the directory does not exist or is not writable,
///        or the stream reports a write failure. Exceptions thrown by `write` propagate unchanged
///        after the temporary file has been removed.
void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// The file an output path finally names: symbolic links (also chains and relative links)
/// followed even when the final target does not exist yet, the result made absolute and
/// lexically normal. Two outputs with the same resolved path would overwrite each other.
std::string resolve_output_path(const std::string& path);

/// Outputs committed together (see the file comment). At most one per thread is open; opening a
/// second one on the same thread throws std::logic_error.
class OutputTransaction {
 public:
  OutputTransaction();
  /// Removes the temporary files of an uncommitted transaction.
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// Renames every staged temporary file onto its target, in the order they were written.
  /// \throw IOError when a rename fails (the temporaries not yet renamed are removed).
  void commit();

  struct Staged {
    std::string temp, target, path;
  };

 private:
  std::vector<Staged> staged_;
  bool committed_ = false;
  friend void write_atomically(const std::string&, const std::function<void(std::ostream&)>&);
};

/// For command-line tools: on SIGINT / SIGTERM / SIGHUP the temporary files not yet renamed are
/// removed before the process dies of the signal, and SIGXFSZ (file size limit) is ignored so
/// that the write fails with an error (and its temporary is removed) instead of killing the
/// process. Installs process-wide signal handlers; the library never calls it by itself.
void remove_temporary_files_on_signals();

/// Formats a double with the shortest representation that reads back exactly (locale
/// independent, "nan"/"inf" for non-finite values). Shared by all text writers.
std::string format_double(double x);

}  // namespace heatcvt
