#pragma once
// Shared glue for the command-line tools: progress reporting on stderr, atomic output
// files, and the uniform "one clear error line, non-zero exit" behaviour.
#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace heatcvt::cli {

/// Progress on stderr: a bar with ETA when stderr is a terminal, a line every few seconds
/// otherwise, nothing when quiet.
class Progress {
 public:
  Progress(std::string label, long total, bool quiet);
  void update(long done);
  void finish();
 private:
  std::string label_;
  long total_;
  bool quiet_, tty_;
  std::chrono::steady_clock::time_point start_, last_;
  bool finished_ = false;
};

/// Runs the body of a tool: catches every exception, prints "<tool>: error: <message>" as one
/// line on stderr and returns 1 (2 for command-line errors from CLI11).
int run_tool(const std::string& tool, const std::function<int()>& body);

/// Fails fast, before any work, when an output could not be written: its directory is missing
/// or not writable, or (when `extensions` is non-empty, e.g. {".ply", ".obj"}) its extension is
/// not one of them. Throws heatcvt::InvalidInputError "<path>: <problem>". Empty paths pass.
void check_output_path(const std::string& path, const std::vector<std::string>& extensions = {});

/// Rows of whitespace-separated numbers from a text file ('#' comments and blank lines skipped),
/// every row with `columns` values (0 = as many as the first row). Throws heatcvt::IOError or
/// InvalidInputError "<path>: line N ..." for an unreadable file, a token that is not a number, a
/// short or long row, a NaN/inf value, or a file without rows ("no <what> in the file").
std::vector<std::vector<double>> read_number_rows(const std::string& path, int columns, const std::string& what);

/// Seconds elapsed since `start`.
double seconds_since(std::chrono::steady_clock::time_point start);

}  // namespace heatcvt::cli
