// Mesh file input/output: real files of ../shared/data, round trips, hand-made files in every
// supported encoding, each class of bad input, byte-level fuzzing and atomic writes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "heatcvt/atomic_file.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace heatcvt;

namespace {

// A fresh, empty temporary directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("heatcvt_mesh_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
};

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Expects `fn` to throw exactly type E whose message contains the path and `problem`.
template <typename E, typename Fn>
void expect_error(Fn&& fn, const std::string& path, const std::string& problem) {
  try {
    fn();
    ADD_FAILURE() << "no exception for " << path << " (expected '" << problem << "')";
  } catch (const E& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
  }
}

// Every vertex is referenced and every index is in range.
void expect_clean(const TriangleMesh& m) {
  ASSERT_GT(m.F.rows(), 0);
  EXPECT_GE(m.F.minCoeff(), 0);
  EXPECT_LT(m.F.maxCoeff(), m.V.rows());
  std::vector<char> used(static_cast<size_t>(m.V.rows()), 0);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(m.F(f, k))] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 1), m.V.rows());
  EXPECT_TRUE(m.V.allFinite());
}

// An irregular torus: coordinates with many significant digits.
TriangleMesh test_mesh() {
  TriangleMesh m = test::torus(12, 9, 1.3, 0.45);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) += Eigen::RowVector3d(1e-3 * std::sin(7.0 * i), 1.0 / 3.0, -2e5);
  return m;
}

struct BigEndianBytes {
  std::string bytes;
  template <typename T>
  void put(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));  // host is little endian on every platform we build on (checked below)
    bytes.append(reinterpret_cast<const char*>(b), sizeof(T));
  }
};

}  // namespace

// ------------------------------------------------------------------------------------------
// Real files

struct MeshFileFacts {
  const char* file;
  int vertices;     // as stored (SOURCES.md)
  int polygons;     // as stored (SOURCES.md)
  int unreferenced; // SOURCES.md where stated, -1 = not stated
};

TEST(MeshIO, ReadsEverySharedMeshWithTheDocumentedCounts) {
  const MeshFileFacts facts[] = {
      {"armadillo.obj", 43243, 86482, -1},         {"armadillo_cgal.off", 26002, 52000, -1},
      {"armadillo_remeshed_14k.obj", 14587, 29170, -1}, {"bun_zipper.ply", 35947, 69451, 1113},
      {"bun_zipper_res2.ply", 8171, 16301, 25},    {"bun_zipper_res3.ply", 1889, 3851, -1},
      {"bun_zipper_res4.ply", 453, 948, -1},       {"bunny00_cgal.off", 37706, 75408, -1},
      {"bunny_libigl.off", 3485, 6966, -1},        {"bunny_manifold_3k.obj", 3301, 6598, -1},
      {"bunny_pmp.off", 34835, 69666, -1},         {"casting.obj", 5096, 10224, -1},
      {"double_torus_cgal.off", 231, 220, -1},     {"double_torus_ddg.obj", 3070, 6144, -1},
      {"dragon_23k.obj", 22998, 47794, 16},        {"dragon_vrip_res4.obj", 5205, 11102, -1},
      {"elephant.off", 2775, 5558, -1},            {"face_open.obj", 17157, 34144, -1},
      {"fandisk.off", 7229, 14454, -1},            {"fertility.off", 4494, 9000, -1},
      {"hemisphere_open.obj", 2051, 4000, -1},     {"kitten.obj", 9447, 18894, -1},
      {"klein_disc.obj", 2625, 2612, -1},          {"knot1.off", 3200, 6400, -1},
      {"knot_open3d.ply", 1440, 2880, -1},         {"max_planck_decimated.obj", 5272, 10540, -1},
      {"moebius.obj", 280, 224, -1},               {"redwood_frag_115_open3d.ply", 64365, 127229, -1},
      {"sphere_cgal.off", 162, 320, -1},           {"sphere_ddg.obj", 2562, 5120, -1},
      {"sphere_ico642.obj", 642, 1280, -1},        {"sphere_pmp.off", 16070, 32136, -1},
      {"spot.obj", 2930, 5856, -1},                {"spot_remeshed.obj", 11533, 23062, -1},
      {"torus.obj", 2304, 4608, -1},               {"torus_ddg.obj", 3840, 7680, -1}};
  int files = 0;
  for (const auto& fact : facts) {
    SCOPED_TRACE(fact.file);
    const std::string path = test::data_path(std::string("meshes/") + fact.file);
    MeshReadReport rep;
    const TriangleMesh m = read_mesh(path, &rep);
    ++files;
    EXPECT_EQ(rep.vertices_in_file, fact.vertices);
    EXPECT_EQ(rep.polygons_in_file, fact.polygons);
    if (fact.unreferenced >= 0) EXPECT_EQ(rep.unreferenced_vertices_dropped, fact.unreferenced);
    EXPECT_EQ(m.V.rows(), fact.vertices - rep.unreferenced_vertices_dropped);
    EXPECT_EQ(rep.degenerate_faces_dropped, 0);
    // Triangles: one per stored triangle plus what the polygons produced.
    EXPECT_EQ(m.F.rows(), fact.polygons - rep.polygons_triangulated + rep.triangles_from_polygons);
    expect_clean(m);
    // The soup (no clean-up) agrees: the number of distinct referenced vertices is V.
    const PolygonSoup soup = read_polygon_soup(path);
    std::set<int> referenced(soup.polygon_index.begin(), soup.polygon_index.end());
    EXPECT_EQ(static_cast<Eigen::Index>(referenced.size()), m.V.rows());
  }
  EXPECT_EQ(files, 36);
}

