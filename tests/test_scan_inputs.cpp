// Scans as users bring them: per-point colour read from every cloud format and carried to the
// reconstructed vertices, normals written on request, and several scans with rigid poses merged
// into one surface (scan_merge.h, vertex_attributes.h, cloud2mesh).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/normals.h"
#include "heatcvt/point_index.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/scan_merge.h"
#include "heatcvt/validate.h"
#include "heatcvt/vertex_attributes.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

void write_binary(const std::string& path, const std::string& header, const std::string& body) {
  std::ofstream out(path, std::ios::binary);
  out << header;
  out.write(body.data(), static_cast<std::streamsize>(body.size()));
}

template <typename T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// Mean over vertices and channels of |colour(v) − colour of the input point nearest to v|.
double mean_colour_error(const PointCloud& cloud, const Eigen::MatrixX3d& V, const Eigen::MatrixX3d& colours) {
  const Eigen::MatrixXi nn = nearest_neighbors_of(cloud.P, V, 1);
  double sum = 0;
  for (Eigen::Index v = 0; v < V.rows(); ++v) sum += (colours.row(v) - cloud.C.row(nn(v, 0))).cwiseAbs().sum();
  return sum / (3.0 * static_cast<double>(V.rows()));
}

Eigen::Isometry3d some_pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  pose.translation() = t;
  return pose;
}

std::string matrix_text(const Eigen::Isometry3d& pose) {
  std::ostringstream s;
  s.precision(17);
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) s << m(r, 0) << ' ' << m(r, 1) << ' ' << m(r, 2) << ' ' << m(r, 3) << '\n';
  return s.str();
}

}  // namespace

TEST(CloudColour, PcdPackedRgbFloatAndRgbaUint) {
  test::ScratchDir dir("colour_pcd");
  // PCL packs colour into 4 bytes read as a little-endian uint32 0xAARRGGBB.
  const std::uint32_t packed[2] = {0xff102030u, 0x00ff8000u};
  for (const char* type : {"F", "U"}) {
    std::string body;
    for (int i = 0; i < 2; ++i) {
      put<float>(body, static_cast<float>(i));
      put<float>(body, 0.f);
      put<float>(body, 0.f);
      put<std::uint32_t>(body, packed[i]);
    }
    const std::string field = std::string(type) == "F" ? "rgb" : "rgba";
    const std::string header = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z " + field + "\nSIZE 4 4 4 4\nTYPE F F F " + type +
                               "\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n";
    const std::string path = dir.path(field + ".pcd");
    write_binary(path, header, body);
    CloudReadReport rep;
    const PointCloud c = read_cloud(path, &rep);
    ASSERT_TRUE(c.has_colours()) << field;
    EXPECT_TRUE(rep.has_colours);
    EXPECT_NEAR(c.C(0, 0), 0x10 / 255.0, 1e-12);
    EXPECT_NEAR(c.C(0, 1), 0x20 / 255.0, 1e-12);
    EXPECT_NEAR(c.C(0, 2), 0x30 / 255.0, 1e-12);
    EXPECT_NEAR(c.C(1, 0), 1.0, 1e-12);
    EXPECT_NEAR(c.C(1, 1), 0x80 / 255.0, 1e-12);
    EXPECT_NEAR(c.C(1, 2), 0.0, 1e-12);
  }
}

