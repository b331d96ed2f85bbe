// The cloud2mesh tool end to end: a real reconstruction with its report, determinism, every
// shared cloud at a small site count (valid mesh or one clear error line, never a crash or
// hang), and bad inputs (one error line, non-zero exit, no output left behind).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/validate.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Non-zero exit, exactly one "cloud2mesh: error:" line containing every needle, and the
// directory holds `expected_entries` entries (no output, no temporary).
void expect_clean_failure(const test::CommandResult& r, const std::vector<std::string>& needles,
                          const test::ScratchDir& dir, int expected_entries) {
  test::expect_tool_failure("cloud2mesh", r, needles, dir, expected_entries);
}

// Writes a sphere cloud ("x y z" lines) of n golden-spiral points.
void write_sphere_cloud(const std::string& path, int n) {
  std::ostringstream s;
  s.precision(17);
  const double ga = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    s << r * std::cos(ga * i) << " " << r * std::sin(ga * i) << " " << z << "\n";
  }
  test::write_text_file(path, s.str());
}

}  // namespace

TEST(Cloud2MeshTool, HelpListsDefaults) {
  auto r = test::run_tool("cloud2mesh", "--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* needle : {"-n", "3000", "--iterations", "INT=6", "--neighbours", "--anisotropy", "--denoise", "--seed",
                             "--relaxation", "--fast-start", "--surface-lloyd", "INT=40", "--points-per-site",
                             "FLOAT=10", "--tip-growth", "--threads", "--report", "--quiet"})
    EXPECT_NE(r.out.find(needle), std::string::npos) << needle;
}

