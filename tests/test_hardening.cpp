// Hardening of the readers and the tools against hostile input: no crash, one clear error line,
// scale invariance, all-or-nothing outputs, exit statuses, the shared JSON report schema.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "heatcvt/atomic_file.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/cloud_stream.h"
#include "heatcvt/errors.h"
#include "heatcvt/heatcvt.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/natural_neighbour.h"
#include "heatcvt/normalize.h"
#include "heatcvt/parallel.h"
#include "heatcvt/pcl/heat_cvt_reconstruction.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/shapes.h"
#include "test_support.h"

using namespace heatcvt;
namespace fs = std::filesystem;

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

bool has_control_bytes(const std::string& s) {
  for (unsigned char c : s)
    if (c < 0x20 || c == 0x7f) return true;
  return false;
}

// The tool failed with exit status 2 and exactly one line "<tool>: error: <subject>: ..." on
// stderr (the subject is the file or option at fault), free of control bytes and of internal
// function names, and the scratch directory holds `entries` entries (no output, no temporary).
void expect_bad_input(const test::CommandResult& r, const std::string& tool, const std::string& subject,
                      const test::ScratchDir& dir, int entries) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = lines_of(r.err);
  std::vector<std::string> errors;
  for (const auto& l : lines)
    if (l.find("error") != std::string::npos) errors.push_back(l);
  ASSERT_EQ(errors.size(), 1u) << r.err;
  const std::string head = tool + ": error: " + subject;
  EXPECT_EQ(errors[0].rfind(head, 0), 0u) << "'" << errors[0] << "' does not start with '" << head << "'";
  EXPECT_FALSE(has_control_bytes(errors[0])) << errors[0];
  for (const char* internal : {"reconstruct_surface", "point_laplacian", "validate_triangle_mesh", "cotan_laplacian",
                               "HeatSolver", "k_nearest_neighbors", "bounding_box_frame"})
    EXPECT_EQ(errors[0].find(internal), std::string::npos) << errors[0];
  EXPECT_EQ(dir.entries(), entries) << "an output or temporary file was left behind";
}

void write_obj(const std::string& path, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  std::ostringstream s;
  s.precision(17);
  for (Eigen::Index i = 0; i < V.rows(); ++i) s << "v " << V(i, 0) << ' ' << V(i, 1) << ' ' << V(i, 2) << '\n';
  for (Eigen::Index f = 0; f < F.rows(); ++f) s << "f " << F(f, 0) + 1 << ' ' << F(f, 1) + 1 << ' ' << F(f, 2) + 1 << '\n';
  test::write_text_file(path, s.str());
}

// icosphere(3) with a deterministic radial jitter: no symmetric ties for the farthest-point start.
TriangleMesh bumpy_sphere() {
  TriangleMesh m = test::icosphere(3);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) *= 1.0 + 0.05 * std::sin(7.0 * i);
  return m;
}

const char* kTetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

// A PLY triangle whose float-typed face list holds a NaN index.
const char* kNanIndexPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    "3 nan 1 2\n3 0 1 3\n";

}  // namespace

// --- 1. crashes -------------------------------------------------------------------------------

TEST(Hardening, NanIndexInFloatFaceListIsAnError) {
  test::ScratchDir dir("hard");
  test::write_text_file(dir.path("nan.ply"), kNanIndexPly);
  try {
    read_mesh(dir.path("nan.ply"));
    FAIL() << "a NaN face index was accepted";
  } catch (const IOError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex index nan"), std::string::npos) << e.what();
  }
  // A non-integer index in a float list is no index either.
  std::string frac = kNanIndexPly;
  frac.replace(frac.find("3 nan 1 2"), 9, "3 0.5 1 2");
  test::write_text_file(dir.path("frac.ply"), frac);
  EXPECT_THROW(read_mesh(dir.path("frac.ply")), IOError);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n1 0 0\n");
  expect_bad_input(test::run_tool("meshcvt", dir.path("nan.ply") + " -n 4 -o " + dir.path("o.obj")), "meshcvt",
                   dir.path("nan.ply"), dir, 3);
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("nan.ply") + " --sites 2 -o " + dir.path("o.ply")),
                   "heatvoronoi", dir.path("nan.ply"), dir, 3);
  expect_bad_input(test::run_tool("nncoords", dir.path("nan.ply") + " --sites " + dir.path("s.txt") + " --weights " +
                                                  dir.path("w.txt")),
                   "nncoords", dir.path("nan.ply"), dir, 3);
}