TEST(CloudColour, PcdSeparateFieldsAndPlyUcharAndFloatColours) {
  test::ScratchDir dir("colour_sep");
  const std::string pcd = dir.path("sep.pcd");
  test::write_text_file(pcd, "VERSION 0.7\nFIELDS x y z r g b\nSIZE 4 4 4 1 1 1\nTYPE F F F U U U\nCOUNT 1 1 1 1 1 1\n"
                             "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 0 255 0 51\n1 0 0 0 102 0\n");
  const PointCloud a = read_cloud(pcd);
  ASSERT_TRUE(a.has_colours());
  EXPECT_NEAR(a.C(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(a.C(0, 2), 0.2, 1e-12);
  EXPECT_NEAR(a.C(1, 1), 0.4, 1e-12);

  const std::string ply_u = dir.path("u.ply"), ply_f = dir.path("f.ply");
  test::write_text_file(ply_u, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                               "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
                               "0 0 0 255 0 51\n1 0 0 0 102 0\n");
  test::write_text_file(ply_f, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                               "property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\nend_header\n"
                               "0 0 0 1 0 0.2\n1 0 0 0 0.4 0\n");
  for (const std::string& path : {ply_u, ply_f}) {
    const PointCloud c = read_cloud(path);
    ASSERT_TRUE(c.has_colours()) << path;
    EXPECT_NEAR(c.C(0, 0), 1.0, 1e-6) << path;
    EXPECT_NEAR(c.C(0, 2), 0.2, 1e-6) << path;
    EXPECT_NEAR(c.C(1, 1), 0.4, 1e-6) << path;
  }
  // A cloud without colour columns has none.
  const std::string plain = dir.path("plain.xyz");
  test::write_text_file(plain, "0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_FALSE(read_cloud(plain).has_colours());
}

TEST(CloudColour, CleanUpKeepsColoursWithTheirPoints) {
  PointCloud c;
  c.P.resize(4, 3);
  c.P << 0, 0, 0, NAN, 0, 0, 1, 0, 0, 0, 0, 0;  // a NaN point and a duplicate of point 0
  c.C.resize(4, 3);
  c.C << 0.1, 0.1, 0.1, 0.2, 0.2, 0.2, 0.3, 0.3, 0.3, 0.4, 0.4, 0.4;
  clean_cloud(c);
  ASSERT_EQ(c.P.rows(), 2);
  ASSERT_TRUE(c.has_colours());
  EXPECT_DOUBLE_EQ(c.C(0, 0), 0.1);  // the first occurrence of the duplicate is kept
  EXPECT_DOUBLE_EQ(c.P(1, 0), 1.0);
  EXPECT_DOUBLE_EQ(c.C(1, 0), 0.3);
}

TEST(TransferColours, ExactAtPointsConstantStaysConstantAndScaleInvariant) {
  // A 20×20 grid coloured red on x < 0.5 and blue elsewhere.
  const int n = 20;
  Eigen::MatrixX3d P(n * n, 3), C(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      P.row(i * n + j) << i / (n - 1.0), j / (n - 1.0), 0;
      C.row(i * n + j) = i < n / 2 ? Eigen::RowVector3d(1, 0, 0) : Eigen::RowVector3d(0, 0, 1);
    }
  const Eigen::MatrixX3d at_points = transfer_colours(P, C, P);
  EXPECT_EQ((at_points - C).cwiseAbs().maxCoeff(), 0.0);
  // Query points well inside each half, off the grid nodes.
  Eigen::MatrixX3d Q(2, 3);
  Q << 0.13, 0.41, 0.01, 0.87, 0.52, -0.01;
  const Eigen::MatrixX3d q = transfer_colours(P, C, Q);
  EXPECT_NEAR(q(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(q(1, 2), 1.0, 1e-12);
  // Constant colour is reproduced anywhere; the result does not depend on the unit of length.
  const Eigen::MatrixX3d grey = Eigen::MatrixX3d::Constant(n * n, 3, 0.5);
  EXPECT_LT((transfer_colours(P, grey, Q).array() - 0.5).abs().maxCoeff(), 1e-12);
  for (double s : {1e-9, 1e6}) {
    const Eigen::MatrixX3d qs = transfer_colours(P * s, C, Q * s);
    EXPECT_LT((qs - q).cwiseAbs().maxCoeff(), 1e-9) << s;
  }
  // Same result for any thread count.
  ColourTransferOptions one;
  one.threads = 1;
  ColourTransferOptions two = one;
  two.threads = 2;
  EXPECT_EQ(transfer_colours(P, C, Q, one), transfer_colours(P, C, Q, two));
}

// The acceptance rule of the real-scans issue: a reconstruction of a coloured scan has per-vertex
// colour within 10/255 (mean absolute difference) of the nearest input point's colour.
TEST(TransferColours, RealColouredScansWithinTenLevelsOfTheNearestPoint) {
  for (const char* name : {"clouds/pcl_milk_color.pcd", "clouds/open3d_cloud_bin_0.pcd", "clouds/open3d_cloud_bin_1.pcd"}) {
    const PointCloud cloud = read_cloud(test::data_path(name));
    ASSERT_TRUE(cloud.has_colours()) << name;
    ReconstructionOptions opt;
    opt.sites = 1000;
    const ReconstructionResult r = reconstruct_surface(cloud.P, opt);
    ASSERT_GT(r.mesh.V.rows(), 500) << name;
    const Eigen::MatrixX3d colours = transfer_colours(cloud.P, cloud.C, r.mesh.V);
    const double error = mean_colour_error(cloud, r.mesh.V, colours);
    std::printf("%s: mean colour difference %.2f / 255\n", name, 255.0 * error);
    EXPECT_LT(error, 10.0 / 255.0) << name;
  }
}

TEST(MeshAttributesIo, NormalsAndColoursRoundTripThroughPlyAndObj) {
  test::ScratchDir dir("attr_io");
  const TriangleMesh m = test::icosphere(1);
  MeshAttributes attr;
  attr.vertex_normal = m.V.rowwise().normalized();
  attr.vertex_color = (m.V.array() * 0.5 + 0.5).matrix();
  for (const char* ext : {".ply", ".obj"}) {
    const std::string path = dir.path(std::string("m") + ext);
    write_mesh(path, m.V, m.F, attr);
    MeshReadReport rep;
    const PolygonSoup soup = read_polygon_soup(path, &rep);
    EXPECT_TRUE(rep.has_vertex_normals) << ext;
    ASSERT_EQ(soup.V.rows(), m.V.rows());
    if (std::string(ext) == ".ply") {
      ASSERT_EQ(soup.C.rows(), m.V.rows());
      EXPECT_LT((soup.C - attr.vertex_color).cwiseAbs().maxCoeff(), 0.5 / 255.0 + 1e-12);
      ASSERT_EQ(soup.N.rows(), m.V.rows());
      EXPECT_LT((soup.N - attr.vertex_normal).cwiseAbs().maxCoeff(), 1e-6);
    }
  }
  const std::string obj = [&] {
    std::ifstream in(dir.path("m.obj"));
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }();
  EXPECT_NE(obj.find("\nvn "), std::string::npos);
  EXPECT_NE(obj.find("//"), std::string::npos);
}

TEST(ScanPoses, PoseFilesRigidOnly) {
  test::ScratchDir dir("poses");
  const Eigen::Isometry3d pose = some_pose(0.7, {1, 2, 3}, {0.5, -1, 2});
  const std::string good = dir.path("good.txt");
  test::write_text_file(good, "# a pose\n" + matrix_text(pose));
  EXPECT_LT((read_pose_file(good).matrix() - pose.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // 3×4 form.
  std::string three_by_four = matrix_text(pose);
  three_by_four.resize(three_by_four.rfind('\n', three_by_four.size() - 2) + 1);
  const std::string top = dir.path("top.txt");
  test::write_text_file(top, three_by_four);
  EXPECT_LT((read_pose_file(top).matrix() - pose.matrix()).cwiseAbs().maxCoeff(), 1e-12);

  Eigen::Isometry3d scaled = pose;
  scaled.linear() *= 2.0;
  const std::string bad_scale = dir.path("scale.txt"), bad_nan = dir.path("nan.txt"), bad_row = dir.path("row.txt"),
                    bad_count = dir.path("count.txt"), bad_word = dir.path("word.txt");
  test::write_text_file(bad_scale, matrix_text(scaled));
  test::write_text_file(bad_nan, "nan 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  test::write_text_file(bad_row, "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n");
  test::write_text_file(bad_count, "1 0 0 0\n0 1 0 0\n");
  test::write_text_file(bad_word, "1 0 0 0\n0 1 0 0\n0 0 one 0\n0 0 0 1\n");
  EXPECT_THROW(read_pose_file(bad_scale), InvalidInputError);
  EXPECT_THROW(read_pose_file(bad_nan), Error);
  EXPECT_THROW(read_pose_file(bad_row), InvalidInputError);
  EXPECT_THROW(read_pose_file(bad_count), IOError);
  EXPECT_THROW(read_pose_file(bad_word), IOError);
  EXPECT_THROW(read_pose_file(dir.path("missing.txt")), IOError);
}

TEST(ScanPoses, StanfordConfRelativeFilesAndErrors) {
  test::ScratchDir dir("conf");
  test::write_text_file(dir.path("a.xyz"), "0 0 0\n1 0 0\n0 1 0\n");
  // 90° about z: quaternion (x, y, z, w) = (0, 0, sin 45°, cos 45°).
  const double h = std::sqrt(0.5);
  test::write_text_file(dir.path("scans.conf"),
                        "camera 0 0 0 0 0 0 1\nbmesh a.xyz 1 2 3 0 0 " + std::to_string(h) + " " + std::to_string(h) + "\n");
  const std::vector<ScanInput> scans = read_stanford_conf(dir.path("scans.conf"));
  ASSERT_EQ(scans.size(), 1u);
  const PointCloud c = read_scans(scans);
  ASSERT_EQ(c.P.rows(), 3);
  EXPECT_NEAR(c.P(1, 0), 1.0, 1e-5);  // (1,0,0) rotated to (0,1,0), then moved by (1,2,3)
  EXPECT_NEAR(c.P(1, 1), 3.0, 1e-5);
  EXPECT_NEAR(c.P(1, 2), 3.0, 1e-5);

  test::write_text_file(dir.path("missing.conf"), "bmesh nowhere.ply 0 0 0 0 0 0 1\n");
  test::write_text_file(dir.path("quat.conf"), "bmesh a.xyz 0 0 0 0 0 0 2\n");
  test::write_text_file(dir.path("empty.conf"), "camera 0 0 0 0 0 0 1\n");
  EXPECT_THROW(read_stanford_conf(dir.path("missing.conf")), IOError);
  EXPECT_THROW(read_stanford_conf(dir.path("quat.conf")), InvalidInputError);
  EXPECT_THROW(read_stanford_conf(dir.path("empty.conf")), IOError);
}

// A torus scanned from two sides, each view stored in its own frame with its pose, merged:
// the reconstruction is as close to the torus as the one from the single complete cloud.
TEST(ScanPoses, TwoViewsInTheirOwnFramesRecoverTheSingleViewResult) {
  test::ScratchDir dir("views");
  const TriangleMesh torus = test::torus(96, 48);
  const Eigen::MatrixX3d all = sample_surface(torus.V, torus.F, 20000, 5);
  const Eigen::Isometry3d poses[2] = {some_pose(0.9, {0, 1, 1}, {3, -2, 1}), some_pose(-2.1, {1, 0, 0.3}, {-40, 7, 0.5})};
  std::vector<ScanInput> scans;
  for (int v = 0; v < 2; ++v) {
    // View v sees x > -0.3 (v = 0) or x < 0.3 (v = 1): an overlap band around x = 0.
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < all.rows(); ++i)
      if (v == 0 ? all(i, 0) > -0.3 : all(i, 0) < 0.3) rows.push_back(i);
    Eigen::MatrixX3d local(static_cast<Eigen::Index>(rows.size()), 3);
    for (size_t i = 0; i < rows.size(); ++i)
      local.row(static_cast<Eigen::Index>(i)) = (poses[v].inverse() * Eigen::Vector3d(all.row(rows[i]))).transpose();
    const std::string file = dir.path("view" + std::to_string(v) + ".xyz"), pose = dir.path("pose" + std::to_string(v) + ".txt");
    write_points_xyz(file, local);
    test::write_text_file(pose, matrix_text(poses[v]));
    scans.push_back({file, read_pose_file(pose)});
  }
  const PointCloud merged = read_scans(scans);
  EXPECT_GT(merged.P.rows(), all.rows());  // the overlap band is there twice
  ReconstructionOptions opt;
  opt.sites = 800;
  const ReconstructionResult single = reconstruct_surface(all, opt);
  const ReconstructionResult both = reconstruct_surface(merged.P, opt);
  const double d_single = surface_distance(single.mesh.V, single.mesh.F, torus.V, torus.F).mean;
  const double d_both = surface_distance(both.mesh.V, both.mesh.F, torus.V, torus.F).mean;
  std::printf("mean distance to the torus: two views %.3g, single cloud %.3g\n", d_both, d_single);
  EXPECT_LT(d_both, 1.1 * d_single);
  EXPECT_EQ(both.validation.genus, 1);
  EXPECT_EQ(both.validation.boundary_loops, 0);
  EXPECT_EQ(both.validation.components, 1);
}

// Pairs of faces of `m` that share no vertex, face each other (normals within 30°, either
// way) and lie closer than `gap`: the centroid of one projects inside the other within `gap`
// of its plane. A surface meshed twice where two scans overlap has many; one layer has none
// (a face sharing no vertex with f lies beyond f's one-ring, a good part of an edge away).
int facing_pairs_closer_than(const TriangleMesh& m, double gap) {
  const Eigen::Index nf = m.F.rows();
  std::vector<Eigen::Vector3d> a(nf), b(nf), c(nf), n(nf), g(nf);
  for (Eigen::Index f = 0; f < nf; ++f) {
    a[f] = m.V.row(m.F(f, 0)), b[f] = m.V.row(m.F(f, 1)), c[f] = m.V.row(m.F(f, 2));
    n[f] = (b[f] - a[f]).cross(c[f] - a[f]).normalized();
    g[f] = (a[f] + b[f] + c[f]) / 3.0;
  }
  int pairs = 0;
  for (Eigen::Index f = 0; f < nf; ++f)
    for (Eigen::Index h = 0; h < nf; ++h) {
      bool shared = false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) shared = shared || m.F(f, i) == m.F(h, j);
      if (shared || std::abs(n[f].dot(n[h])) < std::cos(M_PI / 6)) continue;
      const double height = (g[h] - a[f]).dot(n[f]);
      if (std::abs(height) >= gap) continue;
      const Eigen::Vector3d q = g[h] - height * n[f];
      const Eigen::Vector3d bary = closest_point_barycentric(q, a[f], b[f], c[f]);
      const Eigen::Vector3d on = bary[0] * a[f] + bary[1] * b[f] + bary[2] * c[f];
      pairs += (on - q).norm() < 1e-12 * (1 + q.norm());  // the projection falls inside f
    }
  return pairs;
}

double mean_edge_length(const TriangleMesh& m) {
  double sum = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (m.V.row(m.F(f, k)) - m.V.row(m.F(f, (k + 1) % 3))).norm();
  return sum / (3.0 * static_cast<double>(m.F.rows()));
}

// Two overlapping RGB-D fragments (Open3D's cloud_bin_0 and cloud_bin_1, registered to about
// their point spacing) merge into one layer: no two faces closer than a quarter of the site
// spacing facing each other; a valid mesh with the vertex count asked for.
TEST(Cloud2MeshScans, OverlappingFragmentsGiveOneLayer) {
  const std::string a = test::data_path("clouds/open3d_cloud_bin_0.pcd"), b = test::data_path("clouds/open3d_cloud_bin_1.pcd");
  // Precondition: they overlap (most points of one lie within 2 point spacings of the other).
  const PointCloud pa = read_cloud(a), pb = read_cloud(b);
  double spacing = 0;
  int near = 0;
  for (Eigen::Index i = 0; i < pa.P.rows(); ++i) {
    double own = std::numeric_limits<double>::infinity(), other = own;
    for (Eigen::Index j = 0; j < pa.P.rows(); ++j)
      if (j != i) own = std::min(own, (pa.P.row(i) - pa.P.row(j)).squaredNorm());
    for (Eigen::Index j = 0; j < pb.P.rows(); ++j) other = std::min(other, (pa.P.row(i) - pb.P.row(j)).squaredNorm());
    spacing += std::sqrt(own) / static_cast<double>(pa.P.rows());
    near += other < 4 * own;
  }
  ASSERT_GT(near, pa.P.rows() / 2) << "spacing " << spacing;
  // The check finds a double layer: a grid and its copy a tenth of an edge above it.
  const TriangleMesh grid = test::grid(8);
  TriangleMesh twice;
  twice.V.resize(2 * grid.V.rows(), 3);
  twice.V << grid.V, grid.V.rowwise() + Eigen::RowVector3d(0.01, 0.02, 0.1 / 8);
  twice.F.resize(2 * grid.F.rows(), 3);
  twice.F << grid.F, grid.F.array() + static_cast<int>(grid.V.rows());
  ASSERT_GT(facing_pairs_closer_than(twice, 0.25 * mean_edge_length(twice)), grid.F.rows() / 2);
  ASSERT_EQ(facing_pairs_closer_than(grid, 0.25 * mean_edge_length(grid)), 0);
  test::ScratchDir dir("c2m_fragments");
  const std::string out = dir.path("both.ply");
  for (const int n : {1000, 2000}) {
    SCOPED_TRACE(n);
    const auto r = test::run_tool("cloud2mesh", "'" + a + "' '" + b + "' -n " + std::to_string(n) + " -q -o " + out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const TriangleMesh m = read_mesh(out);
    ValidationOptions vo;
    vo.require_closed = false;
    const ValidationReport v = validate_triangle_mesh(m.V, m.F, vo);
    EXPECT_TRUE(v.ok()) << v.summary();
    EXPECT_NEAR(static_cast<double>(v.vertices), n, 0.02 * n);
    EXPECT_EQ(facing_pairs_closer_than(m, 0.25 * mean_edge_length(m)), 0);
  }
}

TEST(Cloud2MeshScans, ColourWrittenOnlyWhenTheInputHasItAndNormalsOnRequest) {
  test::ScratchDir dir("c2m_colour");
  const std::string out_c = dir.path("c.ply"), out_p = dir.path("p.ply");
  const auto rc = test::run_tool("cloud2mesh", test::data_path("clouds/pcl_milk_color.pcd") + " -n 500 -q --normals -o " + out_c);
  ASSERT_EQ(rc.exit_code, 0) << rc.err;
  const auto rp = test::run_tool("cloud2mesh", test::data_path("clouds/pcl_milk.pcd") + " -n 500 -q -o " + out_p);
  ASSERT_EQ(rp.exit_code, 0) << rp.err;
  MeshReadReport rep_c, rep_p;
  const PolygonSoup c = read_polygon_soup(out_c, &rep_c), p = read_polygon_soup(out_p, &rep_p);
  EXPECT_EQ(c.C.rows(), c.V.rows());
  EXPECT_TRUE(rep_c.has_vertex_normals);
  EXPECT_EQ(p.C.rows(), 0);
  EXPECT_FALSE(rep_p.has_vertex_normals);
}

TEST(Cloud2MeshScans, BadPosesGiveOneErrorLineAndNoOutput) {
  test::ScratchDir dir("c2m_pose");
  const std::string cloud = test::data_path("clouds/pcl_milk.pcd");
  test::write_text_file(dir.path("scale.txt"), "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n");
  test::write_text_file(dir.path("nan.txt"), "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  test::write_text_file(dir.path("missing.conf"), "bmesh not_there.pcd 0 0 0 0 0 0 1\n");
  const struct {
    std::string args, needle;
  } cases[] = {
      {cloud + " --pose " + dir.path("scale.txt"), "scale.txt"},
      {cloud + " --pose " + dir.path("nan.txt"), "nan.txt"},
      {"--conf " + dir.path("missing.conf"), "not_there.pcd"},
      {cloud + " " + cloud + " --pose " + dir.path("scale.txt"), "--pose"},
  };
  for (const auto& c : cases) {
    const std::string out = dir.path("out.ply");
    const auto r = test::run_tool("cloud2mesh", c.args + " -n 300 -q -o " + out);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_EQ(r.err.rfind("cloud2mesh: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
  }
}

// A cloud with more points than --stream-above (default StreamOptions::max_raw_points, 200,000)
// is streamed into a voxel summary by cloud2mesh; the mesh meets the same checks.
// A cloud far below --stream-above but with more points per site than --stream-per-site (default
// 40) is streamed into a voxel summary; with the per-site limit off (0) it is reconstructed from
// its raw points. raw_point_limit() is the smaller of the two limits.
TEST(Cloud2MeshScans, ACloudWithManyPointsPerSiteIsStreamedUnlessThatLimitIsOff) {
  StreamOptions limits;
  limits.max_raw_points = 200000;
  EXPECT_EQ(raw_point_limit(limits, 300), 12000);  // the default 40 per site
  EXPECT_EQ(raw_point_limit(limits, 10000), 200000);
  limits.max_raw_points_per_site = 0;
  EXPECT_EQ(raw_point_limit(limits, 300), 200000);
  test::ScratchDir dir("c2m_per_site");
  const TriangleMesh sphere = test::icosphere(4);
  const std::string cloud = dir.path("mid.xyz");
  write_points_xyz(cloud, sample_surface(sphere.V, sphere.F, 30000, 5, 0.001));
  for (const bool per_site : {false, true}) {
    SCOPED_TRACE(per_site);
    const std::string out = dir.path(per_site ? "s.ply" : "r.ply"), rep = dir.path(per_site ? "s.json" : "r.json");
    const auto r = test::run_tool("cloud2mesh", cloud + " -n 300 -q -o " + out + " --report " + rep +
                                                    (per_site ? "" : " --stream-per-site 0"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string json = test::read_file(rep);
    EXPECT_NE(json.find(per_site ? "\"streamed\": true" : "\"streamed\": false"), std::string::npos) << json;
    const TriangleMesh m = read_mesh(out);
    const ValidationReport v = validate_triangle_mesh(m.V, m.F, ValidationOptions{});
    EXPECT_TRUE(v.ok()) << v.summary();
    EXPECT_EQ(v.genus, 0);
    EXPECT_NEAR(m.V.rows(), 300, 6);
  }
}

TEST(Cloud2MeshScans, ALargeCloudIsStreamedIntoAVoxelSummary) {
  test::ScratchDir dir("c2m_stream");
  const TriangleMesh sphere = test::icosphere(5);
  const std::string cloud = dir.path("big.xyz"), out = dir.path("big.ply"), rep = dir.path("big.json");
  write_points_xyz(cloud, sample_surface(sphere.V, sphere.F, 400000, 9, 0.001));
  ASSERT_GT(400000, StreamOptions{}.max_raw_points);
  const auto r = test::run_tool("cloud2mesh", cloud + " -n 600 -q -o " + out + " --report " + rep);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(rep);
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(json.find("\"streamed\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"peak_memory_mb\""), std::string::npos);
  const TriangleMesh m = read_mesh(out);
  ValidationOptions vo;
  const ValidationReport v = validate_triangle_mesh(m.V, m.F, vo);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.boundary_loops, 0);
  EXPECT_EQ(v.genus, 0);
  EXPECT_GE(m.V.rows(), 0.95 * 600);
  // --points-per-site sizes the summary too: half the voxel points per site, about half the points.
  const std::string rep5 = dir.path("big5.json");
  const auto r5 = test::run_tool("cloud2mesh", cloud + " -n 600 --points-per-site 5 -o " + dir.path("big5.ply") +
                                                   " --report " + rep5);
  ASSERT_EQ(r5.exit_code, 0) << r5.err;
  // Progress on stderr (not a terminal): both read passes, then a line as each stage starts.
  for (const char* line : {"reading (pass 1): done", "reading (pass 2): done", "(laplacian)", "(cvt: factor and start)",
                           "(cvt: heat Lloyd iterations)", "(mesh)", "(validate)", "reconstructing: done"})
    EXPECT_NE(r5.err.find(line), std::string::npos) << line << " missing from\n" << r5.err;
  std::ifstream in5(rep5);
  const std::string json5((std::istreambuf_iterator<char>(in5)), {});
  const auto number_after = [](const std::string& text, const std::string& key) {
    const auto at = text.find("\"" + key + "\": ");
    return at == std::string::npos ? -1.0 : std::atof(text.c_str() + at + key.size() + 4);
  };
  const double used10 = number_after(json, "points_used"), used5 = number_after(json5, "points_used");
  ASSERT_GT(used10, 600 * 5);
  EXPECT_NEAR(used5 / used10, 0.5, 0.15) << used5 << " of " << used10;
}

// A room at a coarse count: the dual of 150 sites spread over walls, floor and furniture leaves
// most sites out, and the sizing stage must still bring the mesh to the count asked for (its
// rule keeps a complete mesh over a mostly missing one that is slightly better shaped).
TEST(Cloud2MeshScans, ACoarseCountOnARoomScanIsStillMet) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/pcldata_room_scan1.pcd"));
  ReconstructionOptions o;
  o.sites = 150;
  o.threads = 2;
  const ReconstructionResult r = reconstruct_surface(cloud.P, o);
  // Precondition: the dual left more than a quarter of the sites out (IsotropicRemeshOptions::count_first_error).
  ASSERT_GT(r.unused_sites, o.sites / 4);
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
  EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), o.sites, 0.02 * o.sites);
  EXPECT_GE(r.min_angle_deg, 20.0);  // IsotropicRemeshOptions::traded_min_angle_deg
}

// An RGB-D fragment of a room at 100 sites: the dual of the first start sites crosses itself
// across the scene's depth jumps, the untangling and the polish take out most of its faces, and
// the piece left is too little for the sizing to regrow (18 vertices). The CVT and the mesher run
// again from the start sites of the next seed on the same fit and Laplacian: the count is met.
TEST(Cloud2MeshScans, AMeshFarOffTheCountIsRebuiltFromOtherStartSites) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/open3d_cloud_bin_1.pcd"));
  ReconstructionOptions o;
  o.sites = 100;
  o.threads = 2;
  o.count_retries = 0;
  // The retries from other start sites alone (the run on finer sites after them has its own test,
  // CloudCoverage.APartTooThinForTheCountsCellsIsMeshedFromFinerSites).
  o.finer_retry_factor = 1;
  const ReconstructionResult once = reconstruct_surface(cloud.P, o);
  // Precondition: the first start sites give a mesh more than retry_count_error off the count.
  ASSERT_GT(std::abs(static_cast<double>(once.mesh.V.rows()) - o.sites), o.retry_count_error * o.sites);
  EXPECT_EQ(once.count_retries, 0);
  o.count_retries = ReconstructionOptions{}.count_retries;
  const ReconstructionResult r = reconstruct_surface(cloud.P, o);
  EXPECT_GE(r.count_retries, 1);
  EXPECT_NE(r.seed_used, o.seed);
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
  EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), o.sites, 0.02 * o.sites);
  EXPECT_GE(r.min_angle_deg, 25.0);
  // The retries are deterministic: the same options give the same mesh.
  const ReconstructionResult again = reconstruct_surface(cloud.P, o);
  EXPECT_TRUE(again.mesh.V == r.mesh.V && again.mesh.F == r.mesh.F);
}

// φmin of `cloud` reconstructed with `o` from `stream`, after checking the mesh valid, crossing
// nothing and within 2 % of the count.
double valid_phi_min(const char* cloud, const ReconstructionOptions& o, const StreamOptions& stream) {
  const StreamedReconstruction r = reconstruct_surface_streamed(test::data_path(cloud), o, stream);
  EXPECT_TRUE(r.result.validation.ok()) << r.result.validation.summary();
  EXPECT_EQ(r.result.validation.self_intersecting_pairs, 0);
  EXPECT_NEAR(static_cast<double>(r.result.mesh.V.rows()), o.sites, 0.02 * o.sites);
  return r.result.min_angle_deg;
}

// A room scan at 2,000 sites: the sizing's last sliver repair is undone where one of its edits
// makes faces cross, and its region frozen. Without the repair that takes, one sliver at a time,
// the best edit crossing nothing, a sliver below 25° stays; with it, every triangle reaches 25°
// and none crosses another.
TEST(Cloud2MeshScans, SliversWhoseBestRepairCrossesGetTheBestThatDoesNot) {
  double phi_min[2] = {0, 0};
  for (const bool careful : {false, true}) {
    SCOPED_TRACE(careful);
    ReconstructionOptions o;
    o.sites = 2000;
    o.threads = 2;
    o.mesher.sizing.repair_without_crossings = careful;
    o.mesher.sizing.cut_unrepairable = false;  // the repair alone: no sliver is cut out
    o.count_retries = 0;  // one run of the mesher: the retries' other start sites give other slivers
    o.stray.min_group_points = 0;  // the scan with its small groups of returns, where the sliver is
    o.stray.sparse_group_fraction = 0;
    StreamOptions raw;
    raw.max_raw_points_per_site = 0;  // the raw points (56 per site), where the repair is needed
    phi_min[careful] = valid_phi_min("clouds/pcldata_room_scan2.pcd", o, raw);
  }
  ASSERT_LT(phi_min[0], 25.0);  // precondition: a sliver is left without it
  EXPECT_GE(phi_min[1], 25.0);
}

// The stereo table scene at 1,000 sites: a strip of long faces bridges the mug's handle and the
// table, and every edit there that would raise its slivers makes faces cross. The sizing cuts
// the slivers no edit could raise out of the open piece: φmin ≥ 25°, the count within 2 %.
TEST(Cloud2MeshScans, SliversNoEditCanRaiseAreCutFromOpenPieces) {
  double phi_min[2] = {0, 0};
  for (const bool cut : {false, true}) {
    SCOPED_TRACE(cut);
    ReconstructionOptions o;
    o.sites = 1000;
    o.threads = 2;
    o.mesher.sizing.cut_unrepairable = cut;
    o.stray.min_group_points = 0;  // the scan with its small groups of returns, where the strip is
    o.stray.sparse_group_fraction = 0;
    StreamOptions as_read;  // the file's depth steps as they are (their refit flattens the strip away)
    as_read.depth_steps.max_distinct_fraction = 0;
    phi_min[cut] = valid_phi_min("clouds/pcl_table_scene_mug_stereo_textured.pcd", o, as_read);
  }
  ASSERT_LT(phi_min[0], 25.0);  // precondition: slivers are left without the cut
  EXPECT_GE(phi_min[1], 25.0);
}

// A cloud far sparser than -n asks for (min_cut at 5,000 sites: 1.9 points per site): the
// sizing rebuilds most of the mesh, and the faces it leaves crossing are untangled after it. The
// border is drawn in by the relaxation (follow_sample_border off): the mesh the sizing gets then
// makes it leave crossing faces (the slivers among them are not cut: cut_unrepairable off).
TEST(Cloud2MeshScans, FacesTheSizingLeavesCrossingAreUntangled) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/pcldata_min_cut_segmentation_tutorial.pcd"));
  ReconstructionOptions o;
  o.sites = 5000;
  o.threads = 2;
  o.mesher.polish.follow_sample_border = false;
  o.mesher.sizing.cut_unrepairable = false;
  const ReconstructionResult r = reconstruct_surface(cloud.P, o);
  ASSERT_GT(r.crossing_after_sizing, 0);  // precondition: the sized mesh crossed itself
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
  EXPECT_EQ(r.validation.self_intersecting_pairs, 0);
  EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), o.sites, 0.02 * o.sites);
}

// A room scan at 10,000 sites (5.6 points per site): the sizing leaves faces crossing, and
// untangle() refills the holes they leave with fans that hold slivers, with no polish after
// them. The repair that follows (SurfaceMesherOptions::repair_after_untangle) gives each of those
// slivers the best of its local edits that makes no faces cross: φmin rises, the mesh stays
// valid, crosses nothing and keeps the count.
TEST(Cloud2MeshScans, SliversOfTheRefillAfterTheSizingAreRepaired) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/pcldata_room_scan1.pcd"));
  double phi_min[2] = {0, 0};
  for (const bool repair : {false, true}) {
    SCOPED_TRACE(repair);
    ReconstructionOptions o;
    o.sites = 10000;
    o.threads = 2;
    o.mesher.repair_after_untangle = repair;
    o.count_retries = 0;  // one run of the mesher: the retries' other start sites give other crossings
    const ReconstructionResult r = reconstruct_surface(cloud.P, o);
    ASSERT_GT(r.crossing_after_sizing, 0);  // precondition: the sized mesh crossed itself
    EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
    EXPECT_EQ(r.validation.self_intersecting_pairs, 0);
    EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), o.sites, 0.02 * o.sites);
    phi_min[repair] = r.min_angle_deg;
  }
  ASSERT_LT(phi_min[0], 25.0);  // precondition: the refill left slivers
  EXPECT_GT(phi_min[1], phi_min[0] + 5.0);
}