TEST(Cloud2MeshTool, SphereCloudClosedGenus0WithReportAndSameSeedSameOutput) {
  test::ScratchDir dir("c2m");
  write_sphere_cloud(dir.path("s.xyz"), 6000);
  auto r = test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 400 -o " + dir.path("a.ply") + " --report " +
                                            dir.path("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The summary on stdout names every stage's figure and the CGAL checks.
  for (const char* needle : {"6000 read", "Laplacian", "factor", "heat iterations", "stages:", "400 vertices", "phi_min", "phi_m",
                             "PASS manifold_edges", "PASS no_self_intersections"})
    EXPECT_NE(r.out.find(needle), std::string::npos) << needle << " not in:\n" << r.out;
  TriangleMesh m = read_mesh(dir.path("a.ply"));
  ValidationOptions vo;
  vo.expected_genus = 0;
  vo.expected_components = 1;
  const ValidationReport rep = validate_triangle_mesh(m.V, m.F, vo);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(m.V.rows(), 400);
  EXPECT_EQ(m.F.rows(), 2 * 400 - 4);  // closed genus-0 triangulation
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) EXPECT_NEAR(m.V.row(i).norm(), 1.0, 5e-3);
  const std::string json = test::read_file(dir.path("r.json"));
  for (const char* key : {"\"points_in_file\": 6000", "\"vertices\": 400", "\"laplacian_s\"", "\"factor_s\"",
                          "\"per_iteration_s\"", "\"phi_min_deg\"", "\"phi_mean_deg\"", "\"name\": \"no_self_intersections\"",
                          "\"all_checks_passed\": true"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " not in:\n" << json;
  // Same seed: byte-identical output with 1, 2 and 4 threads; another seed differs.
  for (int threads : test::kThreadCounts) {
    SCOPED_TRACE(threads);
    auto r2 = test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 400 -o " + dir.path("b.ply") + " --threads " +
                                               std::to_string(threads) + " -q");
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    EXPECT_TRUE(r2.out.empty() && r2.err.empty()) << "--quiet must be silent";
    EXPECT_EQ(test::read_file(dir.path("a.ply")), test::read_file(dir.path("b.ply")));
  }
  auto r3 = test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 400 -o " + dir.path("c.ply") + " --seed 5 -q");
  ASSERT_EQ(r3.exit_code, 0) << r3.err;
  EXPECT_NE(test::read_file(dir.path("a.ply")), test::read_file(dir.path("c.ply")));
}

// Every shared cloud at -n 200 (5 iterations, k = 12, and clouds of more than 200,000 points
// streamed into a voxel summary, to keep the suite short), one rule for all: a mesh that passes
// every check (manifold edges and vertices, consistent orientation, every vertex used, no
// self-intersections), with no stray piece (every component has at least the mesher's smallest
// piece: 20 faces and 1 % of the vertices), and whose vertex count, φm and φmin are within the
// bounds below. The real-scans issue sets the targets (vertex count within 2 % of -n,
// φm >= 52°, φmin >= 25°). With the mesher's sizing stage 40 of the 42 clouds
// are within 2 % of -n; the other 2 are where the sizing would make the shape worse and is
// refused, so the bounds are the floor that every shared cloud meets today (the worst cloud of
// each figure, measured with these options: pcldata_room_scan1.pcd keeps 76 of the 200 sites,
// pcl_five_people.pcd a φm of 30.6° and a
// φmin of 0.7°), rounded down: a guard against regressions, not the targets. The vertex count
// may exceed -n by the 2 %. The bounds were measured on the raw-points front end, which
// the sweep pins (--stream-above 200000 --stream-per-site 0): at 200 sites every cloud of more
// than 8,000 points would otherwise be summarised into voxels.
constexpr int kSweepSites = 200;
constexpr int kSweepMaxVertices = kSweepSites + kSweepSites / 50;
constexpr int kSweepMinVertices = 70;
constexpr double kSweepMinPhiMean = 30.0;
constexpr double kSweepMinPhiMin = 0.5;

TEST(Cloud2MeshTool, EverySharedCloudSmallSiteCount) {
  test::ScratchDir dir("c2m");
  const std::string clouds = test::data_path("clouds");
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(clouds))
    if (e.is_regular_file() && e.path().extension() != ".md") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 20u);
  for (const auto& f : files) {
    SCOPED_TRACE(f);
    const std::string out = dir.path(std::filesystem::path(f).stem().string() + ".ply");
    const std::string report = dir.path(std::filesystem::path(f).stem().string() + ".json");
    auto r = test::run_tool("cloud2mesh", "'" + f + "' -n " + std::to_string(kSweepSites) +
                                              " -i 5 -k 12 --stream-above 200000 --stream-per-site 0 -o '" + out +
                                              "' --report '" + report + "' -q --threads 2");
    // Every check passes but, on a cloud the mesh covers in part at this coarse count (blobby.xyz
    // fills a volume), the coverage: that one alone fails, with exit status 3.
    const std::vector<std::string> failed = test::failed_checks(test::read_file(report));
    EXPECT_TRUE(failed.empty() || failed == std::vector<std::string>{"covers_cloud"}) << testing::PrintToString(failed);
    ASSERT_EQ(r.exit_code, failed.empty() ? 0 : 3) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    const TriangleMesh m = read_mesh(out);
    ValidationOptions vo;
    vo.require_closed = false;
    const ValidationReport rep = validate_triangle_mesh(m.V, m.F, vo);
    const TriangleQuality q = triangle_quality(m.V, m.F);
    std::printf("[ %s ] V %ld F %ld components %d boundary loops %d self-intersecting pairs %ld phi_min %.1f phi_m %.1f\n",
                std::filesystem::path(f).filename().c_str(), static_cast<long>(m.V.rows()),
                static_cast<long>(m.F.rows()), rep.components, rep.boundary_loops, rep.self_intersecting_pairs,
                q.min_angle_deg, q.mean_min_angle_deg);
    for (const char* check : {"manifold_edges", "manifold_vertices", "consistent_orientation", "all_vertices_used",
                              "no_self_intersections"}) {
      const MeshCheck* c = rep.find(check);
      ASSERT_NE(c, nullptr) << check;
      EXPECT_TRUE(c->ran && c->passed) << check << " " << c->detail;
    }
    EXPECT_GE(m.V.rows(), kSweepMinVertices);
    EXPECT_LE(m.V.rows(), kSweepMaxVertices);
    EXPECT_GE(rep.components, 1);
    Eigen::VectorXi piece;
    const int pieces = connected_components(static_cast<int>(m.V.rows()), m.F, piece);
    std::vector<int> piece_vertices(pieces, 0), piece_faces(pieces, 0);
    for (Eigen::Index v = 0; v < m.V.rows(); ++v) ++piece_vertices[piece[v]];
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) ++piece_faces[piece[m.F(f, 0)]];
    for (int c = 0; c < pieces; ++c) {
      EXPECT_GE(piece_faces[c], 20) << "piece " << c;
      EXPECT_GE(piece_vertices[c], 0.01 * m.V.rows()) << "piece " << c;
    }
    EXPECT_GE(q.mean_min_angle_deg, kSweepMinPhiMean);
    EXPECT_GE(q.min_angle_deg, kSweepMinPhiMin);
  }
}

