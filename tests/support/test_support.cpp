#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>
#include <sys/wait.h>

#include "heatcvt/mesh.h"

namespace heatcvt::test {

std::string data_path(const std::string& relative) {
  const std::filesystem::path dir(HEATCVT_DATA_DIR);
  if (!std::filesystem::is_directory(dir)) {
    ADD_FAILURE() << "test data directory missing: " << dir
                  << " (expected ../shared/data beside the repository; configure with -DHEATCVT_DATA_DIR=...)";
    throw std::runtime_error("missing test data directory " + dir.string());
  }
  const auto path = dir / relative;
  if (!std::filesystem::exists(path)) {
    ADD_FAILURE() << "test data file missing: " << path;
    throw std::runtime_error("missing test data file " + path.string());
  }
  return path.string();
}

TriangleMesh icosphere(int subdivisions) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                                    {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : v) x.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> nf;
    for (const auto& t : f) {
      int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      nf.push_back({t[0], a, c});
      nf.push_back({t[1], b, a});
      nf.push_back({t[2], c, b});
      nf.push_back({a, b, c});
    }
    f = nf;
  }
  TriangleMesh m;
  m.V.resize(v.size(), 3);
  m.F.resize(f.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) m.V.row(i) = v[i];
  for (size_t i = 0; i < f.size(); ++i) m.F.row(i) = f[i];
  return m;
}

TriangleMesh spiked_sphere(int subdivisions, double tip_radius) {
  TriangleMesh m = icosphere(subdivisions);
  m.V.row(0) *= tip_radius;
  return m;
}

TriangleMesh grid(int n, double x0, double x1, double y0, double y1, bool alternate) {
  TriangleMesh m;
  m.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.V.row(j * (n + 1) + i) << x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * j / n, 0.0;
  m.F.resize(2 * n * n, 3);
  int f = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      if (!alternate || (i + j) % 2 == 0) {
        m.F.row(f++) << a, b, d;
        m.F.row(f++) << a, d, c;
      } else {
        m.F.row(f++) << a, b, c;
        m.F.row(f++) << b, d, c;
      }
    }
  return m;
}

Eigen::MatrixX3d sphere_points(int n, double r, const Eigen::Vector3d& c, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixX3d P(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d(g(rng), g(rng), g(rng));
    P.row(i) = (c + r * d.normalized()).transpose();
  }
  return P;
}

TriangleMesh torus(int n, int m, double R, double r) {
  TriangleMesh t;
  t.V.resize(n * m, 3);
  t.F.resize(2 * n * m, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      double u = 2 * M_PI * i / n, v = 2 * M_PI * j / m;
      t.V.row(i * m + j) << (R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v);
    }
  int f = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      int a = i * m + j, b = ((i + 1) % n) * m + j, c = ((i + 1) % n) * m + (j + 1) % m, d = i * m + (j + 1) % m;
      t.F.row(f++) << a, b, c;
      t.F.row(f++) << a, c, d;
    }
  return t;
}

void scale_to_area(TriangleMesh& mesh, double area) {
  mesh.V *= std::sqrt(area / surface_area(mesh.V, mesh.F));
}

UnitSphere unit_area_sphere(int subdivisions) {
  UnitSphere u;
  u.mesh = icosphere(subdivisions);
  scale_to_area(u.mesh, 1.0);
  u.laplacian = cotan_laplacian(u.mesh.V, u.mesh.F);
  return u;
}

WorkingMesh working_mesh(const TriangleMesh& m) {
  WorkingMesh w(m.V, vertex_normals(m.V, m.F), std::vector<int>(m.V.rows(), -1));
  std::vector<MeshFace> faces;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) faces.push_back({m.F(f, 0), m.F(f, 1), m.F(f, 2)});
  w.set_faces(faces);
  return w;
}

}  // namespace heatcvt::test

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <unistd.h>

namespace heatcvt::test {

ScratchDir::ScratchDir(const std::string& tag) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "heatcvt_" + tag + "_" + (info ? std::string(info->name()) : "x") + "_" + std::to_string(::getpid());
  dir_ = (std::filesystem::temp_directory_path() / name).string();
  std::filesystem::remove_all(dir_);
  std::filesystem::create_directories(dir_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::string ScratchDir::path(const std::string& name) const { return dir_ + "/" + name; }

int ScratchDir::entries() const {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir_)) ++n;
  return n;
}

static std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult run_tool(const std::string& tool, const std::string& args) {
  const std::string exe = std::string(HEATCVT_BIN_DIR) + "/" + tool;
  if (!std::filesystem::exists(exe)) {
    ADD_FAILURE() << "tool not built: " << exe;
    return {};
  }
  const auto base = std::filesystem::temp_directory_path() /
                    ("heatcvt_cmd_" + std::to_string(::getpid()) + "_" + std::to_string(std::rand()));
  const std::string out = base.string() + ".out", err = base.string() + ".err";
  const std::string cmd = exe + " " + args + " > " + out + " 2> " + err;
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

double json_number(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\"\\s*:\\s*(-?[0-9.eE+-]+)"))) {
    ADD_FAILURE() << key << " not in:\n" << json;
    return std::nan("");
  }
  return std::stod(m[1].str());
}

std::vector<std::string> failed_checks(const std::string& json) {
  const nlohmann::json report = nlohmann::json::parse(json, nullptr, false);
  if (report.is_discarded() || !report.contains("checks") || report["checks"].empty()) {
    ADD_FAILURE() << "no checks in:\n" << json;
    return {"<no checks>"};
  }
  std::vector<std::string> failed;
  for (const auto& c : report["checks"])
    if (!(c["passed"].is_boolean() && c["passed"].get<bool>())) failed.push_back(c["name"].get<std::string>());
  return failed;
}

void expect_tool_failure(const std::string& tool, const CommandResult& r, const std::vector<std::string>& needles,
                         const ScratchDir& dir, int expected_entries) {
  EXPECT_NE(r.exit_code, 0);
  std::vector<std::string> error_lines;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);)
    if (line.find("error") != std::string::npos) error_lines.push_back(line);
  ASSERT_EQ(error_lines.size(), 1u) << r.err;
  EXPECT_EQ(error_lines[0].rfind(tool + ": error: ", 0), 0u) << error_lines[0];
  for (const auto& n : needles)
    EXPECT_NE(error_lines[0].find(n), std::string::npos) << "'" << n << "' not in: " << error_lines[0];
  EXPECT_EQ(dir.entries(), expected_entries) << "an output or temporary file was left behind";
}

}  // namespace heatcvt::test
