// Fuzz suite: small valid files of every format the readers accept, built in code, and
// deterministic mutations of them (truncations, bit flips, swapped and huge numbers, NaN, repeated
// lines and fields, control bytes), run against every reader in-process and, for a subset,
// against every tool as a subprocess. Asserted: no crash or signal, no hang (a generous deadline
// kills a hung tool), and either a valid result or exactly one error line naming the file, with
// no output and no temporary file left.
//
// HEATCVT_FUZZ_CASES sets the number of in-process cases (default kDefaultCases); every
// kToolEvery-th case also runs the tools. `HEATCVT_FUZZ_CASES=50000 test_fuzz` is the long run.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "test_support.h"

using namespace heatcvt;
namespace fs = std::filesystem;

namespace {

constexpr int kDefaultCases = 3000;
constexpr int kToolEvery = 25;              // every 25th case also runs the tools
constexpr double kToolDeadlineSeconds = 120;  // a tool still running after this is hung

struct Seed {
  std::string name;  // file name with the extension that selects the reader
  std::string bytes;
  bool mesh;         // read_mesh accepts it (else read_cloud)
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The corpus: one small valid file per format (and encoding) the readers accept.
std::vector<Seed> build_corpus(const test::ScratchDir& dir) {
  const TriangleMesh m = test::icosphere(2);  // 162 vertices, 320 faces
  std::vector<Seed> seeds;
  MeshWriteOptions ascii;
  ascii.ply_encoding = PlyEncoding::ascii;
  MeshWriteOptions big;
  big.ply_encoding = PlyEncoding::binary_big_endian;
  const std::vector<std::tuple<std::string, MeshWriteOptions>> meshes = {
      {"m.obj", {}}, {"m.off", {}}, {"m_ascii.ply", ascii}, {"m_le.ply", {}}, {"m_be.ply", big}, {"m_bin.stl", {}}};
  for (const auto& [name, opt] : meshes) {
    write_mesh(dir.path(name), m.V, m.F, {}, opt);
    seeds.push_back({name, slurp(dir.path(name)), true});
  }
  std::ostringstream stl, xyz, pwn, ply;
  stl.precision(9);
  stl << "solid s\n";
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    stl << "facet normal 0 0 0\nouter loop\n";
    for (int k = 0; k < 3; ++k) stl << "vertex " << m.V(m.F(f, k), 0) << ' ' << m.V(m.F(f, k), 1) << ' ' << m.V(m.F(f, k), 2) << '\n';
    stl << "endloop\nendfacet\n";
  }
  stl << "endsolid s\n";
  seeds.push_back({"m_ascii.stl", stl.str(), true});
  xyz.precision(17);
  pwn.precision(17);
  xyz << m.V.rows() << '\n';
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    xyz << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
    pwn << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << ' ' << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2)
        << '\n';
  }
  seeds.push_back({"c.xyz", xyz.str(), false});
  seeds.push_back({"c.pwn", pwn.str(), false});
  seeds.push_back({"c.txt", xyz.str(), false});
  ply << "ply\nformat ascii 1.0\nelement vertex " << m.V.rows()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
         "end_header\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    ply << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << " 0 0 1\n";
  seeds.push_back({"c_ascii.ply", ply.str(), false});
  pcl::PointCloud<pcl::PointNormal> cloud;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(m.V(i, 0)), p.y = static_cast<float>(m.V(i, 1)), p.z = static_cast<float>(m.V(i, 2));
    p.normal_x = p.x, p.normal_y = p.y, p.normal_z = p.z;
    cloud.push_back(p);
  }
  pcl::PCDWriter writer;
  writer.writeASCII(dir.path("c_ascii.pcd"), cloud);
  writer.writeBinary(dir.path("c_bin.pcd"), cloud);
  writer.writeBinaryCompressed(dir.path("c_comp.pcd"), cloud);
  for (const char* name : {"c_ascii.pcd", "c_bin.pcd", "c_comp.pcd"}) seeds.push_back({name, slurp(dir.path(name)), false});
  for (const auto& s : seeds) fs::remove(dir.path(s.name));
  return seeds;
}