// The README's own command on the README's own input (clouds/pcl_milk.pcd, an open scan of a
// milk carton: one boundary loop). Every real-scans target holds: every check passes, one
// component with one boundary loop, the vertex count within 2 % of -n, φm >= 52°, φmin >= 25°.
// A cluttered scan (a table top with objects) leaves stray pieces: by default every piece of the
// output has at least 1 % of its vertices and the report counts the pieces dropped; --keep-small
// keeps them all (and so has more components); either way the vertex count asked for is met.
// A sphere with a spike about 4 site spacings long at -n 1000 (Reconstruct.
// ASpikeLongerThanARingReachesIsGrownByInsertedVertices has the geometry): by default the tips'
// repair inserts vertices on it and the report counts them; --tip-growth 0 only moves vertices.
TEST(Cloud2MeshTool, TipGrowthInsertsVerticesOnALongSpikeAndZeroTurnsItOff) {
  test::ScratchDir dir("c2m");
  const TriangleMesh src = test::spiked_sphere(4, 1.45);
  const Eigen::MatrixX3d P = sample_surface(src.V, src.F, 40000, 5);
  std::ostringstream text;
  text.precision(17);
  for (Eigen::Index i = 0; i < P.rows(); ++i) text << P(i, 0) << " " << P(i, 1) << " " << P(i, 2) << "\n";
  test::write_text_file(dir.path("spike.xyz"), text.str());
  nlohmann::json report[2];
  for (int off = 0; off < 2; ++off) {
    const std::string rep = dir.path(off ? "off.json" : "on.json");
    auto r = test::run_tool("cloud2mesh", dir.path("spike.xyz") + " -n 1000 -o " + dir.path(off ? "off.ply" : "on.ply") +
                                              " --report " + rep + (off ? " --tip-growth 0" : "") + " -q");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    report[off] = nlohmann::json::parse(test::read_file(rep));
    EXPECT_NEAR(report[off]["vertices"].get<int>(), 1000, 20);
  }
  EXPECT_GT(report[0]["tip_vertices_inserted"].get<int>(), 0);
  EXPECT_EQ(report[1]["tip_vertices_inserted"].get<int>(), 0);
}