TEST(Hardening, ZeroAreaMeshIsAnErrorForNaturalNeighbours) {
  test::ScratchDir dir("hard");
  // Collinear vertices: every face has zero area.
  const std::string needle = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\nf 1 3 4\n";
  test::write_text_file(dir.path("needle.obj"), needle);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n3 0 0\n");
  const TriangleMesh m = read_mesh(dir.path("needle.obj"));
  std::vector<SurfacePoint> sites = {{0, {1, 0, 0}}, {1, {0, 0, 1}}};
  EXPECT_THROW(NaturalNeighbourCoordinates(m.V, m.F, sites), InvalidInputError);
  for (const char* extra : {"", " --exact"})
    expect_bad_input(test::run_tool("nncoords", dir.path("needle.obj") + " --sites " + dir.path("s.txt") +
                                                    " --weights " + dir.path("w.txt") + extra),
                     "nncoords", dir.path("needle.obj"), dir, 2);
  // The mesh tools say so before any heat step.
  test::write_text_file(dir.path("point.obj"), "v 1 1 1\nv 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\nf 1 3 4\n");
  for (const char* mesh : {"needle.obj", "point.obj"}) {
    const auto r = test::run_tool("meshcvt", dir.path(mesh) + " -n 4 -o " + dir.path("o.obj"));
    expect_bad_input(r, "meshcvt", dir.path(mesh), dir, 3);
    EXPECT_NE(r.err.find("zero area"), std::string::npos) << r.err;
    expect_bad_input(test::run_tool("heatvoronoi", dir.path(mesh) + " --sites 2 -o " + dir.path("o.ply")), "heatvoronoi",
                     dir.path(mesh), dir, 3);
  }
}

// --- 2. command-line misuse ---------------------------------------------------------------------

TEST(Hardening, CommandLineMisuseIsOneLineAndExit2) {
  test::ScratchDir dir("hard");
  test::write_text_file(dir.path("t.obj"), kTetra);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n1 0 0\n");
  const std::string mesh = dir.path("t.obj");
  expect_bad_input(test::run_tool("heatvoronoi", mesh + " -o " + dir.path("o.ply") + " --sites 2 --sites-file " +
                                                     dir.path("s.txt")),
                   "heatvoronoi", "--sites", dir, 2);
  expect_bad_input(test::run_tool("nncoords", mesh + " --weights " + dir.path("w.txt")), "nncoords", "--sites", dir, 2);
  expect_bad_input(test::run_tool("nncoords", mesh + " --sites " + dir.path("s.txt")), "nncoords", "one of", dir, 2);
  for (const char* tool : {"meshcvt", "cloud2mesh", "heatvoronoi", "nncoords"}) {
    expect_bad_input(test::run_tool(tool, mesh + " -o " + dir.path("o.ply") + " --no-such-option"), tool, "", dir, 2);
    expect_bad_input(test::run_tool(tool, mesh + " -o " + dir.path("o.ply") + " --threads abc"), tool, "", dir, 2);
  }
  // cloud2mesh without an input; normals asked for an output format that cannot carry them.
  expect_bad_input(test::run_tool("cloud2mesh", "-n 10 -o " + dir.path("o.ply")), "cloud2mesh", "no input", dir, 2);
  expect_bad_input(test::run_tool("cloud2mesh", mesh + " -n 10 --stray-ratio 0.5 -o " + dir.path("o.ply")), "cloud2mesh",
                   "--stray-ratio", dir, 2);
  expect_bad_input(test::run_tool("cloud2mesh", mesh + " -n 10 --normals -o " + dir.path("o.off")), "cloud2mesh",
                   dir.path("o.off") + ": --normals", dir, 2);
  // --help still succeeds and documents the exit statuses.
  for (const char* tool : {"meshcvt", "cloud2mesh", "heatvoronoi", "nncoords"}) {
    const auto r = test::run_tool(tool, "--help");
    EXPECT_EQ(r.exit_code, 0) << tool;
    EXPECT_NE(r.out.find("Exit status"), std::string::npos) << tool;
    EXPECT_NE(r.out.find("3 = outputs written"), std::string::npos) << tool;
  }
}

// --- 3. control bytes ----------------------------------------------------------------------------

TEST(Hardening, CloudReaderErrorsCarryNoControlBytes) {
  test::ScratchDir dir("hard");
  const std::vector<std::pair<std::string, std::string>> files = {
      {"esc.xyz", "0 0 0\n1 \x1b[31mred\x07 2\n"},
      {"cr.xyz", "0 0 0\n1 2 3\x1b\r\n"},
      {"esc.pcd", "# .PCD\nVERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                  "POINTS 1\nDATA \x1b]0;title\x07\n0 0 0\n"},
      {"ff.pcd", "# .PCD\nVERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                 "POINTS 1\nDATA ascii\n0 \x0c 0\n"},
      {"bell.pcd", "\x07\x1b[2J\n"},
      {"esc.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                  "end_header\n0 \x1b[1m 0\n"}};
  for (const auto& [name, content] : files) {
    test::write_text_file(dir.path(name), content);
    try {
      read_cloud(dir.path(name));
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_FALSE(has_control_bytes(e.what())) << name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).rfind(dir.path(name) + ": ", 0), 0u) << e.what();
    }
  }
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("esc.xyz") + " -o " + dir.path("o.ply")), "cloud2mesh",
                   dir.path("esc.xyz"), dir, static_cast<int>(files.size()));
}

// --- 4. ASCII PCD ---------------------------------------------------------------------------------