// Token boundaries of a text (whitespace separated).
std::vector<std::pair<size_t, size_t>> tokens(const std::string& s) {
  std::vector<std::pair<size_t, size_t>> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    size_t j = i;
    while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
    if (j > i) out.emplace_back(i, j - i);
    i = j;
  }
  return out;
}

std::vector<std::pair<size_t, size_t>> lines(const std::string& s) {
  std::vector<std::pair<size_t, size_t>> out;
  size_t i = 0;
  while (i < s.size()) {
    size_t j = s.find('\n', i);
    j = j == std::string::npos ? s.size() : j + 1;
    out.emplace_back(i, j - i);
    i = j;
  }
  return out;
}

// One deterministic mutation of `s`, chosen and parametrised by `rng`.
std::string mutate(std::string s, std::mt19937& rng) {
  auto pick = [&](size_t n) { return n == 0 ? size_t(0) : std::uniform_int_distribution<size_t>(0, n - 1)(rng); };
  static const std::vector<std::string> odd = {"nan", "-nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "1e400",
                                               "99999999999999999999", "-1", "0", "2147483648", "-2147483649",
                                               "4294967295", "1,5", "0x10", "+", "-", "1e", ".", "3.5", "\x1b[31m",
                                               "\x07", ""};
  static const std::string controls = std::string("\x1b\x07\r\f\v\b", 6) + std::string(1, '\0');
  const int kind = static_cast<int>(pick(9));
  switch (kind) {
    case 0:  // truncation
      s.resize(pick(s.size() + 1));
      break;
    case 1: {  // bit flips
      const int flips = 1 + static_cast<int>(pick(8));
      for (int i = 0; i < flips && !s.empty(); ++i) s[pick(s.size())] ^= static_cast<char>(1u << pick(8));
      break;
    }
    case 2: {  // a token replaced by an odd number or text
      const auto t = tokens(s);
      if (!t.empty()) {
        const auto [at, len] = t[pick(t.size())];
        s.replace(at, len, odd[pick(odd.size())]);
      }
      break;
    }
    case 3: {  // two tokens swapped
      const auto t = tokens(s);
      if (t.size() >= 2) {
        auto a = t[pick(t.size())], b = t[pick(t.size())];
        if (a.first > b.first) std::swap(a, b);
        if (a.first + a.second <= b.first) {
          const std::string ta = s.substr(a.first, a.second), tb = s.substr(b.first, b.second);
          s.replace(b.first, b.second, ta);
          s.replace(a.first, a.second, tb);
        }
      }
      break;
    }
    case 4: {  // a line repeated (repeated header fields, extra elements)
      const auto l = lines(s);
      if (!l.empty()) {
        const auto [at, len] = l[pick(std::min<size_t>(l.size(), 16))];  // mostly header lines
        s.insert(at, s.substr(at, len));
      }
      break;
    }
    case 5: {  // control bytes inserted
      const int n = 1 + static_cast<int>(pick(4));
      for (int i = 0; i < n; ++i) s.insert(pick(s.size() + 1), 1, controls[pick(controls.size())]);
      break;
    }
    case 6: {  // a line deleted
      const auto l = lines(s);
      if (!l.empty()) {
        const auto [at, len] = l[pick(l.size())];
        s.erase(at, len);
      }
      break;
    }
    case 7: {  // random bytes overwritten
      const int n = 1 + static_cast<int>(pick(8));
      if (!s.empty()) {
        const size_t at = pick(s.size());
        for (int i = 0; i < n && at + i < s.size(); ++i) s[at + i] = static_cast<char>(pick(256));
      }
      break;
    }
    default: {  // a number in the header made huge (counts, sizes)
      const size_t end = std::min<size_t>(s.size(), 400);
      std::vector<size_t> digits;
      for (size_t i = 0; i < end; ++i)
        if (std::isdigit(static_cast<unsigned char>(s[i])) && (i == 0 || !std::isdigit(static_cast<unsigned char>(s[i - 1]))))
          digits.push_back(i);
      if (!digits.empty()) {
        const size_t at = digits[pick(digits.size())];
        size_t len = 0;
        while (at + len < s.size() && std::isdigit(static_cast<unsigned char>(s[at + len]))) ++len;
        static const char* huge[] = {"4294967295", "2000000000", "999999999999", "0", "1"};
        s.replace(at, len, huge[pick(5)]);
      }
      break;
    }
  }
  return s;
}

