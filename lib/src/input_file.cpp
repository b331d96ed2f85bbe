#include "heatcvt/input_file.h"

#include <filesystem>

#include "heatcvt/errors.h"

namespace heatcvt {

void require_regular_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found) throw IOError(path + ": " + what + " does not exist");
  if (ec) throw IOError(path + ": cannot read the " + what + ": " + ec.message());
  if (fs::is_directory(st)) throw IOError(path + ": is a directory, not a " + what);
  if (!fs::is_regular_file(st))
    throw IOError(path + ": is not a regular file (a device, FIFO or socket)");
}

}  // namespace heatcvt