TEST(Cloud2MeshTool, StrayPiecesDroppedUnlessKeepSmall) {
  test::ScratchDir dir("c2m");
  const std::string cloud = test::data_path("clouds/pcldata_min_cut_segmentation_tutorial.pcd");
  nlohmann::json report[2];
  TriangleMesh mesh[2];
  for (int keep = 0; keep < 2; ++keep) {
    const std::string out = dir.path(keep ? "keep.ply" : "default.ply"), rep = dir.path(keep ? "keep.json" : "default.json");
    auto r = test::run_tool("cloud2mesh", "'" + cloud + "' -n 500 -o " + out + " --report " + rep + (keep ? " --keep-small" : "") + " -q");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    report[keep] = nlohmann::json::parse(test::read_file(rep));
    mesh[keep] = read_mesh(out);
  }
  ASSERT_GT(report[0]["pieces_removed"].get<int>(), 0) << "precondition: the scan has stray pieces";
  EXPECT_EQ(report[1]["pieces_removed"].get<int>(), 0);
  EXPECT_GT(report[1]["components"].get<int>(), report[0]["components"].get<int>());
  // Either way the vertex count asked for is shared among the pieces kept.
  for (const TriangleMesh& m : mesh) EXPECT_NEAR(m.V.rows(), 500, 10);
  // Every piece of the default output has at least 1 % of the vertices (vertex-connected pieces).
  const Eigen::MatrixX3i& F = mesh[0].F;
  std::vector<int> parent(mesh[0].V.rows());
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  std::function<int(int)> find = [&](int x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
  for (Eigen::Index f = 0; f < F.rows(); ++f) parent[find(F(f, 1))] = find(F(f, 0)), parent[find(F(f, 2))] = find(F(f, 0));
  std::map<int, int> size;
  for (size_t v = 0; v < parent.size(); ++v) ++size[find(static_cast<int>(v))];
  for (const auto& [root, n] : size) EXPECT_GE(n, 0.01 * mesh[0].V.rows()) << "piece of " << n << " vertices";
  EXPECT_GE(report[0]["phi_min_boundary_deg"].get<double>(), report[0]["phi_min_deg"].get<double>());
}

TEST(Cloud2MeshTool, ReadmeCommandOnPclMilk) {
  test::ScratchDir dir("c2m");
  const std::string cloud = std::string(HEATCVT_SOURCE_DIR) + "/clouds/pcl_milk.pcd";
  auto r = test::run_tool("cloud2mesh", cloud + " -n 3000 -o " + dir.path("milk.ply") + " --report " +
                                            dir.path("milk.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const TriangleMesh m = read_mesh(dir.path("milk.ply"));
  ValidationOptions vo;
  vo.require_closed = false;
  const ValidationReport rep = validate_triangle_mesh(m.V, m.F, vo);
  const TriangleQuality q = triangle_quality(m.V, m.F);
  std::printf("[ pcl_milk.pcd, -n 3000 ] V %ld F %ld components %d boundary loops %d phi_min %.1f phi_m %.2f\n",
              static_cast<long>(m.V.rows()), static_cast<long>(m.F.rows()), rep.components, rep.boundary_loops,
              q.min_angle_deg, q.mean_min_angle_deg);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_TRUE(rep.find("no_self_intersections") && rep.find("no_self_intersections")->ran);
  EXPECT_EQ(rep.components, 1);
  EXPECT_EQ(rep.boundary_loops, 1);
  EXPECT_EQ(rep.genus, 0);
  EXPECT_GE(m.V.rows(), 0.98 * 3000);
  EXPECT_LE(m.V.rows(), 3000);
  EXPECT_GE(q.mean_min_angle_deg, 52.0);
  EXPECT_GE(q.min_angle_deg, 25.0);
  // The report describes the written mesh.
  const std::string json = test::read_file(dir.path("milk.json"));
  EXPECT_EQ(test::json_number(json, "vertices"), m.V.rows());
  EXPECT_EQ(test::json_number(json, "faces"), m.F.rows());
  EXPECT_NE(json.find("\"all_checks_passed\": true"), std::string::npos);
  // The carton's open bottom: the border within one site spacing of the scan's edge (90 % of its
  // vertices, and 90 % of the edge's points within one spacing of the mesh), reported on both.
  EXPECT_LE(test::json_number(json, "border_p90_spacings"), 1.0);
  EXPECT_GE(test::json_number(json, "scan_edge_covered"), 0.9);
  EXPECT_GT(test::json_number(json, "border_vertices"), 0);
  EXPECT_NE(r.out.find("  border: "), std::string::npos) << r.out;
}

TEST(Cloud2MeshTool, MissingFile) {
  test::ScratchDir dir("c2m");
  const std::string missing = dir.path("nope.xyz");
  expect_clean_failure(test::run_tool("cloud2mesh", missing + " -o " + dir.path("o.ply")), {missing}, dir, 0);
}

TEST(Cloud2MeshTool, EmptyFile) {
  test::ScratchDir dir("c2m");
  test::write_text_file(dir.path("e.xyz"), "");
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("e.xyz") + " -o " + dir.path("o.ply")), {dir.path("e.xyz")},
                       dir, 1);
}

TEST(Cloud2MeshTool, AllNanCloud) {
  test::ScratchDir dir("c2m");
  test::write_text_file(dir.path("nan.xyz"), "nan 0 0\n0 nan 1\nnan nan nan\n");
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("nan.xyz") + " -o " + dir.path("o.ply")),
                       {dir.path("nan.xyz")}, dir, 1);
}