// A building scan (CGAL's poste_france.xyz, 9,031 points) with small groups of returns tens of
// metres from it: two scatters of about 30 points spread over metres and two dense groups of
// 26 and 28 points. Kept, the scatters get sites in proportion to the area they seem to cover,
// and the dense groups' 30-point neighbourhoods reach across the gap to the building, so the
// Laplacian, the dual and the sizing bridge it: vertices land metres off the data. Dropped as
// stray (StrayPointOptions::min_group_points, sparse_group_fraction), every vertex lies on the
// building, within one site spacing of a point.
TEST(Cloud2MeshScans, SmallAndSparseGroupsOfReturnsGetNoSites) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/poste_france.xyz"));
  const PointIndex index(cloud.P);
  double farthest[2] = {0, 0};
  int stray[2] = {0, 0};
  Eigen::Index vertices[2] = {0, 0};
  for (const bool rules : {false, true}) {
    SCOPED_TRACE(rules);
    ReconstructionOptions o;
    o.sites = 500;
    o.threads = 2;
    if (!rules) o.stray.min_group_points = 0, o.stray.sparse_group_fraction = 0;
    const ReconstructionResult r = reconstruct_surface(cloud.P, o);
    EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
    const double spacing = mean_edge_length(r.mesh);
    for (Eigen::Index v = 0; v < r.mesh.V.rows(); ++v) {
      double d = 0;
      index.nearest(r.mesh.V.row(v).transpose(), d);
      farthest[rules] = std::max(farthest[rules], d / spacing);
    }
    stray[rules] = r.points_stray;
    vertices[rules] = r.mesh.V.rows();
  }
  ASSERT_GT(farthest[0], 5.0);  // precondition: kept, the groups pull vertices off the data
  EXPECT_LT(farthest[1], 1.0);
  EXPECT_GE(stray[1] - stray[0], 26 + 28 + 2 * 29);  // the four groups, at least
  EXPECT_NEAR(static_cast<double>(vertices[1]), 500, 0.02 * 500);
}
