// The nncoords tool end to end: interpolated values as a PLY (colour for 3 columns in [0,1]),
// skinning weights as text, and every class of bad input gives one clear error line naming the
// file, a non-zero exit and no output file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "heatcvt/mesh_io.h"
#include "heatcvt/shapes.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

void expect_clean_failure(const test::CommandResult& r, const std::vector<std::string>& needles,
                          const test::ScratchDir& dir, int expected_entries) {
  test::expect_tool_failure("nncoords", r, needles, dir, expected_entries);
}

// An icosphere written as OBJ, and sites at four of its vertices.
struct SphereCase {
  test::ScratchDir dir{"nn"};
  std::string mesh, sites;
  TriangleMesh m;
  SphereCase() {
    m = test::icosphere(3);
    mesh = dir.path("sphere.obj");
    write_mesh(mesh, m.V, m.F);
    sites = dir.path("sites.xyz");
    std::ostringstream s;
    s.precision(17);
    for (int v : {0, 3, 5, 9}) s << m.V(v, 0) << ' ' << m.V(v, 1) << ' ' << m.V(v, 2) << '\n';
    test::write_text_file(sites, s.str());
  }
};

}  // namespace

TEST(NncoordsTool, InterpolatesColoursAndWritesWeights) {
  SphereCase s;
  test::write_text_file(s.dir.path("rgb.txt"), "1 0 0\n0 1 0\n0 0 1\n1 1 0\n");
  auto r = test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --values " + s.dir.path("rgb.txt") + " -o " +
                                          s.dir.path("out.ply") + " --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("nncoords: 4 sites"), std::string::npos) << r.out;
  // the PLY: same mesh, value_0..2 and colours per vertex
  const TriangleMesh back = read_mesh(s.dir.path("out.ply"));
  EXPECT_EQ(back.V.rows(), s.m.V.rows());
  EXPECT_EQ(back.F.rows(), s.m.F.rows());
  std::ifstream in(s.dir.path("out.ply"));
  std::string line;
  int nv = 0;
  bool colour = false, header = true;
  int checked = 0;
  std::vector<Eigen::Vector3d> values;  // value_0..2 per vertex, checked against the weights below
  while (std::getline(in, line)) {
    if (header) {
      if (line.rfind("element vertex", 0) == 0) nv = std::stoi(line.substr(15));
      colour |= line == "property uchar red";
      if (line == "end_header") header = false;
      continue;
    }
    if (checked >= nv) break;
    std::istringstream ls(line);
    double x, y, z, a, b, c;
    ls >> x >> y >> z >> a >> b >> c;
    EXPECT_GE(std::min({a, b, c}), -1e-12);
    EXPECT_LE(std::max({a, b, c}), 1 + 1e-12);
    values.emplace_back(a, b, c);
    ++checked;
  }
  EXPECT_EQ(checked, s.m.V.rows());
  EXPECT_TRUE(colour) << "3 columns in [0,1] are written as colour";

  // weights: one line per vertex, weights sum to 1, Lagrange at the site vertices
  auto w = test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --weights " + s.dir.path("w.txt") + " -q");
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_TRUE(w.err.empty()) << w.err;
  std::ifstream win(s.dir.path("w.txt"));
  const Eigen::Vector3d site_rows[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};  // rgb.txt
  int rows = 0;
  while (std::getline(win, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    int v, k;
    ls >> v >> k;
    EXPECT_EQ(v, rows);
    double sum = 0;
    Eigen::Vector3d interpolated = Eigen::Vector3d::Zero();
    for (int i = 0; i < k; ++i) {
      int site;
      double weight;
      ls >> site >> weight;
      ASSERT_GE(site, 0);
      ASSERT_LT(site, 4);
      EXPECT_GT(weight, 0);
      sum += weight;
      interpolated += weight * site_rows[site];
      if (v == 0 || v == 3 || v == 5 || v == 9) EXPECT_NEAR(weight, 1.0, 1e-9) << "vertex " << v;
    }
    EXPECT_NEAR(sum, 1.0, 1e-9);
    // The interpolated values are the weighted sums of the site rows (the same coordinates), up
    // to the precision of the two text files.
    ASSERT_LT(v, static_cast<int>(values.size()));
    EXPECT_LT((values[v] - interpolated).norm(), 1e-6) << "vertex " << v;
    ++rows;
  }
  EXPECT_EQ(rows, s.m.V.rows());
}

TEST(NncoordsTool, MissingAndMalformedFiles) {
  SphereCase s;
  const std::string missing = s.dir.path("nope.obj");
  expect_clean_failure(test::run_tool("nncoords", missing + " --sites " + s.sites + " --weights " + s.dir.path("w.txt")),
                       {missing}, s.dir, 2);
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.dir.path("none.xyz") + " --weights " +
                                                      s.dir.path("w.txt")),
                       {s.dir.path("none.xyz")}, s.dir, 2);
  test::write_text_file(s.dir.path("bad.xyz"), "0 0 1\n1 zero 0\n");
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.dir.path("bad.xyz") + " --weights " +
                                                      s.dir.path("w.txt")),
                       {s.dir.path("bad.xyz"), "line 2"}, s.dir, 3);
  test::write_text_file(s.dir.path("vals.txt"), "1\n2\nthree\n4\n");
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --values " + s.dir.path("vals.txt") +
                                                      " -o " + s.dir.path("o.ply")),
                       {s.dir.path("vals.txt"), "line 3"}, s.dir, 4);
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --weights " + s.dir.path("w.txt") +
                                                      " --t-coef 1e10"),
                       {"--t-coef"}, s.dir, 4);
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --weights " + s.dir.path("w.txt") +
                                                      " --threads 1000000"),
                       {"--threads"}, s.dir, 4);
}