TEST(Hardening, AsciiPcdIsReadStrictly) {
  test::ScratchDir dir("hard");
  auto pcd = [](const std::string& fields, int points, const std::string& body) {
    std::string sizes, types, counts;
    std::istringstream f(fields);
    for (std::string w; f >> w;) sizes += " 4", types += " F", counts += " 1";
    return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + fields + "\nSIZE" + sizes + "\nTYPE" + types + "\nCOUNT" + counts +
           "\nWIDTH " + std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
           std::to_string(points) + "\nDATA ascii\n" + body;
  };
  // The well-formed file is read (the reference the broken ones differ from).
  test::write_text_file(dir.path("good.pcd"), pcd("x y z", 3, "0 0 0\n1 0 0\n0 1 nan\n"));
  EXPECT_EQ(read_cloud(dir.path("good.pcd")).P.rows(), 2);
  const std::vector<std::tuple<std::string, std::string, std::string>> bad = {
      {"token.pcd", pcd("x y z", 3, "0 0 0\n1.0 abc 3.0\n0 1 0\n"), "'abc'"},
      {"short.pcd", pcd("x y z", 3, "0.000000 0.000000 0.000000\n1.000000 2.000000\n0.000000 1.000000 0.000000\n"),
       "2 values"},
      {"twice.pcd", pcd("x y x z", 2, "0 0 5 0\n1 0 6 0\n"), "listed twice"},
      {"comma.pcd", pcd("x y z", 3, "0,5 0,5 0,5\n1,5 0,5 0,5\n0,5 1,5 0,5\n"), "decimal commas"},
      {"few.pcd", pcd("x y z", 4, "0 0 0\n1 0 0\n0 1 0\n"), "truncated"}};
  for (const auto& [name, content, needle] : bad) {
    test::write_text_file(dir.path(name), content);
    try {
      read_cloud(dir.path(name));
      ADD_FAILURE() << name << " was accepted";
    } catch (const IOError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << name << ": " << e.what();
    }
  }
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("comma.pcd") + " -o " + dir.path("o.ply")), "cloud2mesh",
                   dir.path("comma.pcd") + ": line", dir, static_cast<int>(bad.size()) + 1);
}

// --- 5. silent nonsense ---------------------------------------------------------------------------

TEST(Hardening, ComponentWithoutSitesAndDuplicateSitesAreErrors) {
  test::ScratchDir dir("hard");
  // Two tetrahedra far apart; both sites on the first.
  std::string two = kTetra;
  two += "v 10 0 0\nv 11 0 0\nv 10 1 0\nv 10 0 1\nf 5 7 6\nf 5 6 8\nf 6 7 8\nf 5 8 7\n";
  test::write_text_file(dir.path("two.obj"), two);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n1 0 0\n");
  expect_bad_input(test::run_tool("nncoords", dir.path("two.obj") + " --sites " + dir.path("s.txt") + " --weights " +
                                                  dir.path("w.txt") + " -q"),
                   "nncoords", dir.path("s.txt") + ": connected component", dir, 2);
  test::write_text_file(dir.path("dup.txt"), "0 0 0\n1 0 0\n0 0 0\n");
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("two.obj") + " --sites-file " + dir.path("dup.txt") + " -o " +
                                                     dir.path("o.ply") + " -q"),
                   "heatvoronoi", dir.path("dup.txt") + ": sites 1 and 3 are duplicates", dir, 3);
}

// --- 6. scale invariance --------------------------------------------------------------------------

TEST(Hardening, NormalizationFrameHandlesExtremeCoordinates) {
  Eigen::MatrixX3d P(2, 3);
  P << -8e307, 0, 0, 8e307, 1, 1;
  const NormalizationFrame f = bounding_box_frame(P);
  EXPECT_TRUE(std::isfinite(f.scale));
  Eigen::MatrixX3d Q = P;
  apply_frame(Q, f);
  EXPECT_TRUE(Q.allFinite());
  EXPECT_NEAR((Q.row(1) - Q.row(0)).norm(), 1.0, 1e-12);
  Eigen::MatrixX3d one(1, 3);
  one << 1e12, -1e12, 5;
  EXPECT_EQ(normalize_positions(one).scale, 1.0);
  EXPECT_EQ(one.norm(), 0.0);
  P << -1e308, 0, 0, 1e308, 0, 0;  // the diagonal 2e308 is beyond the double range
  EXPECT_THROW(bounding_box_frame(P), InvalidInputError);
}

TEST(Hardening, MeshcvtIsScaleInvariant) {
  test::ScratchDir dir("hard");
  const TriangleMesh sphere = test::icosphere(3);  // the 642-vertex icosphere of the report
  ASSERT_EQ(sphere.V.rows(), 642);
  const TriangleMesh bumpy = bumpy_sphere();
  std::vector<Eigen::MatrixX3d> duals;
  for (const auto& [scale, shift] : std::vector<std::pair<double, double>>{{1, 0}, {1e-9, 0}, {1e12, 0}, {1, 1e6}}) {
    // The plain icosphere: every check of the dual passes at every scale.
    write_obj(dir.path("ico.obj"), (sphere.V * scale).array() + shift, sphere.F);
    const auto r = test::run_tool("meshcvt", dir.path("ico.obj") + " -n 200 -q -o " + dir.path("ico_out.obj"));
    EXPECT_EQ(r.exit_code, 0) << "scale " << scale << " shift " << shift << ": " << r.err;
    // The jittered sphere (no symmetric ties): the same dual up to the similarity.
    write_obj(dir.path("b.obj"), (bumpy.V * scale).array() + shift, bumpy.F);
    const auto rb = test::run_tool("meshcvt", dir.path("b.obj") + " -n 150 -q -o " + dir.path("b_out.obj"));
    ASSERT_EQ(rb.exit_code, 0) << rb.err;
    const TriangleMesh out = read_mesh(dir.path("b_out.obj"));
    duals.push_back((out.V.array() - shift) / scale);
  }
  for (size_t i = 1; i < duals.size(); ++i) {
    ASSERT_EQ(duals[i].rows(), duals[0].rows());
    EXPECT_LT((duals[i] - duals[0]).cwiseAbs().maxCoeff(), 1e-6) << "run " << i;
  }
}

