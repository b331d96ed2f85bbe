#include "cli_common.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "heatcvt/atomic_file.h"
#include "heatcvt/errors.h"
#include "heatcvt/input_file.h"
#include "heatcvt/parallel.h"
#include <exception>
#include <iostream>

namespace heatcvt::cli {

void log_line(bool quiet, const std::string& line) {
  if (!quiet) std::cerr << line << std::endl;
}

Progress::Progress(std::string label, long total, bool quiet)
    : label_(std::move(label)), total_(total), quiet_(quiet), tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(long done, const std::string& stage, const std::string& note) {
  if (quiet_ || total_ <= 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  const bool new_stage = stage != stage_;
  stage_ = stage;
  if (!new_stage && (tty_ ? since_last < 0.1 : since_last < 5.0)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double frac = static_cast<double>(done) / static_cast<double>(total_);
  const double eta = frac > 0 ? elapsed * (1 - frac) / frac : 0;
  const std::string detail = stage.empty() || note.empty() ? stage + note : stage + ", " + note;
  const std::string at = detail.empty() ? "" : " (" + detail + ")";
  if (tty_) {
    const int width = 30, filled = static_cast<int>(frac * width);
    std::fprintf(stderr, "\r%s [%s%s] %ld/%ld  %.1fs, ETA %.1fs%-28s", label_.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, '.').c_str(), done, total_, elapsed, eta, at.c_str());
  } else {
    std::fprintf(stderr, "%s: %ld/%ld (%.0f%%), %.1fs elapsed, ETA %.1fs%s\n", label_.c_str(), done, total_, 100 * frac,
                 elapsed, eta, at.c_str());
  }
  std::fflush(stderr);
}

void Progress::restart() {
  start_ = last_ = std::chrono::steady_clock::now();
  stage_.clear();
}

void Progress::finish() {
  if (quiet_ || finished_ || total_ <= 0) return;
  finished_ = true;
  const double elapsed = seconds_since(start_);
  if (tty_) std::fprintf(stderr, "\r%s [%s] %ld/%ld  %.1fs%20s\n", label_.c_str(), std::string(30, '#').c_str(), total_, total_, elapsed, "");
  else std::fprintf(stderr, "%s: done, %ld in %.1fs\n", label_.c_str(), total_, elapsed);
}

std::string exit_status_help() {
  return "Exit status: 0 = outputs written and every check of the result passed; 1 = the computation "
         "failed; 2 = command-line misuse, a bad option value, an unusable input file or output path, or a "
         "failed write; 3 = outputs written, but the result failed some of its checks (listed on stdout and in "
         "--report). Nothing is written unless the status is 0 or 3.\n";
}

int parse_command_line(CLI::App& app, int argc, char** argv, const std::string& tool) {
  app.footer(exit_status_help());
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n' || c == '\r') c = ' ';
    std::cerr << tool << ": error: " << what << " (see " << tool << " --help)" << std::endl;
    return exit_bad_input;
  }
  return -1;
}

void check_time_coefficient(double coefficient) {
  if (!(coefficient > 0) || !std::isfinite(coefficient) || coefficient > kMaxTimeCoefficient) {
    std::ostringstream s;
    s << "--t-coef must be a positive number of at most " << kMaxTimeCoefficient << " (got " << coefficient << ")";
    throw InvalidInputError(s.str());
  }
}

CLI::Option* add_time_coefficient_option(CLI::App& app, double& coefficient) {
  std::ostringstream help;
  help << "time step t = C * (mean edge length)^2, C at most " << kMaxTimeCoefficient;
  return app.add_option("--t-coef", coefficient, help.str())->capture_default_str();
}

void check_threads(int threads) {
  if (threads < 0 || threads > kMaxThreads)
    throw InvalidInputError("--threads must be 0 (all cores) or a count of at most " + std::to_string(kMaxThreads) +
                            " (got " + std::to_string(threads) + ")");
}

CLI::Option* add_threads_option(CLI::App& app, int& threads) {
  return app
      .add_option("--threads", threads,
                  "worker threads, 0 = all cores, at most " + std::to_string(kMaxThreads) + "; results do not depend on it")
      ->capture_default_str();
}

void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(kAllocatorRetainBytes));
  mallopt(M_TRIM_THRESHOLD, static_cast<int>(kAllocatorRetainBytes));
}

