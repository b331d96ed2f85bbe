#pragma once
// Shared glue for the command-line tools: command-line parsing, exit statuses, progress
// reporting on stderr, output checks, and the uniform "one clear error line" behaviour.
#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"

namespace heatcvt::cli {

/// Exit statuses shared by every tool (listed by --help and in the README's tools section).
enum ExitStatus : int {
  exit_ok = 0,              ///< every output written, every check of the result passed
  exit_failure = 1,         ///< the computation failed (e.g. a factorisation); nothing written
  exit_bad_input = 2,       ///< command-line misuse, a bad option value, an unusable input file or
                            ///< output path, or a failed write; nothing written
  exit_checks_failed = 3,   ///< every output written, but the result failed some of its checks
};

/// The text of the exit statuses, appended to every tool's --help.
std::string exit_status_help();

/// Parses the command line. Returns -1 when the tool should go on; otherwise the exit status
/// to return: 0 after --help (printed on stdout), exit_bad_input after a parse error, which is
/// printed as the single line "<tool>: error: <problem> (see <tool> --help)" on stderr.
int parse_command_line(CLI::App& app, int argc, char** argv, const std::string& tool);

/// Prints `line` on stderr as one line (flushed) unless `quiet`: a tool's notes and warnings.
void log_line(bool quiet, const std::string& line);

/// Progress on stderr: a bar with ETA when stderr is a terminal, a line every few seconds
/// otherwise (and one whenever the stage named by update()'s `stage` changes), nothing when
/// quiet. `stage` and `note` (e.g. the points read so far) are shown after the figures.
class Progress {
 public:
  Progress(std::string label, long total, bool quiet);
  void update(long done, const std::string& stage = "", const std::string& note = "");
  /// Starts the count again (a new run of the same work): elapsed time and ETA from now.
  void restart();
  void finish();
 private:
  std::string label_;
  std::string stage_;
  long total_;
  bool quiet_, tty_;
  std::chrono::steady_clock::time_point start_, last_;
  bool finished_ = false;
};

/// Largest block (and freed top of the heap) that the allocator keeps in the process instead of
/// handing it back to the OS: 1 GiB. glibc's defaults map every block above 128 KiB afresh and
/// unmap it on free, so arrays of the point or vertex count that a stage allocates and frees in
/// every pass (workspaces, candidate lists, sort buffers) are faulted in page by page each time
/// (measured in docs/benchmarks.md). Freed memory stays reusable by the next allocation; the
/// peak resident size grows by what is held between stages.
constexpr long kAllocatorRetainBytes = 1L << 30;

/// Sets the allocator to keep freed blocks up to kAllocatorRetainBytes (mallopt M_MMAP_THRESHOLD
/// and M_TRIM_THRESHOLD). Called by run_tool(); results do not depend on it.
void keep_freed_memory();

/// Runs the body of a tool: keeps freed memory in the process (keep_freed_memory()), removes
/// temporary output files on SIGINT/SIGTERM (atomic_file.h),
/// catches every exception, prints "<tool>: error: <message>" as one line on stderr (control
/// bytes replaced) and returns exit_bad_input for InvalidInputError / IOError, exit_failure
/// otherwise. The body's own return value is passed through.
int run_tool(const std::string& tool, const std::function<int()>& body);

/// The whole of a tool's main() once its options are declared: parse_command_line(), and unless
/// that ends the tool (--help, a parse error), `body` under run_tool(). Returns the exit status.
int parse_and_run(CLI::App& app, int argc, char** argv, const std::string& tool, const std::function<int()>& body);

/// Runs `work` (a library call on the content of `path`) and rethrows any heatcvt::Error of the
/// same class with the message "<path>: <problem>", the library's internal function name
/// removed, so that the error line names the file at fault.
template <typename Work>
auto on_file(const std::string& path, Work&& work) -> decltype(work()) {
  auto context = [&](const Error& e) {
    const std::string what = e.what();
    return what.rfind(path + ": ", 0) == 0 ? what : path + ": " + without_function_prefix(what);
  };
  try {
    return work();
  } catch (const InvalidInputError& e) {
    throw InvalidInputError(context(e));
  } catch (const IOError& e) {
    throw IOError(context(e));
  } catch (const SolverError& e) {
    throw SolverError(context(e));
  } catch (const Error& e) {
    throw Error(context(e));
  }
}

/// Largest heat time coefficient the tools accept (t = C · h̄², h̄ the Laplacian's mean edge
/// length): 10⁴, a diffusion length of 100 edges. Far beyond it the heat is nearly constant over
/// the surface and its gradient, the heat method's distance direction (paper §2, eq. 7), is
/// rounding noise: the diagrams and meshes fall apart while every check still passes.
constexpr double kMaxTimeCoefficient = 1e4;

/// Checks --t-coef: a finite number in (0, kMaxTimeCoefficient]. Throws heatcvt::InvalidInputError.
void check_time_coefficient(double coefficient);

/// Adds the --t-coef option (the heat time coefficient, its bound in the help) bound to `coefficient`.
CLI::Option* add_time_coefficient_option(CLI::App& app, double& coefficient);

/// Checks --threads: 0 (all cores) up to heatcvt::kMaxThreads. Throws heatcvt::InvalidInputError.
void check_threads(int threads);

/// Adds the --threads option (0 = all cores, its bound in the help) bound to `threads`.
CLI::Option* add_threads_option(CLI::App& app, int& threads);

/// Fails fast, before any work, when an output could not be written: its directory is missing
/// or not writable, or (when `extensions` is non-empty, e.g. {".ply", ".obj"}) its extension is
/// not one of them. Throws heatcvt::InvalidInputError "<path>: <problem>". Empty paths pass.
void check_output_path(const std::string& path, const std::vector<std::string>& extensions = {});

/// Fails fast when two outputs name the same file (after following symbolic links), or an output
/// names one of the `inputs` (which it would overwrite): `outputs` are (option, path) pairs, empty
/// paths are skipped.
/// Throws InvalidInputError "<path>: given to both <option> and <option> ..." or
/// "<path>: is also an input; <option> would overwrite it".
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                            const std::vector<std::string>& inputs = {});

/// Rows of whitespace-separated numbers from a text file ('#' comments and blank lines skipped),
/// every row with `columns` values (0 = as many as the first row). Throws heatcvt::IOError or
/// InvalidInputError "<path>: line N ..." for an unreadable file or a directory, a token that is
/// not a number, a short or long row, a NaN/inf value, or a file without rows ("no <what> in
/// the file").
std::vector<std::vector<double>> read_number_rows(const std::string& path, int columns, const std::string& what);

/// Seconds elapsed since `start`.
double seconds_since(std::chrono::steady_clock::time_point start);

}  // namespace heatcvt::cli