TEST(Hardening, HeatvoronoiNncoordsAndCloud2meshAreScaleInvariant) {
  test::ScratchDir dir("hard");
  const TriangleMesh m = bumpy_sphere();
  const std::vector<int> site_vertices = {0, 40, 200, 333, 500, 600};
  std::vector<std::string> weights;
  std::vector<long> cell_faces;
  std::vector<Eigen::MatrixX3d> recon;
  std::vector<Eigen::MatrixX3i> recon_faces;
  for (const auto& [scale, shift] : std::vector<std::pair<double, double>>{{1, 0}, {1e-9, 0}, {1e12, 0}, {1, 1e6}}) {
    const Eigen::MatrixX3d V = (m.V * scale).array() + shift;
    write_obj(dir.path("m.obj"), V, m.F);
    std::ostringstream s;
    s.precision(17);
    for (int v : site_vertices) s << V(v, 0) << ' ' << V(v, 1) << ' ' << V(v, 2) << '\n';
    test::write_text_file(dir.path("s.txt"), s.str());
    const auto hv = test::run_tool("heatvoronoi", dir.path("m.obj") + " --sites-file " + dir.path("s.txt") + " -q -o " +
                                                      dir.path("cells.ply"));
    ASSERT_EQ(hv.exit_code, 0) << hv.err;
    cell_faces.push_back(static_cast<long>(read_mesh(dir.path("cells.ply")).F.rows()));
    const auto nn = test::run_tool("nncoords", dir.path("m.obj") + " --sites " + dir.path("s.txt") + " -q --weights " +
                                                   dir.path("w.txt"));
    ASSERT_EQ(nn.exit_code, 0) << nn.err;
    weights.push_back(slurp(dir.path("w.txt")));
    // A cloud of the same surface, reconstructed.
    const Eigen::MatrixX3d P = (sample_surface(m.V, m.F, 3000, 3).array() * scale) + shift;
    std::ostringstream c;
    c.precision(17);
    for (Eigen::Index i = 0; i < P.rows(); ++i) c << P(i, 0) << ' ' << P(i, 1) << ' ' << P(i, 2) << '\n';
    test::write_text_file(dir.path("c.xyz"), c.str());
    const auto cm = test::run_tool("cloud2mesh", dir.path("c.xyz") + " -n 150 -q -o " + dir.path("r.ply"));
    ASSERT_EQ(cm.exit_code, 0) << cm.err;
    const TriangleMesh r = read_mesh(dir.path("r.ply"));
    recon.push_back((r.V.array() - shift) / scale);
    recon_faces.push_back(r.F);
  }
  for (size_t i = 1; i < weights.size(); ++i) {
    EXPECT_EQ(cell_faces[i], cell_faces[0]) << "run " << i;
    // Weights agree to rounding (the text of the figures may differ in the last digits).
    std::vector<double> a, b;
    for (auto [text, out] : {std::pair{&weights[0], &a}, std::pair{&weights[i], &b}})
      for (const auto& line : lines_of(*text)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ls(line);
        for (double x; ls >> x;) out->push_back(x);
      }
    ASSERT_EQ(a.size(), b.size()) << "run " << i;
    int compared = 0;
    for (size_t k = 0; k < a.size(); ++k, ++compared) EXPECT_NEAR(a[k], b[k], 1e-7) << "run " << i << " value " << k;
    EXPECT_GT(compared, 642);
    // The reconstruction amplifies last-bit differences of the normalised points (a unit cloud
    // shifted by 1e-3 gives another mesh of the same quality), so it is compared as a surface: the
    // same vertex count, every check passed (exit 0 above), and both meshes within twice the
    // sagitta h²/8 of a 150-vertex unit sphere (h ≈ 0.33) of each other.
    ASSERT_EQ(recon[i].rows(), recon[0].rows()) << "run " << i;
    const SurfaceDistance d = surface_distance(recon[i], recon_faces[i], recon[0], recon_faces[0], 5000);
    EXPECT_LT(d.mean, 2 * 0.33 * 0.33 / 8) << "run " << i;
  }
}

// --- 7. outputs -----------------------------------------------------------------------------------

TEST(Hardening, TwoOutputsOnOnePathAreRejected) {
  test::ScratchDir dir("hard");
  write_obj(dir.path("m.obj"), bumpy_sphere().V, bumpy_sphere().F);
  expect_bad_input(test::run_tool("meshcvt", dir.path("m.obj") + " -n 50 -o " + dir.path("s.ply") + " --cells " +
                                                 dir.path("s.ply")),
                   "meshcvt", dir.path("s.ply"), dir, 1);
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("m.obj") + " --sites 5 -o " + dir.path("s.obj") + " --edges " +
                                                     dir.path("s.obj")),
                   "heatvoronoi", dir.path("s.obj"), dir, 1);
  // Also through a symbolic link to the other output.
  fs::create_symlink(dir.path("s.ply"), dir.path("alias.ply"));
  expect_bad_input(test::run_tool("meshcvt", dir.path("m.obj") + " -n 50 -o " + dir.path("s.ply") + " --cells " +
                                                 dir.path("alias.ply")),
                   "meshcvt", dir.path("alias.ply"), dir, 2);
}