TEST(MeshIO, PolygonFilesAreTriangulatedWithTheRightTopologyAndArea) {
  struct Case {
    const char* file;
    int euler;  // SOURCES.md: double torus genus 2 (chi -2), klein_disc chi 1, moebius chi 0
  };
  for (const Case c : {Case{"double_torus_cgal.off", -2}, Case{"klein_disc.obj", 1}, Case{"moebius.obj", 0}}) {
    SCOPED_TRACE(c.file);
    const std::string path = test::data_path(std::string("meshes/") + c.file);
    MeshReadReport rep;
    const TriangleMesh m = read_mesh(path, &rep);
    const PolygonSoup soup = read_polygon_soup(path);
    EXPECT_EQ(rep.polygons_triangulated, soup.num_polygons());  // all faces were polygons
    long expected_triangles = 0;
    double polygon_area = 0;  // Newell area of every (planar or not) polygon
    for (int f = 0; f < soup.num_polygons(); ++f) {
      const int n = soup.polygon_start[f + 1] - soup.polygon_start[f];
      expected_triangles += n - 2;
      Eigen::Vector3d a = Eigen::Vector3d::Zero();
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d p = soup.V.row(soup.polygon_index[soup.polygon_start[f] + k]);
        const Eigen::Vector3d q = soup.V.row(soup.polygon_index[soup.polygon_start[f] + (k + 1) % n]);
        a += p.cross(q);
      }
      polygon_area += 0.5 * a.norm();
    }
    EXPECT_EQ(m.F.rows(), expected_triangles);
    const MeshTopology topo = mesh_topology(m.F, static_cast<int>(m.V.rows()));
    EXPECT_EQ(topo.euler_characteristic(), c.euler);
    // Triangulating near-planar polygons keeps the area (equal for planar ones).
    EXPECT_NEAR(surface_area(m.V, m.F), polygon_area, 2e-2 * polygon_area);
  }
}

// ------------------------------------------------------------------------------------------
// Round trips

