// The heatvoronoi tool end to end: a real run, and every class of bad input gives one clear
// error line naming the file, a non-zero exit and no output file.
#include <gtest/gtest.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Asserts: exit code non-zero, exactly one "heatvoronoi: error:" line on stderr mentioning
// every needle, no output file and no temporary left behind.
void expect_clean_failure(const test::CommandResult& r, const std::vector<std::string>& needles,
                          const test::ScratchDir& dir, int expected_entries) {
  test::expect_tool_failure("heatvoronoi", r, needles, dir, expected_entries);
}

const char* kTetra =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

}  // namespace

TEST(HeatVoronoiTool, RealMeshProducesCellsEdgesCentroidsAndReport) {
  test::ScratchDir dir("hv");
  const std::string mesh = test::data_path("meshes/spot.obj");
  auto r = test::run_tool("heatvoronoi", mesh + " -o " + dir.path("cells.ply") + " --sites 30 --edges " +
                                             dir.path("edges.obj") + " --centroids " + dir.path("c.xyz") + " --report " +
                                             dir.path("r.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << "--quiet must silence stderr: " << r.err;
  TriangleMesh cells = read_mesh(dir.path("cells.ply"));
  TriangleMesh input = read_mesh(mesh);
  EXPECT_GE(cells.F.rows(), input.F.rows());
  EXPECT_NEAR(surface_area(cells.V, cells.F), surface_area(input.V, input.F), 1e-9 * surface_area(input.V, input.F));
  // Centroids: 30 points "x y z", each on the input surface (a heat centroid is a surface point):
  // within a mean edge length of an input vertex.
  const double h = mean_edge_length(input.V, input.F);
  std::ifstream c(dir.path("c.xyz"));
  int lines = 0;
  for (std::string line; std::getline(c, line);) {
    std::istringstream ls(line);
    Eigen::RowVector3d p;
    ASSERT_TRUE(ls >> p[0] >> p[1] >> p[2]) << line;
    EXPECT_LT((input.V.rowwise() - p).rowwise().norm().minCoeff(), h) << line;
    ++lines;
  }
  EXPECT_EQ(lines, 30);
  // Edges: the OBJ holds the refined vertices of cells.ply and one polyline per Voronoi edge;
  // every polyline runs between two Voronoi vertices (points where three or more cells meet).
  std::ifstream e(dir.path("edges.obj"));
  int edge_points = 0, polylines = 0;
  std::map<int, int> endpoint_uses;
  for (std::string line; std::getline(e, line);) {
    if (line.rfind("v ", 0) == 0) ++edge_points;
    if (line.rfind("l ", 0) != 0) continue;
    ++polylines;
    std::istringstream ls(line.substr(2));
    std::vector<int> ids;
    for (int id; ls >> id;) ids.push_back(id);
    ASSERT_GE(ids.size(), 2u) << line;
    for (int id : ids) ASSERT_TRUE(id >= 1 && id <= edge_points) << line;
    ++endpoint_uses[ids.front()];
    ++endpoint_uses[ids.back()];
  }
  EXPECT_EQ(edge_points, cells.V.rows());
  // Spot is a closed genus-0 surface: the cells, Voronoi edges and Voronoi vertices form a
  // cell complex of Euler characteristic 2, and every Voronoi vertex ends at least 3 edges.
  EXPECT_EQ(static_cast<int>(endpoint_uses.size()) - polylines + 30, 2);
  for (const auto& [id, uses] : endpoint_uses) EXPECT_GE(uses, 3) << "Voronoi vertex " << id;
  // Report: the counts of the files and of the input.
  const std::string json = test::read_file(dir.path("r.json"));
  EXPECT_EQ(test::json_number(json, "cells"), 30);
  EXPECT_EQ(test::json_number(json, "vertices"), input.V.rows());
  EXPECT_EQ(test::json_number(json, "faces"), input.F.rows());
  EXPECT_EQ(test::json_number(json, "refined_vertices"), cells.V.rows());
  EXPECT_EQ(test::json_number(json, "refined_faces"), cells.F.rows());
  EXPECT_EQ(test::json_number(json, "voronoi_edges"), polylines);
  EXPECT_EQ(test::json_number(json, "voronoi_vertices"), static_cast<double>(endpoint_uses.size()));
  EXPECT_NEAR(30 * test::json_number(json, "cell_area_mean"), surface_area(input.V, input.F), 1e-6 * surface_area(input.V, input.F));
  // same seed, same output
  auto r2 = test::run_tool("heatvoronoi", mesh + " -o " + dir.path("cells2.ply") + " --sites 30 -q");
  ASSERT_EQ(r2.exit_code, 0);
  std::ifstream a(dir.path("cells.ply"), std::ios::binary), b(dir.path("cells2.ply"), std::ios::binary);
  std::string sa((std::istreambuf_iterator<char>(a)), {}), sb((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(sa, sb);
}

TEST(HeatVoronoiTool, MissingFile) {
  test::ScratchDir dir("hv");
  const std::string missing = dir.path("nope.obj");
  expect_clean_failure(test::run_tool("heatvoronoi", missing + " -o " + dir.path("o.ply")), {missing}, dir, 0);
}

TEST(HeatVoronoiTool, UnknownFormat) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("mesh.xyzw"), kTetra);
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("mesh.xyzw") + " -o " + dir.path("o.ply")),
                       {dir.path("mesh.xyzw")}, dir, 1);
}

