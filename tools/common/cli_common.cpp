#include "cli_common.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "heatcvt/errors.h"
#include <exception>
#include <iostream>

namespace heatcvt::cli {

Progress::Progress(std::string label, long total, bool quiet)
    : label_(std::move(label)), total_(total), quiet_(quiet), tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(long done) {
  if (quiet_ || total_ <= 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  if (tty_ ? since_last < 0.1 : since_last < 5.0) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double frac = static_cast<double>(done) / static_cast<double>(total_);
  const double eta = frac > 0 ? elapsed * (1 - frac) / frac : 0;
  if (tty_) {
    const int width = 30, filled = static_cast<int>(frac * width);
    std::fprintf(stderr, "\r%s [%s%s] %ld/%ld  %.1fs, ETA %.1fs ", label_.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, '.').c_str(), done, total_, elapsed, eta);
  } else {
    std::fprintf(stderr, "%s: %ld/%ld (%.0f%%), %.1fs elapsed, ETA %.1fs\n", label_.c_str(), done, total_, 100 * frac,
                 elapsed, eta);
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (quiet_ || finished_ || total_ <= 0) return;
  finished_ = true;
  const double elapsed = seconds_since(start_);
  if (tty_) std::fprintf(stderr, "\r%s [%s] %ld/%ld  %.1fs%20s\n", label_.c_str(), std::string(30, '#').c_str(), total_, total_, elapsed, "");
  else std::fprintf(stderr, "%s: done, %ld in %.1fs\n", label_.c_str(), total_, elapsed);
}

int run_tool(const std::string& tool, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << std::endl;
    return 1;
  } catch (...) {
    std::cerr << tool << ": error: unknown failure" << std::endl;
    return 1;
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
        throw IOError(path + ": line " + std::to_string(line_no) + ": '" + tok + "' is not a number");
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