TEST(Hardening, AnOutputOnAnInputIsRejectedAndTheInputKept) {
  test::ScratchDir dir("hard");
  const TriangleMesh m = bumpy_sphere();
  write_obj(dir.path("m.obj"), m.V, m.F);
  write_mesh(dir.path("c.ply"), m.V, m.F);  // read by cloud2mesh as a cloud of its vertices
  const std::string mesh_before = slurp(dir.path("m.obj")), cloud_before = slurp(dir.path("c.ply"));
  expect_bad_input(test::run_tool("meshcvt", dir.path("m.obj") + " -n 50 -o " + dir.path("m.obj")), "meshcvt",
                   dir.path("m.obj"), dir, 2);
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("c.ply") + " -n 50 -o " + dir.path("c.ply")), "cloud2mesh",
                   dir.path("c.ply"), dir, 2);
  // Also through a symbolic link to the input.
  fs::create_symlink(dir.path("m.obj"), dir.path("alias.obj"));
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("alias.obj") + " --sites 5 -o " + dir.path("m.obj")),
                   "heatvoronoi", dir.path("m.obj"), dir, 3);
  EXPECT_EQ(slurp(dir.path("m.obj")), mesh_before);
  EXPECT_EQ(slurp(dir.path("c.ply")), cloud_before);
  // Site files read as inputs are inputs too: --weights and --centroids may not overwrite them.
  std::ostringstream sites;
  sites.precision(17);
  for (int v : {0, 7, 19, 33}) sites << m.V(v, 0) << ' ' << m.V(v, 1) << ' ' << m.V(v, 2) << '\n';
  test::write_text_file(dir.path("s.txt"), sites.str());
  const std::string sites_before = slurp(dir.path("s.txt"));
  expect_bad_input(test::run_tool("nncoords", dir.path("m.obj") + " --sites " + dir.path("s.txt") + " --weights " +
                                                  dir.path("s.txt")),
                   "nncoords", dir.path("s.txt"), dir, 4);
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("m.obj") + " --sites-file " + dir.path("s.txt") + " -o " +
                                                     dir.path("v.ply") + " --centroids " + dir.path("s.txt")),
                   "heatvoronoi", dir.path("s.txt"), dir, 4);
  EXPECT_EQ(slurp(dir.path("s.txt")), sites_before);
}

TEST(Hardening, AFailingLaterOutputLeavesNoEarlierOne) {
  test::ScratchDir dir("hard");
  write_obj(dir.path("m.obj"), bumpy_sphere().V, bumpy_sphere().F);
  // Without a limit both outputs are written.
  const auto r = test::run_tool("meshcvt", dir.path("m.obj") + " -n 40 -q -o " + dir.path("dual.obj") + " --cells " +
                                               dir.path("cells.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_LT(fs::file_size(dir.path("dual.obj")), 8192u);
  ASSERT_GT(fs::file_size(dir.path("cells.ply")), 16384u);
  fs::remove(dir.path("dual.obj"));
  fs::remove(dir.path("cells.ply"));
  // A file-size limit of 8-16 KiB (512- or 1024-byte blocks, as the shell counts them): the dual
  // fits, the tessellated input (--cells) does not. SIGXFSZ must not kill the tool: the write
  // fails with one error line and neither output (nor a temporary) is left behind.
  const std::string cmd = "(ulimit -f 16; exec " + std::string(HEATCVT_BIN_DIR) + "/meshcvt " + dir.path("m.obj") +
                          " -n 40 -q -o " + dir.path("dual.obj") + " --cells " + dir.path("cells.ply") + ") 2> " +
                          dir.path("err.txt");
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal";
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string err = slurp(dir.path("err.txt"));
  fs::remove(dir.path("err.txt"));
  EXPECT_EQ(lines_of(err).size(), 1u) << err;
  EXPECT_EQ(err.rfind("meshcvt: error: " + dir.path("cells.ply") + ":", 0), 0u) << err;
  EXPECT_EQ(dir.entries(), 1) << "an output or a temporary file was left behind";
}

// An output path that is a FIFO, directly or through a symbolic link: the write is refused
// with an IOError naming the path, and the FIFO stays a FIFO (the temporary file is not renamed
// over it). The same path as a regular file is written.
TEST(Hardening, AnOutputThatIsNotARegularFileIsRefusedAndKept) {
  test::ScratchDir dir("hard");
  const std::string fifo = dir.path("fifo"), link = dir.path("link.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_symlink(fifo, link);
  for (const std::string& path : {fifo, link}) {
    SCOPED_TRACE(path);
    try {
      write_atomically(path, [](std::ostream& o) { o << "data"; });
      ADD_FAILURE() << "the write must be refused";
    } catch (const IOError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": cannot write, it is not a regular file", 0), 0u) << e.what();
    }
    EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  }
  EXPECT_EQ(dir.entries(), 2) << "a temporary file was left behind";
  write_atomically(dir.path("plain.txt"), [](std::ostream& o) { o << "data"; });
  EXPECT_EQ(slurp(dir.path("plain.txt")), "data");
}

// An input that is a FIFO (opening one with no writer blocks for ever), directly or through a
// symbolic link, or a device: every reader refuses it at once with an IOError naming the path.
TEST(Hardening, AnInputThatIsNotARegularFileIsRefusedWithoutOpeningIt) {
  test::ScratchDir dir("hard");
  const std::string fifo_cloud = dir.path("fifo.xyz"), fifo_mesh = dir.path("fifo.obj"), link = dir.path("link.pcd");
  ASSERT_EQ(::mkfifo(fifo_cloud.c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo(fifo_mesh.c_str(), 0600), 0);
  fs::create_symlink(fifo_cloud, link);
  const auto expect_refused = [](const std::string& path, const std::function<void()>& read) {
    SCOPED_TRACE(path);
    try {
      read();
      ADD_FAILURE() << "the read must be refused";
    } catch (const IOError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": is not a regular file", 0), 0u) << e.what();
    }
  };
  expect_refused(fifo_cloud, [&] { read_cloud(fifo_cloud); });
  expect_refused(link, [&] { read_cloud(link); });
  expect_refused(fifo_cloud, [&] { CloudChunkReader reader(fifo_cloud); });
  expect_refused(fifo_mesh, [&] { read_mesh(fifo_mesh); });
  ASSERT_TRUE(fs::is_character_file("/dev/zero"));
  expect_refused("/dev/zero", [&] { read_mesh("/dev/zero"); });
}