TEST(MeshIO, RoundTripIsExactForPlyObjOff) {
  TempDir tmp;
  const TriangleMesh m = test_mesh();
  struct Case {
    std::string name;
    PlyEncoding enc;
    std::string format;
  };
  const Case cases[] = {{"a.ply", PlyEncoding::binary_little_endian, "ply-binary_little_endian"},
                        {"b.PLY", PlyEncoding::binary_big_endian, "ply-binary_big_endian"},
                        {"c.ply", PlyEncoding::ascii, "ply-ascii"},
                        {"d.obj", PlyEncoding::ascii, "obj"},
                        {"e.OFF", PlyEncoding::ascii, "off"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    MeshWriteOptions opt;
    opt.ply_encoding = c.enc;
    write_mesh(tmp.path(c.name), m.V, m.F, {}, opt);
    MeshReadReport rep;
    const TriangleMesh r = read_mesh(tmp.path(c.name), &rep);
    EXPECT_EQ(rep.format, c.format);
    ASSERT_EQ(r.V.rows(), m.V.rows());
    ASSERT_EQ(r.F.rows(), m.F.rows());
    EXPECT_EQ(r.F, m.F);
    EXPECT_EQ((r.V - m.V).cwiseAbs().maxCoeff(), 0.0);  // shortest round-trip text / raw doubles
  }
}

TEST(MeshIO, StlRoundTripWeldsVerticesAndKeepsFloatPositions) {
  TempDir tmp;
  const TriangleMesh m = test::torus(10, 7);
  write_mesh(tmp.path("t.stl"), m.V, m.F);
  EXPECT_EQ(fs::file_size(tmp.path("t.stl")), 84u + 50u * static_cast<unsigned>(m.F.rows()));
  MeshReadReport rep;
  const TriangleMesh r = read_mesh(tmp.path("t.stl"), &rep);
  EXPECT_EQ(rep.format, "stl-binary");
  EXPECT_EQ(r.V.rows(), m.V.rows());  // welded back to the shared vertices
  EXPECT_EQ(rep.welded_vertices, 3 * m.F.rows() - m.V.rows());
  ASSERT_EQ(r.F.rows(), m.F.rows());
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d)
        EXPECT_EQ(r.V(r.F(f, k), d), static_cast<double>(static_cast<float>(m.V(m.F(f, k), d))));
  const MeshTopology topo = mesh_topology(r.F, static_cast<int>(r.V.rows()));
  EXPECT_EQ(topo.euler_characteristic(), 0);
  EXPECT_EQ(topo.boundary_edges, 0);
}

TEST(MeshIO, AsciiStlWithPolygonLoopIsRead) {
  TempDir tmp;
  const std::string p = tmp.path("tet.stl");
  write_text(p,
             "solid tet\n"
             " facet normal 0 0 -1\n  outer loop\n   vertex 0 0 0\n   vertex 0 1 0\n   vertex 1 0 0\n  endloop\n endfacet\n"
             " facet normal 0 -1 0\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 0 1\n  endloop\n endfacet\n"
             " facet normal -1 0 0\n  outer loop\n   vertex 0 0 0\n   vertex 0 0 1\n   vertex 0 1 0\n  endloop\n endfacet\n"
             " facet normal 1 1 1\n  outer loop\n   vertex 1 0 0\n   vertex 0 1 0\n   vertex 0 0 1\n  endloop\n endfacet\n"
             "endsolid tet\n");
  MeshReadReport rep;
  const TriangleMesh r = read_mesh(p, &rep);
  EXPECT_EQ(rep.format, "stl-ascii");
  EXPECT_EQ(r.V.rows(), 4);
  EXPECT_EQ(r.F.rows(), 4);
  const MeshTopology topo = mesh_topology(r.F, 4);
  EXPECT_EQ(topo.euler_characteristic(), 2);
  EXPECT_EQ(topo.boundary_edges, 0);
  EXPECT_EQ(topo.inconsistent_edges, 0);
}

TEST(MeshIO, PlyAttributesAreWrittenAndSkippedOnRead) {
  TempDir tmp;
  const TriangleMesh m = test_mesh();
  MeshAttributes attr;
  attr.face_int = Eigen::VectorXi::LinSpaced(m.F.rows(), 0, static_cast<int>(m.F.rows()) - 1);
  attr.face_color = Eigen::MatrixX3d::Constant(m.F.rows(), 3, 0.5);
  attr.vertex_color = Eigen::MatrixX3d::Constant(m.V.rows(), 3, 1.0);
  const std::string p = tmp.path("attr.ply");
  write_mesh(p, m.V, m.F, attr);
  const std::string bytes = read_bytes(p);
  const size_t header_end = bytes.find("end_header\n") + 11;
  EXPECT_NE(bytes.find("property int cell\n"), std::string::npos);
  EXPECT_NE(bytes.find("property uchar red\n"), std::string::npos);
  // Exact binary layout: vertices 3 doubles + 3 uchar, faces uchar + 3 int + int + 3 uchar.
  EXPECT_EQ(bytes.size(), header_end + static_cast<size_t>(m.V.rows()) * 27 + static_cast<size_t>(m.F.rows()) * 20);
  // Last face: label and colour bytes at the end of the file.
  int32_t last_label;
  std::memcpy(&last_label, bytes.data() + bytes.size() - 7, 4);
  EXPECT_EQ(last_label, m.F.rows() - 1);
  EXPECT_EQ(static_cast<unsigned char>(bytes.back()), 128);
  const TriangleMesh r = read_mesh(p);
  EXPECT_EQ(r.F, m.F);
  EXPECT_EQ(r.V, m.V);
  // Size mismatches are refused before anything is written.
  attr.face_int.resize(3);
  expect_error<InvalidInputError>([&] { write_mesh(tmp.path("bad.ply"), m.V, m.F, attr); }, "bad.ply", "face_int");
  EXPECT_FALSE(fs::exists(tmp.path("bad.ply")));
}