int run_tool(const std::string& tool, const std::function<int()>& body) {
  remove_temporary_files_on_signals();
  keep_freed_memory();
  auto report = [&](const std::string& what) {
    std::string line = what;
    for (char& c : line)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';  // one line, no terminal escapes
    std::cerr << tool << ": error: " << line << std::endl;
  };
  try {
    return body();
  } catch (const InvalidInputError& e) {
    report(e.what());
    return exit_bad_input;
  } catch (const IOError& e) {
    report(e.what());
    return exit_bad_input;
  } catch (const std::bad_alloc&) {
    report("out of memory");
    return exit_failure;
  } catch (const std::exception& e) {
    report(e.what());
    return exit_failure;
  } catch (...) {
    report("unknown failure");
    return exit_failure;
  }
}

int parse_and_run(CLI::App& app, int argc, char** argv, const std::string& tool, const std::function<int()>& body) {
  if (const int status = parse_command_line(app, argc, argv, tool); status >= 0) return status;
  return run_tool(tool, body);
}

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                            const std::vector<std::string>& inputs) {
  std::vector<std::pair<std::string, std::string>> seen;  // (resolved path, option)
  for (const auto& [option, path] : outputs) {
    if (path.empty()) continue;
    for (const std::string& input : inputs) {
      std::error_code ec;  // a missing output or input cannot be the same file
      if (std::filesystem::equivalent(path, input, ec) && !ec)
        throw InvalidInputError(path + ": is also an input; " + option + " would overwrite it");
    }
    const std::string resolved = resolve_output_path(path);
    for (const auto& [other, other_option] : seen)
      if (other == resolved)
        throw InvalidInputError(path + ": given to both " + other_option + " and " + option +
                                " (outputs must be distinct files)");
    seen.emplace_back(resolved, option);
  }
}

void check_output_path(const std::string& path, const std::vector<std::string>& extensions) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (!extensions.empty()) {
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
      std::string list;
      for (const auto& e : extensions) list += (list.empty() ? "" : " ") + e;
      throw InvalidInputError(path + ": unsupported output extension (use one of: " + list + ")");
    }
  }
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir)) throw InvalidInputError(path + ": output directory '" + dir.string() + "' does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw InvalidInputError(path + ": output directory '" + dir.string() + "' is not writable");
  if (fs::is_directory(p)) throw InvalidInputError(path + ": is a directory, not an output file");
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<std::vector<double>> read_number_rows(const std::string& path, int columns, const std::string& what) {
  require_regular_file(path, what + " file");
  std::ifstream in(path);
  if (!in) throw IOError(path + ": cannot open the " + what + " file");
  std::vector<std::vector<double>> rows;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ls(line);
    std::vector<double> row;
    std::string tok;
    while (ls >> tok) {
      try {
        size_t used = 0;
        const double x = std::stod(tok, &used);
        if (used != tok.size()) throw std::invalid_argument(tok);
        row.push_back(x);
      } catch (const std::exception&) {
        throw IOError(path + ": line " + std::to_string(line_no) + ": " + quote_excerpt(tok) + " is not a number");
      }
    }
    const int want = columns > 0 ? columns : (rows.empty() ? static_cast<int>(row.size()) : static_cast<int>(rows[0].size()));
    if (static_cast<int>(row.size()) != want)
      throw IOError(path + ": line " + std::to_string(line_no) + " has " + std::to_string(row.size()) +
                    " values, expected " + std::to_string(want));
    for (double x : row)
      if (!std::isfinite(x)) throw InvalidInputError(path + ": line " + std::to_string(line_no) + " has a NaN or infinite value");
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw InvalidInputError(path + ": no " + what + " in the file");
  return rows;
}

}  // namespace heatcvt::cli