TEST(Hardening, TransactionCommitsAllOrNothing) {
  test::ScratchDir dir("hard");
  test::write_text_file(dir.path("a.txt"), "old a");
  {
    OutputTransaction t;
    write_atomically(dir.path("a.txt"), [](std::ostream& o) { o << "new a"; });
    write_atomically(dir.path("b.txt"), [](std::ostream& o) { o << "new b"; });
    EXPECT_EQ(slurp(dir.path("a.txt")), "old a");  // nothing renamed before commit
    EXPECT_FALSE(fs::exists(dir.path("b.txt")));
  }  // destroyed without commit: temporaries removed, old content kept
  EXPECT_EQ(slurp(dir.path("a.txt")), "old a");
  EXPECT_EQ(dir.entries(), 1);
  {
    OutputTransaction t;
    write_atomically(dir.path("a.txt"), [](std::ostream& o) { o << "new a"; });
    EXPECT_THROW(write_atomically(dir.path("b.txt"), [](std::ostream&) { throw IOError("writer failed"); }), IOError);
  }
  EXPECT_EQ(slurp(dir.path("a.txt")), "old a");
  EXPECT_EQ(dir.entries(), 1);
  {
    OutputTransaction t;
    write_atomically(dir.path("a.txt"), [](std::ostream& o) { o << "new a"; });
    write_atomically(dir.path("b.txt"), [](std::ostream& o) { o << "new b"; });
    t.commit();
  }
  EXPECT_EQ(slurp(dir.path("a.txt")), "new a");
  EXPECT_EQ(slurp(dir.path("b.txt")), "new b");
  EXPECT_EQ(dir.entries(), 2);
}

TEST(Hardening, SymlinkedOutputIsWrittenThrough) {
  test::ScratchDir dir("hard");
  fs::create_directory(dir.path("real"));
  fs::create_symlink("real/target.obj", dir.path("link.obj"));  // relative, dangling until written
  write_obj(dir.path("m.obj"), bumpy_sphere().V, bumpy_sphere().F);
  const auto r = test::run_tool("meshcvt", dir.path("m.obj") + " -n 40 -q -o " + dir.path("link.obj"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path("link.obj")));
  EXPECT_EQ(read_mesh(dir.path("real/target.obj")).V.rows(), 40);
  EXPECT_EQ(dir.entries(), 3);
}

TEST(Hardening, TemporaryFilesAreRemovedOnSignals) {
  for (int sig : {SIGINT, SIGTERM}) {
    test::ScratchDir dir("hard");
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      remove_temporary_files_on_signals();
      OutputTransaction t;
      write_atomically(dir.path("a.txt"), [](std::ostream& o) { o << "a"; });
      write_atomically(dir.path("b.txt"), [&](std::ostream& o) {
        o << "partial";
        o.flush();
        ::raise(sig);  // killed while the second output is being written
      });
      ::_exit(0);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(dir.entries(), 0) << "temporary files left after signal " << sig;
  }
}

// --- 8. error lines -------------------------------------------------------------------------------