bool one_clean_line(const std::string& message) {
  for (unsigned char c : message)
    if (c < 0x20 || c == 0x7f) return false;
  return true;
}

// In-process: a valid result or a heatcvt::Error "<path>: <problem>" on one clean line.
void check_reader(const Seed& seed, const std::string& path, int case_no) {
  const std::string where = seed.name + " case " + std::to_string(case_no);
  try {
    if (seed.mesh) {
      const TriangleMesh m = read_mesh(path);
      EXPECT_TRUE(m.V.allFinite()) << where;
      EXPECT_GT(m.F.rows(), 0) << where;
      EXPECT_TRUE(m.F.minCoeff() >= 0 && m.F.maxCoeff() < m.V.rows()) << where;
    }
    if (!seed.mesh || fs::path(path).extension() == ".ply") {
      const PointCloud c = read_cloud(path);
      EXPECT_GT(c.P.rows(), 0) << where;
      EXPECT_TRUE(c.P.allFinite()) << where;
    }
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << where << ": " << what;
    EXPECT_TRUE(one_clean_line(what)) << where << ": control bytes in: " << quote_excerpt(what, 300);
  } catch (const std::exception& e) {
    ADD_FAILURE() << where << ": not a heatcvt::Error: " << e.what();
  }
}

struct Run {
  bool signaled = false, hung = false;
  int status = -1;
  std::string err;
};

// Runs a tool with a deadline (fork / exec, stdout discarded, stderr captured).
Run run_with_deadline(const std::string& tool, const std::vector<std::string>& args, const std::string& err_path) {
  const std::string exe = std::string(HEATCVT_BIN_DIR) + "/" + tool;
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!std::freopen("/dev/null", "w", stdout) || !std::freopen(err_path.c_str(), "w", stderr)) ::_exit(127);
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  Run r;
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > kToolDeadlineSeconds) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      r.hung = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.signaled = !r.hung && WIFSIGNALED(status);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err_path);
  fs::remove(err_path);
  return r;
}

// Subprocess: no signal, no hang; on an error exactly one "<tool>: error: <file>: ..." line and no
// output or temporary file; on success (0, or 3 = written but failed checks) the outputs exist.
void check_tool(const std::string& tool, const std::vector<std::string>& args, const std::vector<std::string>& outputs,
                const std::vector<std::string>& named_files, const test::ScratchDir& dir, int entries_before,
                const std::string& where) {
  const Run r = run_with_deadline(tool, args, dir.path("stderr.txt"));
  ASSERT_FALSE(r.hung) << where << ": " << tool << " hung";
  ASSERT_FALSE(r.signaled) << where << ": " << tool << " died of a signal";
  if (r.status == 0 || r.status == 3) {
    for (const auto& o : outputs) EXPECT_TRUE(fs::exists(o)) << where << ": " << o << " missing";
    for (const auto& o : outputs) fs::remove(o);
  } else {
    EXPECT_TRUE(r.status == 1 || r.status == 2) << where << ": exit " << r.status;
    std::vector<std::string> lines;
    std::istringstream in(r.err);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    ASSERT_EQ(lines.size(), 1u) << where << ": " << r.err;
    const std::string head = tool + ": error: ";
    EXPECT_EQ(lines[0].rfind(head, 0), 0u) << where << ": " << lines[0];
    bool names_file = false;
    for (const auto& f : named_files) names_file |= lines[0].rfind(head + f + ": ", 0) == 0;
    EXPECT_TRUE(names_file) << where << ": " << lines[0];
    EXPECT_TRUE(one_clean_line(lines[0])) << where;
  }
  EXPECT_EQ(dir.entries(), entries_before) << where << ": an output or temporary file was left behind";
}

