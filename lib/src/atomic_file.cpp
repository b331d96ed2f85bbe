#include "heatcvt/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace fs = std::filesystem;

namespace {
std::atomic<unsigned> g_temp_counter{0};
thread_local OutputTransaction* t_open_transaction = nullptr;

// Temporary files that exist right now, for the signal handler. Fixed storage: the handler may
// only read plain memory and call unlink(2). A slot is claimed with a compare-exchange on `used`
// and its path is written before `ready` is set.
constexpr int kTempSlots = 64;
constexpr size_t kTempPathMax = 4096;
struct TempSlot {
  std::atomic<int> used{0};
  std::atomic<int> ready{0};
  char path[kTempPathMax];
};
std::array<TempSlot, kTempSlots> g_temp_slots;

int register_temp(const std::string& path) {
  if (path.size() >= kTempPathMax) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    int expected = 0;
    if (g_temp_slots[i].used.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_temp_slots[i].path, path.c_str(), path.size() + 1);
      g_temp_slots[i].ready.store(1);
      return i;
    }
  }
  return -1;  // more live temporaries than slots: still written, just not cleaned on a signal
}

void unregister_temp(int slot) {
  if (slot < 0) return;
  g_temp_slots[slot].ready.store(0);
  g_temp_slots[slot].used.store(0);
}

extern "C" void remove_temps_and_reraise(int sig) {
  for (auto& s : g_temp_slots)
    if (s.ready.load()) ::unlink(s.path);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// Removes a temporary file and forgets it.
void drop_temp(const fs::path& temp, int slot) {
  std::error_code ignore;
  fs::remove(temp, ignore);
  unregister_temp(slot);
}

int slot_of(const std::string& temp) {
  for (int i = 0; i < kTempSlots; ++i)
    if (g_temp_slots[i].ready.load() && temp == g_temp_slots[i].path) return i;
  return -1;
}
}  // namespace

std::string format_double(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), x);
  return std::string(buf, res.ptr);
}

std::string resolve_output_path(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::absolute(fs::path(path), ec);
  if (ec) p = fs::path(path);
  for (int depth = 0; depth < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++depth) {
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) break;
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  // Resolve symlinked directories too (the file itself may not exist yet).
  const fs::path dir = fs::weakly_canonical(p.parent_path(), ec);
  return ((ec ? p.parent_path() : dir) / p.filename()).lexically_normal().string();
}

void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (fs::path(path).filename().empty()) throw IOError(path + ": not a file name");
  const fs::path target(resolve_output_path(path));
  fs::path dir = target.parent_path();
  std::error_code ec;
  if (!dir.empty() && !fs::is_directory(dir, ec))
    throw IOError(path + ": cannot write, directory '" + dir.string() + "' does not exist");
  if (fs::is_directory(target, ec)) throw IOError(path + ": cannot write, it is a directory");
  // The temporary is renamed over the target: a device, FIFO or socket there would be replaced
  // by a regular file (through a symbolic link too, which resolve_output_path() follows).
  if (fs::exists(target, ec) && !fs::is_regular_file(target, ec))
    throw IOError(path + ": cannot write, it is not a regular file (a device, FIFO or socket)");
  const fs::path temp = dir / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                               std::to_string(g_temp_counter.fetch_add(1)));
  const int slot = register_temp(temp.string());
  std::ofstream out(temp, std::ios::binary | std::ios::trunc);
  if (!out) {
    const int err = errno;
    unregister_temp(slot);
    throw IOError(path + ": cannot create temporary file in '" + (dir.empty() ? std::string(".") : dir.string()) +
                  "': " + std::strerror(err));
  }
  auto discard = [&]() {
    out.close();
    drop_temp(temp, slot);
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
    throw IOError(path + ": write failed (disk full, file too large or I/O error)");
  }
  out.close();
  if (out.fail()) {
    discard();
    throw IOError(path + ": write failed while closing the file");
  }
  if (t_open_transaction) {
    t_open_transaction->staged_.push_back({temp.string(), target.string(), path});
    return;
  }
  fs::rename(temp, target, ec);
  if (ec) {
    drop_temp(temp, slot);
    throw IOError(path + ": cannot rename temporary file into place: " + ec.message());
  }
  unregister_temp(slot);
}

OutputTransaction::OutputTransaction() {
  if (t_open_transaction) throw std::logic_error("OutputTransaction: one is already open on this thread");
  t_open_transaction = this;
}

OutputTransaction::~OutputTransaction() {
  if (t_open_transaction == this) t_open_transaction = nullptr;
  if (!committed_)
    for (const Staged& s : staged_) drop_temp(s.temp, slot_of(s.temp));
}

void OutputTransaction::commit() {
  if (t_open_transaction == this) t_open_transaction = nullptr;
  committed_ = true;
  for (size_t i = 0; i < staged_.size(); ++i) {
    std::error_code ec;
    const int slot = slot_of(staged_[i].temp);
    fs::rename(staged_[i].temp, staged_[i].target, ec);
    if (ec) {
      for (size_t j = i; j < staged_.size(); ++j) drop_temp(staged_[j].temp, slot_of(staged_[j].temp));
      throw IOError(staged_[i].path + ": cannot rename temporary file into place: " + ec.message());
    }
    unregister_temp(slot);
  }
}

void remove_temporary_files_on_signals() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::signal(sig, remove_temps_and_reraise);
  ::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace heatcvt