TEST(Hardening, ErrorLinesNameTheFileOrOptionNotAFunction) {
  test::ScratchDir dir("hard");
  // 10 points: too few for the reconstruction.
  std::string few;
  for (int i = 0; i < 10; ++i) few += std::to_string(i) + " " + std::to_string(i * i % 7) + " " + std::to_string(i % 3) + "\n";
  test::write_text_file(dir.path("few.xyz"), few);
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("few.xyz") + " -n 4 -o " + dir.path("o.ply")), "cloud2mesh",
                   dir.path("few.xyz") + ": ", dir, 1);
  // A tiny voxel names the option.
  std::ostringstream cloud;
  const Eigen::MatrixX3d P = sample_surface(test::icosphere(2).V, test::icosphere(2).F, 500, 1);
  for (Eigen::Index i = 0; i < P.rows(); ++i) cloud << P(i, 0) << ' ' << P(i, 1) << ' ' << P(i, 2) << '\n';
  test::write_text_file(dir.path("c.xyz"), cloud.str());
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("c.xyz") + " -n 50 --voxel 1e-30 -o " + dir.path("o.ply")),
                   "cloud2mesh", "--voxel", dir, 2);
  // ±1e300 outliers: named as such, not "collinear or coincident".
  test::write_text_file(dir.path("far.xyz"), cloud.str() + "1e300 0 0\n-1e300 0 0\n");
  expect_bad_input(test::run_tool("cloud2mesh", dir.path("far.xyz") + " -n 50 -o " + dir.path("o.ply")), "cloud2mesh",
                   dir.path("far.xyz") + ": a few points lie far outside", dir, 3);
  // Directories as the input or the sites file.
  fs::create_directory(dir.path("d.obj"));
  fs::create_directory(dir.path("sites"));
  write_obj(dir.path("m.obj"), test::icosphere(1).V, test::icosphere(1).F);
  expect_bad_input(test::run_tool("meshcvt", dir.path("d.obj") + " -o " + dir.path("o.obj")), "meshcvt",
                   dir.path("d.obj") + ": is a directory", dir, 6);
  expect_bad_input(test::run_tool("heatvoronoi", dir.path("m.obj") + " --sites-file " + dir.path("sites") + " -o " +
                                                     dir.path("o.ply")),
                   "heatvoronoi", dir.path("sites") + ": is a directory", dir, 6);
  EXPECT_EQ(without_function_prefix("reconstruct_surface: only 10 usable points"), "only 10 usable points");
  EXPECT_EQ(without_function_prefix("HeatSolver: not positive definite"), "not positive definite");
  EXPECT_EQ(without_function_prefix("mesh.obj: truncated"), "mesh.obj: truncated");
}

// --- 9. exit status of an invalid result, reports, options -----------------------------------------

TEST(Hardening, FailedChecksExitWith3AndTheOutputIsWritten) {
  test::ScratchDir dir("hard");
  // Two sheets through each other: the remesh crosses itself where the input does (a failed
  // check; a result without any triangle is an error instead, MeshcvtTool.NoTriangleIsAnErrorWithNoOutput).
  const TriangleMesh sheets = interpenetrating_sheets_mesh(24);
  write_obj(dir.path("m.obj"), sheets.V, sheets.F);
  const auto r = test::run_tool("meshcvt", dir.path("m.obj") + " -n 300 -q -o " + dir.path("o.obj") + " --report " +
                                               dir.path("r.json"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_TRUE(fs::exists(dir.path("o.obj")));
  const auto j = nlohmann::json::parse(slurp(dir.path("r.json")));
  EXPECT_EQ(j["all_checks_passed"], false);
  EXPECT_EQ(j["exit_status"], 3);
  // heatvoronoi: a component without a generator.
  std::string two = kTetra;
  two += "v 10 0 0\nv 11 0 0\nv 10 1 0\nv 10 0 1\nf 5 7 6\nf 5 6 8\nf 6 7 8\nf 5 8 7\n";
  test::write_text_file(dir.path("two.obj"), two);
  test::write_text_file(dir.path("s.txt"), "0 0 0\n1 0 0\n");
  const auto h = test::run_tool("heatvoronoi", dir.path("two.obj") + " --sites-file " + dir.path("s.txt") + " -q -o " +
                                                   dir.path("c.ply"));
  EXPECT_EQ(h.exit_code, 3) << h.err;
  EXPECT_TRUE(fs::exists(dir.path("c.ply")));
}

TEST(Hardening, EveryToolWritesTheSameReportSchema) {
  test::ScratchDir dir("hard");
  const TriangleMesh m = bumpy_sphere();
  write_obj(dir.path("m.obj"), m.V, m.F);
  test::write_text_file(dir.path("s.txt"), "1 0 0\n-1 0 0\n0 1 0\n");
  std::ostringstream cloud;
  cloud.precision(17);
  const Eigen::MatrixX3d P = sample_surface(m.V, m.F, 3000, 1);
  for (Eigen::Index i = 0; i < P.rows(); ++i) cloud << P(i, 0) << ' ' << P(i, 1) << ' ' << P(i, 2) << '\n';
  test::write_text_file(dir.path("c.xyz"), cloud.str());
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"meshcvt", dir.path("m.obj") + " -n 100 -o " + dir.path("a.obj")},
      {"cloud2mesh", dir.path("c.xyz") + " -n 100 -o " + dir.path("b.ply")},
      {"heatvoronoi", dir.path("m.obj") + " --sites 10 -o " + dir.path("c.ply")},
      {"nncoords", dir.path("m.obj") + " --sites " + dir.path("s.txt") + " --snap-tolerance 0.1 --weights " +
                       dir.path("w.txt")}};
  for (const auto& [tool, args] : runs) {
    const std::string report = dir.path(tool + ".json");
    const auto r = test::run_tool(tool, args + " -q --report " + report);
    ASSERT_EQ(r.exit_code, 0) << tool << ": " << r.err;
    const auto j = nlohmann::json::parse(slurp(report));
    EXPECT_EQ(j["tool"], tool);
    ASSERT_TRUE(j["outputs"].is_array()) << tool;
    ASSERT_TRUE(j["checks"].is_array()) << tool;
    EXPECT_FALSE(j["checks"].empty()) << tool;
    for (const auto& c : j["checks"]) {
      EXPECT_TRUE(c.contains("name") && c.contains("passed") && c.contains("detail")) << tool << ": " << c.dump();
      EXPECT_EQ(c.size(), 3u) << tool;
    }
    ASSERT_TRUE(j["stages"].is_array()) << tool;
    EXPECT_FALSE(j["stages"].empty()) << tool;
    for (const auto& s : j["stages"]) EXPECT_TRUE(s["name"].is_string() && s["seconds"].is_number()) << tool;
    EXPECT_EQ(j["all_checks_passed"], true) << tool;
    EXPECT_EQ(j["exit_status"], 0) << tool;
    if (tool == "meshcvt" || tool == "cloud2mesh") {
      EXPECT_TRUE(j["phi_min_deg"].is_number()) << tool;
      EXPECT_TRUE(j["phi_mean_deg"].is_number()) << tool;
      EXPECT_FALSE(j.contains("min_angle_deg")) << tool;
    }
  }
}