// ------------------------------------------------------------------------------------------
// Hand-made files in the less common encodings

TEST(MeshIO, BigEndianPlyWithMixedTypesAndExtraElements) {
  const uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  ASSERT_EQ(first, 1) << "this test builds big-endian bytes assuming a little-endian host";
  TempDir tmp;
  // A unit square (4 vertices, one quad), an unused 5th vertex, an extra element before the
  // faces with a list property, extra per-vertex properties of several types.
  BigEndianBytes b;
  b.bytes =
      "ply\nformat binary_big_endian 1.0\ncomment hand made\nobj_info scanner 7\n"
      "element vertex 5\nproperty int16 id\nproperty float32 x\nproperty float64 y\nproperty float z\n"
      "property uchar red\nproperty uint8 green\nproperty char blue\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element range_grid 2\nproperty list uchar int vertex_indices\n"
      "element face 1\nproperty uint32 flags\nproperty list uint16 uint32 vertex_index\nproperty double quality\n"
      "end_header\n";
  const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {9, 9, 9}};
  for (int i = 0; i < 5; ++i) {
    b.put<int16_t>(static_cast<int16_t>(-i));
    b.put<float>(static_cast<float>(xyz[i][0]));
    b.put<double>(xyz[i][1]);
    b.put<float>(static_cast<float>(xyz[i][2]));
    b.put<uint8_t>(200);
    b.put<uint8_t>(100);
    b.put<int8_t>(-3);
    b.put<float>(0);
    b.put<float>(0);
    b.put<float>(1);
  }
  b.put<uint8_t>(2);  // range_grid 0: two entries
  b.put<int32_t>(7);
  b.put<int32_t>(8);
  b.put<uint8_t>(0);  // range_grid 1: empty
  b.put<uint32_t>(0xdeadbeef);
  b.put<uint16_t>(4);
  for (uint32_t v : {0u, 1u, 2u, 3u}) b.put<uint32_t>(v);
  b.put<double>(0.25);
  const std::string p = tmp.path("be.ply");
  write_text(p, b.bytes);
  MeshReadReport rep;
  const TriangleMesh m = read_mesh(p, &rep);
  EXPECT_EQ(rep.format, "ply-binary_big_endian");
  EXPECT_TRUE(rep.has_vertex_normals);
  EXPECT_EQ(rep.vertices_in_file, 5);
  EXPECT_EQ(rep.unreferenced_vertices_dropped, 1);
  EXPECT_EQ(rep.polygons_triangulated, 1);
  ASSERT_EQ(m.V.rows(), 4);
  ASSERT_EQ(m.F.rows(), 2);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.V(i, k), xyz[i][k]);
  EXPECT_DOUBLE_EQ(surface_area(m.V, m.F), 1.0);
  const Eigen::MatrixX3d n = vertex_normals(m.V, m.F);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(n(i, 2), 1.0, 1e-12);  // orientation of the quad kept
  // The same file cut short anywhere in the body is reported as truncated.
  const size_t body = b.bytes.find("end_header\n") + 11;
  for (size_t cut = body; cut < b.bytes.size(); cut += 7) {
    write_text(p, b.bytes.substr(0, cut));
    expect_error<IOError>([&] { read_mesh(p); }, p, "truncated");
  }
}

