#include "heatcvt/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace fs = std::filesystem;

namespace {
std::atomic<unsigned> g_temp_counter{0};
}

std::string format_double(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), x);
  return std::string(buf, res.ptr);
}

void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const fs::path target(path);
  if (target.filename().empty()) throw IOError(path + ": not a file name");
  fs::path dir = target.parent_path();
  std::error_code ec;
  if (!dir.empty() && !fs::is_directory(dir, ec))
    throw IOError(path + ": cannot write, directory '" + dir.string() + "' does not exist");
  if (fs::is_directory(target, ec)) throw IOError(path + ": cannot write, it is a directory");
  const fs::path temp = dir / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                               std::to_string(g_temp_counter.fetch_add(1)));
  std::ofstream out(temp, std::ios::binary | std::ios::trunc);
  if (!out) {
    const int err = errno;
    throw IOError(path + ": cannot create temporary file in '" + (dir.empty() ? std::string(".") : dir.string()) +
                  "': " + std::strerror(err));
  }
  auto discard = [&]() {
    out.close();
    std::error_code ignore;
    fs::remove(temp, ignore);
  };
  try {
    write(out);
    out.flush();
  } catch (...) {
    discard();
    throw;
  }
  if (!out) {
    discard();
    throw IOError(path + ": write failed (disk full or I/O error)");
  }
  out.close();
  if (out.fail()) {
    discard();
    throw IOError(path + ": write failed while closing the file");
  }
  fs::rename(temp, target, ec);
  if (ec) {
    std::error_code ignore;
    fs::remove(temp, ignore);
    throw IOError(path + ": cannot rename temporary file into place: " + ec.message());
  }
}

}  // namespace heatcvt