TEST(Cloud2MeshTool, MoreSitesThanPoints) {
  test::ScratchDir dir("c2m");
  write_sphere_cloud(dir.path("s.xyz"), 500);
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 600 -o " + dir.path("o.ply")),
                       {"600", "500"}, dir, 1);
}

// The summary notes a cloud with fewer than 3 usable points per requested site, and only then.
TEST(Cloud2MeshTool, SummaryNotesAnUndersampledCloud) {
  test::ScratchDir dir("c2m");
  write_sphere_cloud(dir.path("s.xyz"), 500);
  const auto sparse = test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 200 -o " + dir.path("a.ply"));
  EXPECT_NE(sparse.out.find("undersampled for -n 200"), std::string::npos) << sparse.out;
  const auto dense = test::run_tool("cloud2mesh", dir.path("s.xyz") + " -n 50 -o " + dir.path("b.ply"));
  ASSERT_EQ(dense.exit_code, 0) << dense.err;
  EXPECT_EQ(dense.out.find("undersampled"), std::string::npos) << dense.out;
}

TEST(Cloud2MeshTool, NonsenseOptions) {
  test::ScratchDir dir("c2m");
  write_sphere_cloud(dir.path("s.xyz"), 500);
  const std::string base = dir.path("s.xyz") + " -o " + dir.path("o.ply") + " ";
  expect_clean_failure(test::run_tool("cloud2mesh", base + "-n 2"), {"-n"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "-n abc"), {"abc"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "-i -3"), {"-i"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "-k 2"), {"-k"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--anisotropy -1"), {"--anisotropy"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--adaptive -1"), {"--adaptive"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--adaptive nan"), {"--adaptive"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--adaptive 1 --size-ratio 0.9"), {"--size-ratio"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--threads -1"), {"--threads"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--threads 1000000"), {"--threads"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--relaxation 2"), {"--relaxation"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--surface-lloyd -1"), {"--surface-lloyd"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--mean-tolerance -1"), {"--mean-tolerance"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--mean-tolerance nan"), {"--mean-tolerance"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--points-per-site 2"), {"--points-per-site"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--points-per-site nan"), {"--points-per-site"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--count-retries -1"), {"--count-retries"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--retry-count-error nan"), {"--retry-count-error"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--finer-retry 0.5"), {"--finer-retry"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--finer-retry nan"), {"--finer-retry"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--dense-pieces 1.5"), {"--dense-pieces"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--dense-pieces nan"), {"--dense-pieces"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--tip-growth -1"), {"--tip-growth"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--tip-growth nan"), {"--tip-growth"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--t-coef 1e10"), {"--t-coef"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", base + "--bogus"), {"bogus"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("s.xyz") + " -o " + dir.path("o.xyz")), {"o.xyz"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("s.xyz") + " -o " + dir.path("missing/o.ply")),
                       {"missing"}, dir, 1);
  expect_clean_failure(test::run_tool("cloud2mesh", dir.path("s.xyz") + " -o " + dir.path("o.ply") + " --report " +
                                                        dir.path("r.txt")),
                       {"r.txt"}, dir, 1);
}