TEST(MeshIO, AsciiPlyWithVertexIndexAndUnknownElement) {
  TempDir tmp;
  const std::string p = tmp.path("a.ply");
  write_text(p,
             "ply\r\nformat ascii 1.0\r\ncomment crlf header\r\nelement vertex 4\r\nproperty double x\r\nproperty double y\r\n"
             "property double z\r\nproperty uchar red\r\nelement material 1\r\nproperty list int float weights\r\n"
             "element face 2\r\nproperty list uint8 int32 vertex_index\r\nproperty int cell\r\nend_header\r\n"
             "0 0 0 1\r\n1 0 0 2\r\n0 1 0 3\r\n0 0 1 4\r\n3 0.5 0.25 1e-3\r\n3 0 2 1 7\r\n4 0 1 2 3 8\r\n");
  MeshReadReport rep;
  const TriangleMesh m = read_mesh(p, &rep);
  EXPECT_EQ(rep.format, "ply-ascii");
  EXPECT_EQ(m.V.rows(), 4);
  EXPECT_EQ(m.F.rows(), 3);
  EXPECT_EQ(m.F.row(0), Eigen::RowVector3i(0, 2, 1));
}

TEST(MeshIO, ObjIndexFormsNegativeIndicesAndConcavePolygons) {
  TempDir tmp;
  const std::string p = tmp.path("forms.obj");
  // An L-shaped (concave) hexagon, written with every index form; a fan from corner 0 would
  // produce a triangle outside the polygon.
  write_text(p,
             "# comment\nmtllib x.mtl\no thing\n"
             "v 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\n"
             "vt 0 0\nvt 1 0\nvn 0 0 1\ng group\nusemtl m\ns off\n"
             "f 3/1/1 4//1 5/2 -1 1 2/1/1\n"
             "l 1 2\n");
  MeshReadReport rep;
  const TriangleMesh m = read_mesh(p, &rep);
  EXPECT_EQ(rep.format, "obj");
  EXPECT_TRUE(rep.has_vertex_normals);
  EXPECT_EQ(m.F.rows(), 4);
  EXPECT_EQ(rep.polygons_triangulated, 1);
  EXPECT_EQ(rep.triangles_from_polygons, 4);
  // Ear clipping: the triangles tile the L exactly (area 3), all oriented like the polygon (+z).
  EXPECT_NEAR(surface_area(m.V, m.F), 3.0, 1e-12);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    EXPECT_GT((b - a).cross(c - a).z(), 0.0) << "triangle " << f;
  }
}

TEST(MeshIO, HugePolygonIsTriangulatedQuickly) {
  TempDir tmp;
  // A regular 5000-gon (planar, convex): n-2 triangles covering exactly its area.
  const int n = 5000;
  std::ostringstream off;
  off << "OFF\n" << n << " 1 0\n";
  for (int i = 0; i < n; ++i)
    off << format_double(std::cos(2 * M_PI * i / n)) << ' ' << format_double(std::sin(2 * M_PI * i / n)) << " 0\n";
  off << n;
  for (int i = 0; i < n; ++i) off << ' ' << i;
  off << '\n';
  write_text(tmp.path("ngon.off"), off.str());
  MeshReadReport rep;
  const TriangleMesh m = read_mesh(tmp.path("ngon.off"), &rep);
  EXPECT_EQ(m.F.rows(), n - 2);
  EXPECT_EQ(rep.triangles_from_polygons, n - 2);
  EXPECT_NEAR(surface_area(m.V, m.F), 0.5 * n * std::sin(2 * M_PI / n), 1e-9);
}