TEST(HeatVoronoiTool, TruncatedFile) {
  test::ScratchDir dir("hv");
  std::ifstream in(test::data_path("meshes/knot_open3d.ply"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  test::write_text_file(dir.path("cut.ply"), bytes.substr(0, bytes.size() / 2));
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("cut.ply") + " -o " + dir.path("o.ply")),
                       {dir.path("cut.ply"), "truncated"}, dir, 1);
}

TEST(HeatVoronoiTool, FaceIndexOutOfRange) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("bad.obj") + " -o " + dir.path("o.ply")),
                       {dir.path("bad.obj"), "range"}, dir, 1);
}

TEST(HeatVoronoiTool, NaNCoordinates) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("nan.off"), "OFF\n4 4 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("nan.off") + " -o " + dir.path("o.ply")),
                       {dir.path("nan.off"), "NaN"}, dir, 1);
}

TEST(HeatVoronoiTool, NoFaces) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("pts.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("pts.obj") + " -o " + dir.path("o.ply")),
                       {dir.path("pts.obj"), "no faces"}, dir, 1);
}

TEST(HeatVoronoiTool, ImpossibleOptions) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("t.obj"), kTetra);
  const std::string base = dir.path("t.obj") + " -o " + dir.path("o.ply");
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --sites 5"), {"--sites", "exceeds"}, dir, 1);
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --sites 0"), {"--sites"}, dir, 1);
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --t-coef -2"), {"--t-coef"}, dir, 1);
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --t-coef 1e10"), {"--t-coef"}, dir, 1);
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --threads 1000000"), {"--threads"}, dir, 1);
  // A site far off the surface (another mesh's, other units) is an error, not snapped silently;
  // --snap-tolerance lets it through.
  test::write_text_file(dir.path("far.txt"), "0 0 0\n5 5 5\n");
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --sites-file " + dir.path("far.txt")),
                       {dir.path("far.txt"), "site 2", "off the surface"}, dir, 2);
  EXPECT_EQ(test::run_tool("heatvoronoi", base + " -q --snap-tolerance 10 --sites-file " + dir.path("far.txt")).exit_code, 0);
  std::remove(dir.path("o.ply").c_str());
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --snap-tolerance 0 --sites-file " + dir.path("far.txt")),
                       {"--snap-tolerance"}, dir, 2);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n1 2\n");
  expect_clean_failure(test::run_tool("heatvoronoi", base + " --sites-file " + dir.path("s.txt")),
                       {dir.path("s.txt"), "line 2"}, dir, 3);
}

TEST(HeatVoronoiTool, UnwritableOutputLeavesNothing) {
  test::ScratchDir dir("hv");
  test::write_text_file(dir.path("t.obj"), kTetra);
  const std::string out = dir.path("missing_dir/o.ply");
  expect_clean_failure(test::run_tool("heatvoronoi", dir.path("t.obj") + " -o " + out + " --sites 2"), {out}, dir, 1);
}

TEST(HeatVoronoiTool, DegenerateAndNonManifoldMeshesAreHandled) {
  test::ScratchDir dir("hv");
  // tetrahedron + a zero-area face + a fin sharing edge (1,2): non-manifold edge
  test::write_text_file(dir.path("nm.obj"), std::string(kTetra) + "v 0.5 0 0\nv 1 1 -1\nf 1 2 5\nf 1 2 6\n");
  auto r = test::run_tool("heatvoronoi", dir.path("nm.obj") + " -o " + dir.path("o.ply") + " --sites 3");
  // Written; status 3 because the generator on the vertex of the zero-area face gets an empty cell.
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.out.find("FAIL no_empty_cells"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("degenerate"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir.path("o.ply")));
}