TEST(NncoordsTool, BadSites) {
  SphereCase s;
  // fewer than 2 sites
  test::write_text_file(s.dir.path("one.xyz"), "0 0 1\n");
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.dir.path("one.xyz") + " --weights " +
                                                      s.dir.path("w.txt")),
                       {s.dir.path("one.xyz"), "at least 2"}, s.dir, 3);
  // a site off the surface
  test::write_text_file(s.dir.path("off.xyz"), "0 0 1\n0 0 3\n");
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.dir.path("off.xyz") + " --weights " +
                                                      s.dir.path("w.txt")),
                       {s.dir.path("off.xyz"), "site 2", "off the surface"}, s.dir, 4);
  // duplicate sites
  std::ostringstream dup;
  dup << s.m.V(0, 0) << ' ' << s.m.V(0, 1) << ' ' << s.m.V(0, 2) << '\n' << s.m.V(7, 0) << ' ' << s.m.V(7, 1) << ' '
      << s.m.V(7, 2) << '\n' << s.m.V(0, 0) << ' ' << s.m.V(0, 1) << ' ' << s.m.V(0, 2) << '\n';
  test::write_text_file(s.dir.path("dup.xyz"), dup.str());
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.dir.path("dup.xyz") + " --weights " +
                                                      s.dir.path("w.txt")),
                       {s.dir.path("dup.xyz"), "duplicates"}, s.dir, 5);
}

TEST(NncoordsTool, RowCountMismatchAndUsage) {
  SphereCase s;
  test::write_text_file(s.dir.path("vals.txt"), "1\n2\n3\n");
  expect_clean_failure(test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --values " + s.dir.path("vals.txt") +
                                                      " -o " + s.dir.path("o.ply")),
                       {s.dir.path("vals.txt"), "3 rows of values for 4 sites"}, s.dir, 3);
  // no output chosen, or both: usage error (non-zero exit), nothing written
  auto r = test::run_tool("nncoords", s.mesh + " --sites " + s.sites);
  EXPECT_NE(r.exit_code, 0);
  r = test::run_tool("nncoords", s.mesh + " --sites " + s.sites + " --values " + s.dir.path("vals.txt") + " --weights " +
                                     s.dir.path("w.txt"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(s.dir.entries(), 3);
  // --help lists the defaults
  r = test::run_tool("nncoords", "--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--t-coef"), std::string::npos);
  EXPECT_NE(r.out.find("--t-coef FLOAT=1 "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--samples INT=0 "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--threads"), std::string::npos);
}