TEST(MeshIO, OffVariantsWithCommentsColoursAndInlineCounts) {
  TempDir tmp;
  const std::string p = tmp.path("c.off");
  write_text(p,
             "COFF 5 2 0 # counts on the header line\n"
             "# a comment line\n\n"
             "0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 255\n5 5 5 0 0 0 255\n"
             "4 0 1 2 3 0.5 0.5 0.5 1\n"
             "3 0 0 1\n");  // degenerate triangle (repeated index)
  MeshReadReport rep;
  const TriangleMesh m = read_mesh(p, &rep);
  EXPECT_EQ(m.V.rows(), 4);
  EXPECT_EQ(m.F.rows(), 2);
  EXPECT_EQ(rep.degenerate_faces_dropped, 1);
  EXPECT_EQ(rep.unreferenced_vertices_dropped, 1);
  EXPECT_DOUBLE_EQ(surface_area(m.V, m.F), 1.0);
  const std::string q = tmp.path("n.off");
  write_text(q, "NOFF\n3 1 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  EXPECT_EQ(read_mesh(q).F.rows(), 1);
}

// ------------------------------------------------------------------------------------------
// Bad input

TEST(MeshIO, MissingFileAndUnknownFormat) {
  TempDir tmp;
  const std::string missing = tmp.path("nope.obj");
  expect_error<IOError>([&] { read_mesh(missing); }, missing, "does not exist");
  const std::string unknown = tmp.path("mesh.xyz3");
  write_text(unknown, "v 0 0 0\n");
  expect_error<IOError>([&] { read_mesh(unknown); }, unknown, "unknown mesh format");
  const std::string noext = tmp.path("mesh");
  write_text(noext, "v 0 0 0\n");
  expect_error<IOError>([&] { read_mesh(noext); }, noext, "unknown mesh format");
  const std::string notply = tmp.path("fake.ply");
  write_text(notply, "OFF\n3 1 0\n");
  expect_error<IOError>([&] { read_mesh(notply); }, notply, "not a PLY file");
  const std::string empty = tmp.path("empty.off");
  write_text(empty, "");
  expect_error<IOError>([&] { read_mesh(empty); }, empty, "empty");
  expect_error<IOError>([&] { read_mesh(tmp.dir().string() + "/"); }, tmp.dir().string(), "");
  expect_error<IOError>([&] { write_mesh(tmp.path("out.vtk"), test_mesh().V, test_mesh().F); }, "out.vtk",
                        "unknown mesh format");
}

TEST(MeshIO, RealFilesCutInHalfAreTruncated) {
  TempDir tmp;
  for (const char* name : {"bun_zipper_res4.ply", "knot_open3d.ply", "redwood_frag_115_open3d.ply", "sphere_cgal.off",
                           "fandisk.off"}) {
    SCOPED_TRACE(name);
    const std::string bytes = read_bytes(test::data_path(std::string("meshes/") + name));
    const std::string p = tmp.path(std::string("half_") + name);
    write_text(p, bytes.substr(0, bytes.size() / 2));
    expect_error<IOError>([&] { read_mesh(p); }, p, "truncated");
  }
  // Binary STL cut in half.
  const TriangleMesh m = test::torus(8, 6);
  write_mesh(tmp.path("full.stl"), m.V, m.F);
  const std::string stl = read_bytes(tmp.path("full.stl"));
  write_text(tmp.path("half.stl"), stl.substr(0, stl.size() / 2));
  expect_error<IOError>([&] { read_mesh(tmp.path("half.stl")); }, tmp.path("half.stl"), "truncated");
  write_text(tmp.path("tiny.stl"), stl.substr(0, 40));
  expect_error<IOError>([&] { read_mesh(tmp.path("tiny.stl")); }, tmp.path("tiny.stl"), "truncated");
}

TEST(MeshIO, HugeHeaderCountsFailFastWithoutAllocating) {
  TempDir tmp;
  const std::string ply = tmp.path("huge.ply");
  write_text(ply, "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty double x\nproperty double y\n"
                  "property double z\nelement face 2000000000\nproperty list uchar int vertex_indices\nend_header\n\x01\x02");
  expect_error<IOError>([&] { read_mesh(ply); }, ply, "truncated");
  const std::string ply2 = tmp.path("huge_list.ply");
  std::string body = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
  body += std::string(12, '\0');
  body += std::string("\xff\xff\xff\x7f", 4);  // list of 2^31-1 entries
  write_text(ply2, body);
  expect_error<IOError>([&] { read_mesh(ply2); }, ply2, "truncated");
  // An element without properties occupies no bytes, so a huge count is legal and must be cheap.
  const std::string empty_el = tmp.path("empty_element.ply");
  write_text(empty_el, "ply\nformat ascii 1.0\nelement nothing 2000000000\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                       "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(read_mesh(empty_el).F.rows(), 1);
  const std::string off = tmp.path("huge.off");
  write_text(off, "OFF\n1999999999 1999999999 0\n0 0 0\n");
  expect_error<IOError>([&] { read_mesh(off); }, off, "truncated");
  const std::string off2 = tmp.path("overflow.off");
  write_text(off2, "OFF\n99999999999999999999999 1 0\n0 0 0\n");
  expect_error<IOError>([&] { read_mesh(off2); }, off2, "malformed");
}

TEST(MeshIO, FaceIndexOutOfRange) {
  TempDir tmp;
  const std::string obj = tmp.path("range.obj");
  write_text(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  expect_error<IOError>([&] { read_mesh(obj); }, obj, "out of range");
  const std::string neg = tmp.path("neg.obj");
  write_text(neg, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  expect_error<IOError>([&] { read_mesh(neg); }, neg, "out of range");
  const std::string off = tmp.path("range.off");
  write_text(off, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expect_error<IOError>([&] { read_mesh(off); }, off, "out of range");
  const std::string ply = tmp.path("range.ply");
  write_text(ply, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n");
  expect_error<IOError>([&] { read_mesh(ply); }, ply, "out of range");
}

TEST(MeshIO, NonFiniteCoordinates) {
  TempDir tmp;
  const std::string obj = tmp.path("nan.obj");
  write_text(obj, "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
  expect_error<InvalidInputError>([&] { read_mesh(obj); }, obj, "non-finite");
  const std::string off = tmp.path("inf.off");
  write_text(off, "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n");
  expect_error<InvalidInputError>([&] { read_mesh(off); }, off, "non-finite");
  const TriangleMesh m = test::torus(6, 5);
  Eigen::MatrixX3d V = m.V;
  V(3, 1) = std::numeric_limits<double>::quiet_NaN();
  write_mesh(tmp.path("nan.ply"), V, m.F);  // writers do not judge, readers do
  expect_error<InvalidInputError>([&] { read_mesh(tmp.path("nan.ply")); }, tmp.path("nan.ply"), "vertex 3 has a non-finite");
}

TEST(MeshIO, NoFaces) {
  TempDir tmp;
  const std::string obj = tmp.path("points.obj");
  write_text(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n");
  expect_error<InvalidInputError>([&] { read_mesh(obj); }, obj, "no faces");
  const std::string ply = tmp.path("points.ply");
  write_text(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n");
  expect_error<InvalidInputError>([&] { read_mesh(ply); }, ply, "no faces");
  const std::string deg = tmp.path("degenerate.off");
  write_text(deg, "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n2 0 1\n");
  expect_error<InvalidInputError>([&] { read_mesh(deg); }, deg, "no faces");
  // The soup reader itself accepts a file without faces (used for point clouds).
  EXPECT_EQ(read_polygon_soup(ply).V.rows(), 1);
}

TEST(MeshIO, MalformedNumbersAndHeaders) {
  TempDir tmp;
  const std::pair<std::string, std::string> cases[] = {
      {"num.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"},
      {"idx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n"},
      {"num.off", "OFF\n3 1 0\n0 0 0\n1 0 0,5\n0 1 0\n3 0 1 2\n"},
      {"cnt.off", "OFF\nthree 1 0\n"},
      {"num.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 O\n3 0 1 2\n"},
      {"type.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float128 x\nend_header\n"},
      {"fmt.ply", "ply\nformat binary_middle_endian 1.0\nelement vertex 3\nproperty float x\nend_header\n"},
      {"nohdr.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"},
      {"int.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1.5\n"},
  };
  for (const auto& [name, text] : cases) {
    SCOPED_TRACE(name);
    const std::string p = tmp.path(name);
    write_text(p, text);
    try {
      read_mesh(p);
      ADD_FAILURE() << "no exception";
    } catch (const IOError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(p + ": ", 0), 0u) << msg;
      EXPECT_TRUE(msg.find("malformed") != std::string::npos || msg.find("unknown") != std::string::npos ||
                  msg.find("truncated") != std::string::npos || msg.find("non-integer") != std::string::npos)
          << msg;
    }
  }
}

// Random byte damage and random truncation of real files must end in a heatcvt::Error or a
// valid mesh, never a crash, hang or foreign exception.
TEST(MeshIO, FuzzedFilesNeverCrash) {
  TempDir tmp;
  std::mt19937 rng(12345);
  int errors = 0, successes = 0;
  for (const char* name : {"bun_zipper_res4.ply", "knot_open3d.ply", "sphere_cgal.off", "double_torus_cgal.off",
                           "moebius.obj"}) {
    const std::string original = read_bytes(test::data_path(std::string("meshes/") + name));
    const std::string ext = fs::path(name).extension().string();
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      const int mode = trial % 3;
      if (mode == 0) {  // flip bytes (the header region more often)
        const int flips = 1 + static_cast<int>(rng() % 8);
        for (int k = 0; k < flips; ++k) {
          const size_t limit = (rng() % 2) ? std::min<size_t>(bytes.size(), 400) : bytes.size();
          bytes[rng() % limit] = static_cast<char>(rng() % 256);
        }
      } else if (mode == 1) {  // truncate anywhere
        bytes.resize(rng() % bytes.size());
      } else {  // overwrite a digit run in the header with a huge number
        const size_t at = bytes.find_first_of("0123456789", rng() % std::min<size_t>(bytes.size(), 300));
        if (at != std::string::npos) bytes.replace(at, 1, "4294967295");
      }
      const std::string p = tmp.path("fuzz" + ext);
      write_text(p, bytes);
      try {
        const TriangleMesh m = read_mesh(p);
        expect_clean(m);
        ++successes;
      } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind(p + ": ", 0), 0u) << msg;
        ++errors;
      }
    }
  }
  EXPECT_GT(errors, 0);
  EXPECT_GT(successes, 0);
}

// ------------------------------------------------------------------------------------------
// Atomic writes and the small writers

TEST(MeshIO, AtomicWriteLeavesNothingBehindOnFailure) {
  TempDir tmp;
  const TriangleMesh m = test::torus(6, 5);
  const std::string nodir = tmp.path("no/such/dir/out.ply");
  expect_error<IOError>([&] { write_mesh(nodir, m.V, m.F); }, nodir, "does not exist");

  const std::string target = tmp.path("out.obj");
  struct Boom : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  EXPECT_THROW(write_atomically(target,
                                [](std::ostream& out) {
                                  out << std::string(100000, 'x');
                                  throw Boom("writer failed midway");
                                }),
               Boom);
  EXPECT_TRUE(fs::is_empty(tmp.dir())) << "neither target nor temporary may remain";

  // An existing file is replaced only by a complete new one.
  write_mesh(target, m.V, m.F);
  const std::string before = read_bytes(target);
  EXPECT_THROW(write_atomically(target, [](std::ostream& out) {
                 out << "partial";
                 throw Boom("fail");
               }),
               Boom);
  EXPECT_EQ(read_bytes(target), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.dir()), fs::directory_iterator()), 1);

  write_atomically(target, [](std::ostream& out) { out << "replaced\n"; });
  EXPECT_EQ(read_bytes(target), "replaced\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.dir()), fs::directory_iterator()), 1);
}

TEST(MeshIO, PolylinesAndPointsWriters) {
  TempDir tmp;
  Eigen::MatrixX3d P(4, 3);
  P << 0, 0, 0, 1, 0.1, 0, 1, 1, 1e-9, 0, 1, -2.5;
  write_polylines_obj(tmp.path("l.obj"), P, {{0, 1, 2}, {2, 3, 0}});
  std::istringstream in(read_bytes(tmp.path("l.obj")));
  std::string line;
  int v = 0;
  std::vector<std::string> lines;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream ls(line.substr(2));
      double x, y, z;
      ls >> x >> y >> z;
      EXPECT_EQ(Eigen::RowVector3d(x, y, z), P.row(v));
      ++v;
    }
    if (line.rfind("l ", 0) == 0) lines.push_back(line);
  }
  EXPECT_EQ(v, 4);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "l 1 2 3");
  EXPECT_EQ(lines[1], "l 3 4 1");
  expect_error<InvalidInputError>([&] { write_polylines_obj(tmp.path("bad.obj"), P, {{0, 4}}); }, "bad.obj", "point 4");
  EXPECT_FALSE(fs::exists(tmp.path("bad.obj")));

  Eigen::MatrixX3d N = P.rowwise().normalized();
  N.row(0).setZero();
  write_points_xyz(tmp.path("p.xyz"), P, N);
  std::istringstream pin(read_bytes(tmp.path("p.xyz")));
  for (int i = 0; i < 4; ++i) {
    double a[6];
    for (double& x : a) pin >> x;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(a[k], P(i, k));
      EXPECT_EQ(a[3 + k], N(i, k));
    }
  }
  EXPECT_THROW(write_points_xyz(tmp.path("q.xyz"), P, N.topRows(2)), InvalidInputError);
}

TEST(MeshIO, FormatDoubleIsShortestAndExact) {
  for (double x : {0.1, 1.0 / 3.0, -2.5e-300, 5.4e6 + 0.125, 1e300, 0.0}) {
    const std::string s = format_double(x);
    EXPECT_EQ(std::stod(s), x) << s;
  }
  EXPECT_EQ(format_double(0.5), "0.5");
  EXPECT_EQ(format_double(std::numeric_limits<double>::quiet_NaN()), "nan");
}
