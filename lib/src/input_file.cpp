#include "heatcvt/input_file.h"

#include <filesystem>

#include "heatcvt/errors.h"

namespace heatcvt {

void require_regular_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw IOError(path + ": " + what + " does not exist");
  if (fs::is_directory(st)) throw IOError(path + ": is a directory, not a " + what);
  if (!fs::is_regular_file(st)) throw IOError(path + ": is not a regular " + what + " (a device, FIFO or socket)");
}

}  // namespace heatcvt