int fuzz_cases() {
  const char* env = std::getenv("HEATCVT_FUZZ_CASES");
  return env ? std::max(1, std::atoi(env)) : kDefaultCases;
}

}  // namespace

TEST(Fuzz, CorpusIsValid) {
  test::ScratchDir dir("fuzz");
  const auto seeds = build_corpus(dir);
  ASSERT_EQ(seeds.size(), 14u);
  for (const auto& s : seeds) {
    test::write_text_file(dir.path(s.name), s.bytes);
    if (s.mesh) EXPECT_EQ(read_mesh(dir.path(s.name)).V.rows(), 162) << s.name;
    else EXPECT_EQ(read_cloud(dir.path(s.name)).P.rows(), 162) << s.name;
  }
}

TEST(Fuzz, MutatedFilesAgainstReadersAndTools) {
  test::ScratchDir dir("fuzz");
  const auto seeds = build_corpus(dir);
  // Sites for nncoords: two vertices of the unmutated icosphere.
  const TriangleMesh ico = test::icosphere(2);
  std::ostringstream sites;
  sites.precision(17);
  for (int v : {0, 100}) sites << ico.V(v, 0) << ' ' << ico.V(v, 1) << ' ' << ico.V(v, 2) << '\n';
  test::write_text_file(dir.path("sites.txt"), sites.str());
  const int cases = fuzz_cases();
  int tool_runs = 0;
  for (int c = 0; c < cases; ++c) {
    std::mt19937 rng(static_cast<unsigned>(c));
    const Seed& seed = seeds[c % seeds.size()];
    std::string bytes = seed.bytes;
    const int rounds = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < rounds; ++k) bytes = mutate(std::move(bytes), rng);
    const std::string in = dir.path("in_" + seed.name);
    test::write_text_file(in, bytes);
    check_reader(seed, in, c);
    if (c % kToolEvery == 0) {
      const int entries = dir.entries();
      const std::string where = seed.name + " case " + std::to_string(c);
      const std::vector<std::string> common = {"-q", "--threads", "1"};
      auto with = [&](std::vector<std::string> a) {
        a.insert(a.end(), common.begin(), common.end());
        return a;
      };
      if (seed.mesh) {
        check_tool("meshcvt", with({in, "-n", "8", "-i", "2", "--surface-lloyd", "2", "-o", dir.path("o.obj")}),
                   {dir.path("o.obj")}, {in}, dir, entries, where);
        check_tool("heatvoronoi", with({in, "--sites", "4", "-o", dir.path("o.ply"), "--report", dir.path("r.json")}),
                   {dir.path("o.ply"), dir.path("r.json")}, {in}, dir, entries, where);
        check_tool("nncoords", with({in, "--sites", dir.path("sites.txt"), "--weights", dir.path("w.txt")}),
                   {dir.path("w.txt")}, {in, dir.path("sites.txt")}, dir, entries, where);
        tool_runs += 3;
      } else {
        check_tool("cloud2mesh",
                   with({in, "-n", "10", "-i", "1", "--surface-lloyd", "2", "-k", "8", "-o", dir.path("o.ply")}),
                   {dir.path("o.ply")}, {in}, dir, entries, where);
        tool_runs += 1;
      }
    }
    fs::remove(in);
    if (::testing::Test::HasFatalFailure()) return;
  }
  std::printf("fuzz: %d mutated files against the readers, %d tool runs\n", cases, tool_runs);
}