TEST(Hardening, Cloud2meshHelpShowsEveryReconstructionOption) {
  const auto r = test::run_tool("cloud2mesh", "--help");
  ASSERT_EQ(r.exit_code, 0);
  const ReconstructionOptions d;
  // One option per field of ReconstructionOptions, with its default.
  for (const std::string& needle : std::vector<std::string>
       {std::string("-n,--sites INT=") + std::to_string(d.sites), "--iterations INT=" + std::to_string(d.iterations),
        std::string("--neighbours"), std::string("--anisotropy"), std::string("--adaptive"), std::string("--size-ratio"),
        std::string("--denoise"), "--denoise-k INT=" + std::to_string(d.denoise_neighbors),
        std::string("--denoise-stddev"), std::string("--voxel"), std::string("--t-coef"), std::string("--seed"),
        std::string("--threads"), "--max-hole-edges INT=" + std::to_string(d.max_hole_edges),
        "--polish-iterations INT=" + std::to_string(d.relaxation_iterations), std::string("--fast-start"),
        std::string("--relaxation"), std::string("--tolerance"), std::string("--mean-tolerance"),
        "--surface-lloyd INT=" + std::to_string(d.surface_lloyd_iterations), std::string("--points-per-site"),
        std::string("--no-smooth-cvt-points")})
    EXPECT_NE(r.out.find(needle), std::string::npos) << needle;
}

TEST(Hardening, OneNeighbourRangeInTheLibraryAndTheTool) {
  const Eigen::MatrixX3d P = sample_surface(test::icosphere(2).V, test::icosphere(2).F, 400, 1);
  for (int k : {ReconstructionOptions::min_neighbors - 1, ReconstructionOptions::max_neighbors + 1}) {
    ReconstructionOptions o;
    o.sites = 20;
    o.neighbors = k;
    EXPECT_THROW(reconstruct_surface(P, o), InvalidInputError) << k;
  }
  test::ScratchDir dir("hard");
  std::ostringstream c;
  for (Eigen::Index i = 0; i < P.rows(); ++i) c << P(i, 0) << ' ' << P(i, 1) << ' ' << P(i, 2) << '\n';
  test::write_text_file(dir.path("c.xyz"), c.str());
  for (int k : {ReconstructionOptions::min_neighbors - 1, ReconstructionOptions::max_neighbors + 1})
    expect_bad_input(test::run_tool("cloud2mesh", dir.path("c.xyz") + " -n 20 -k " + std::to_string(k) + " -o " +
                                                      dir.path("o.ply")),
                     "cloud2mesh", "-k", dir, 1);
  // The PCL adapter: the same range (an empty mesh, PCL's failure contract, outside it).
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    cloud->push_back(pcl::PointXYZ(static_cast<float>(P(i, 0)), static_cast<float>(P(i, 1)), static_cast<float>(P(i, 2))));
  for (int k : {ReconstructionOptions::min_neighbors - 1, ReconstructionOptions::max_neighbors + 1}) {
    HeatCVTReconstruction<pcl::PointXYZ> rec;
    rec.setInputCloud(cloud);
    rec.setNumberOfSites(20);
    rec.setKSearch(k);
    pcl::PolygonMesh mesh;
    rec.reconstruct(mesh);
    EXPECT_TRUE(mesh.polygons.empty()) << k;
  }
  const auto help = test::run_tool("cloud2mesh", "--help");
  EXPECT_NE(help.out.find("[" + std::to_string(ReconstructionOptions::min_neighbors) + ", " +
                          std::to_string(ReconstructionOptions::max_neighbors) + "]"),
            std::string::npos);
}

// A thread count far beyond any machine is reduced to kMaxThreads, not handed to OpenMP; 0 means
// every hardware thread, and a count within the bound is kept.
TEST(Hardening, AThreadCountBeyondTheBoundIsReducedToIt) {
  EXPECT_EQ(resolve_threads(1000000), kMaxThreads);
  EXPECT_EQ(resolve_threads(kMaxThreads), kMaxThreads);
  EXPECT_EQ(resolve_threads(3), 3);
  EXPECT_GE(resolve_threads(0), 1);
  EXPECT_LE(resolve_threads(0), kMaxThreads);
}
