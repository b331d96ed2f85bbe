// Point-cloud input: every shared cloud (PCD ascii/binary/binary_compressed, organised clouds with
// NaN, PLY with/without normals, XYZ/PWN text), clean-up semantics, normalisation frames on UTM
// coordinates, and each class of bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace heatcvt;

namespace {

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("heatcvt_cloud_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

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

template <typename E, typename Fn>
void expect_error(Fn&& fn, const std::string& path, const std::string& problem) {
  try {
    fn();
    ADD_FAILURE() << "no exception for " << path << " (expected '" << problem << "')";
  } catch (const E& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
  }
}

// Number of distinct rows.
size_t distinct_rows(const Eigen::MatrixX3d& P) {
  std::set<std::tuple<double, double, double>> s;
  for (Eigen::Index i = 0; i < P.rows(); ++i) s.emplace(P(i, 0), P(i, 1), P(i, 2));
  return s.size();
}

}  // namespace

struct CloudFacts {
  const char* file;
  long points;    // SOURCES.md
  bool normals;   // SOURCES.md: "normals" attribute (blobby: all zero => absent)
  long finite;    // SOURCES.md where stated, -1 otherwise
  bool organized; // 640x480
};

TEST(CloudIO, ReadsEverySharedCloudWithTheDocumentedCounts) {
  const CloudFacts facts[] = {
      {"b9.ply", 22300, false, -1, false},
      {"blobby.xyz", 3288, false, -1, false},
      {"building.xyz", 8075, true, -1, false},
      {"cube.pwn", 50000, true, -1, false},
      {"elephant.pwn", 10000, true, -1, false},
      {"fin90_with_PCA_normals.xyz", 757, true, -1, false},
      {"hippo1.ply", 6104, true, -1, false},
      {"hippo2.ply", 4387, true, -1, false},
      {"kitten.xyz", 5210, true, -1, false},
      {"oni.pwn", 1435, true, -1, false},
      {"open3d_cloud_bin_0.pcd", 3903, true, -1, false},
      {"open3d_cloud_bin_1.pcd", 3458, true, -1, false},
      {"pcl_bun0.pcd", 397, true, -1, false},
      {"pcl_bun4.pcd", 361, false, -1, false},
      {"pcl_bunny.pcd", 397, false, -1, false},
      {"pcl_car6.pcd", 10031, false, -1, false},
      {"pcl_cturtle.pcd", 167198, false, -1, false},
      {"pcl_five_people.pcd", 307200, false, 239075, true},
      {"pcl_milk.pcd", 13704, false, -1, false},
      {"pcl_milk_color.pcd", 13704, false, -1, false},
      {"pcl_noisy_slice_displaced.pcd", 3782, false, -1, false},
      {"pcl_office1.pcd", 307200, false, 254456, true},
      {"pcl_rs1.pcd", 289541, false, -1, false},
      {"pcl_sac_plane_test.pcd", 3283, true, -1, false},
      {"pcl_table_scene_mug_stereo_textured.pcd", 307200, false, 209280, true},
      {"pcldata_biwi_face_model.pcd", 100000, false, -1, false},
      {"pcldata_capture0001.pcd", 307200, false, -1, true},
      {"pcldata_capture0002.pcd", 307200, false, -1, true},
      {"pcldata_milk_cartoon_all_small_clorox.pcd", 307200, false, -1, true},
      {"pcldata_min_cut_segmentation_tutorial.pcd", 9311, false, -1, false},
      {"pcldata_region_growing_tutorial.pcd", 108104, false, -1, false},
      {"pcldata_room_scan1.pcd", 112586, false, -1, false},
      {"pcldata_room_scan2.pcd", 112624, false, -1, false},
      {"pcldata_rops_points.pcd", 32087, false, -1, false},
      {"pcldata_terrain_CSite1_red2-utm.pcd", 131622, false, -1, false},
      {"pcldata_terrain_samp11-utm-ground.pcd", 21786, false, -1, false},
      {"pcldata_terrain_samp11-utm.pcd", 38010, false, -1, false},
      {"poste_france.xyz", 9031, false, -1, false},
      {"sphere.pwn", 10242, true, -1, false},
      {"sphere926.pwn", 926, true, -1, false},
      {"sphere_20k.xyz", 21000, false, -1, false},
      {"sphere_20k_normal.xyz", 21000, true, -1, false}};
  int files = 0;
  for (const auto& fact : facts) {
    SCOPED_TRACE(fact.file);
    CloudReadReport rep;
    const PointCloud c = read_cloud(test::data_path(std::string("clouds/") + fact.file), &rep);
    ++files;
    EXPECT_EQ(rep.points_in_file, fact.points);
    EXPECT_EQ(rep.has_normals, fact.normals);
    EXPECT_EQ(c.has_normals(), fact.normals);
    if (fact.finite >= 0) EXPECT_EQ(rep.points_in_file - rep.non_finite_dropped, fact.finite);
    if (!fact.organized) EXPECT_EQ(rep.non_finite_dropped, 0);
    EXPECT_EQ(rep.height, fact.organized ? 480 : 1);
    EXPECT_EQ(rep.width, fact.organized ? 640 : fact.points);
    // Organised frames also lose their flying pixels (flying_pixels.h), unorganised clouds none.
    if (!fact.organized) EXPECT_EQ(rep.flying_pixels_removed, 0);
    EXPECT_EQ(c.P.rows(), rep.points_in_file - rep.non_finite_dropped - rep.flying_pixels_removed - rep.duplicates_merged);
    EXPECT_TRUE(c.P.allFinite());
    EXPECT_EQ(distinct_rows(c.P), static_cast<size_t>(c.P.rows()));  // duplicates really merged
    if (c.has_normals()) {
      EXPECT_TRUE(c.N.allFinite());
      // Normals in these files are unit vectors (up to the file's rounding), except where zeroed
      // and a handful of outliers (hippo2.ply has 2 non-unit normals).
      long unit = 0;
      for (Eigen::Index i = 0; i < c.N.rows(); ++i) unit += std::abs(c.N.row(i).norm() - 1.0) < 1e-3;
      EXPECT_GE(unit + rep.invalid_normals_zeroed, c.N.rows() - 2);
    }
  }
  EXPECT_EQ(files, 42);
}

TEST(CloudIO, FormatsAreRecognised) {
  const std::pair<const char*, const char*> cases[] = {{"pcl_bunny.pcd", "pcd-ascii"},
                                                       {"pcldata_biwi_face_model.pcd", "pcd-binary"},
                                                       {"pcl_five_people.pcd", "pcd-binary_compressed"},
                                                       {"b9.ply", "ply-ascii"},
                                                       {"hippo1.ply", "ply-binary_little_endian"},
                                                       {"kitten.xyz", "xyz"},
                                                       {"oni.pwn", "xyz"}};
  for (const auto& [file, format] : cases) {
    CloudReadReport rep;
    read_cloud(test::data_path(std::string("clouds/") + file), &rep);
    EXPECT_EQ(rep.format, format) << file;
  }
}

TEST(CloudIO, BlobbyZeroNormalsAreTreatedAsAbsent) {
  CloudReadReport rep;
  const PointCloud c = read_cloud(test::data_path("clouds/blobby.xyz"), &rep);
  EXPECT_TRUE(rep.normals_all_zero);
  EXPECT_FALSE(rep.has_normals);
  EXPECT_EQ(c.N.rows(), 0);
  EXPECT_EQ(c.P.rows(), 3288);
}

TEST(CloudIO, SameDataInDifferentFormatsAgrees) {
  // pcl_bunny.pcd and pcl_bun0.pcd store the same 397 points (bun0 adds normals) with different
  // decimal rounding of the same float32 values.
  const PointCloud a = read_cloud(test::data_path("clouds/pcl_bunny.pcd"));
  const PointCloud b = read_cloud(test::data_path("clouds/pcl_bun0.pcd"));
  ASSERT_EQ(a.P.rows(), b.P.rows());
  for (Eigen::Index i = 0; i < a.P.rows(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(static_cast<float>(a.P(i, k)), static_cast<float>(b.P(i, k)));
  // sphere.pwn is a unit sphere whose normals equal the positions; sphere926 has radius 10.
  const PointCloud s = read_cloud(test::data_path("clouds/sphere.pwn"));
  EXPECT_LT((s.P - s.N).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT((s.P.rowwise().norm().array() - 1.0).abs().maxCoeff(), 1e-4);
  const PointCloud s10 = read_cloud(test::data_path("clouds/sphere926.pwn"));
  EXPECT_LT((s10.P.rowwise().norm().array() - 10.0).abs().maxCoeff(), 1e-4);
  EXPECT_GT((s10.P.rowwise().normalized().array() * s10.N.array()).rowwise().sum().minCoeff(), 0.999);  // radial normals
  // A PLY cloud written as XYZ reads back identically (normals included).
  TempDir tmp;
  const PointCloud h = read_cloud(test::data_path("clouds/hippo1.ply"));
  write_cloud_xyz(tmp.path("hippo.xyz"), h);
  const PointCloud h2 = read_cloud(tmp.path("hippo.xyz"));
  EXPECT_EQ(h2.P, h.P);
  EXPECT_EQ(h2.N, h.N);
}

TEST(CloudIO, CleanUpDropsNonFiniteAndKeepsFirstDuplicate) {
  TempDir tmp;
  const std::string p = tmp.path("dups.txt");
  write_text(p,
             "# header comment\n5\n"
             "1 2 3 0 0 1 7 7\n"
             "nan 0 0 1 0 0\n"
             "4 5 6 0 1 0\n"
             "1 2 3 1 0 0\n"      // duplicate of the first point, different normal
             "0 0 inf 0 0 1\n"
             "-0 5 1 nan 0 0\n"   // finite point, NaN normal
             "4 5 6 0 0 -1\n");
  CloudReadReport rep;
  const PointCloud c = read_cloud(p, &rep);
  EXPECT_EQ(rep.points_in_file, 7);
  EXPECT_EQ(rep.non_finite_dropped, 2);
  EXPECT_EQ(rep.duplicates_merged, 2);
  EXPECT_EQ(rep.invalid_normals_zeroed, 1);
  ASSERT_EQ(c.P.rows(), 3);
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.P.row(0), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(c.N.row(0), Eigen::RowVector3d(0, 0, 1));  // first occurrence kept
  EXPECT_EQ(c.P.row(1), Eigen::RowVector3d(4, 5, 6));
  EXPECT_EQ(c.N.row(1), Eigen::RowVector3d(0, 1, 0));
  EXPECT_EQ(c.P.row(2), Eigen::RowVector3d(0, 5, 1));
  EXPECT_EQ(c.N.row(2), Eigen::RowVector3d(0, 0, 0));
  // Mixed column counts: normals only when every line has them.
  write_text(p, "0 0 0 1 0 0\n1 0 0\n");
  EXPECT_FALSE(read_cloud(p).has_normals());
}

TEST(CloudIO, NormalizeAndRestorePreserveUtmCoordinates) {
  CloudReadReport rep;
  PointCloud c = read_cloud(test::data_path("clouds/pcldata_terrain_samp11-utm.pcd"), &rep);
  const Eigen::MatrixX3d original = c.P;
  ASSERT_GT(original.col(1).cwiseAbs().maxCoeff(), 1e6);  // UTM northing: a large offset
  // The file holds float32 values: every coordinate read is exactly a float.
  for (Eigen::Index i = 0; i < original.rows(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(static_cast<double>(static_cast<float>(original(i, k))), original(i, k));
  const CloudFrame frame = normalize_cloud(c);
  const Eigen::RowVector3d lo = c.P.colwise().minCoeff(), hi = c.P.colwise().maxCoeff();
  EXPECT_NEAR((hi - lo).norm(), 1.0, 1e-12);
  EXPECT_LT((lo + hi).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(frame.centre.y(), 1e6);
  // Distinct file points stay distinct after normalisation (no precision collapse).
  EXPECT_EQ(distinct_rows(c.P), static_cast<size_t>(c.P.rows()));
  Eigen::MatrixX3d back = c.P;
  restore_frame(back, frame);
  // Far below the file's float32 spacing at 5e6 (0.5): rounding back to float gives the file values.
  EXPECT_LT((back - original).cwiseAbs().maxCoeff(), 1e-8);
  for (Eigen::Index i = 0; i < back.rows(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(static_cast<float>(back(i, k)), static_cast<float>(original(i, k)));
  // apply_frame is the same map as normalize_cloud.
  Eigen::MatrixX3d again = original;
  apply_frame(again, frame);
  EXPECT_EQ(again, c.P);
  // Degenerate frames.
  Eigen::MatrixX3d one(1, 3);
  one << 5e6, 1, 2;
  EXPECT_EQ(bounding_box_frame(one).scale, 1.0);
  EXPECT_THROW(bounding_box_frame(Eigen::MatrixX3d()), InvalidInputError);
}

TEST(CloudIO, MissingUnknownEmptyAndMalformed) {
  TempDir tmp;
  expect_error<IOError>([&] { read_cloud(tmp.path("none.pcd")); }, tmp.path("none.pcd"), "does not exist");
  write_text(tmp.path("c.las"), "x");
  expect_error<IOError>([&] { read_cloud(tmp.path("c.las")); }, tmp.path("c.las"), "unknown point-cloud format");
  write_text(tmp.path("empty.xyz"), "");
  expect_error<IOError>([&] { read_cloud(tmp.path("empty.xyz")); }, tmp.path("empty.xyz"), "empty");
  write_text(tmp.path("blank.xyz"), "\n# only a comment\n\n");
  expect_error<InvalidInputError>([&] { read_cloud(tmp.path("blank.xyz")); }, tmp.path("blank.xyz"), "no points");
  write_text(tmp.path("bad.xyz"), "0 0 0\n1 0 O\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("bad.xyz")); }, tmp.path("bad.xyz"), "line 2: malformed number");
  write_text(tmp.path("short.pwn"), "0 0 0\n1 0\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("short.pwn")); }, tmp.path("short.pwn"), "at least 3 numbers");
  write_text(tmp.path("nan.xyz"), "nan nan nan\ninf 0 0\n0 -inf 0\n");
  expect_error<InvalidInputError>([&] { read_cloud(tmp.path("nan.xyz")); }, tmp.path("nan.xyz"), "no finite points");
  write_text(tmp.path("nan.pcd"),
             "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
             "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\nnan nan nan\nnan nan nan\n");
  expect_error<InvalidInputError>([&] { read_cloud(tmp.path("nan.pcd")); }, tmp.path("nan.pcd"), "no finite points");
  write_text(tmp.path("noxyz.pcd"),
             "VERSION 0.7\nFIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("noxyz.pcd")); }, tmp.path("noxyz.pcd"), "no 'x' field");
  write_text(tmp.path("garbage.pcd"), "this is not a point cloud\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("garbage.pcd")); }, tmp.path("garbage.pcd"), "not a PCD file");
  write_text(tmp.path("huge.pcd"),
             "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\nHEIGHT 1\n"
             "POINTS 2000000000\nDATA binary\n0123456789ab");
  expect_error<IOError>([&] { read_cloud(tmp.path("huge.pcd")); }, tmp.path("huge.pcd"), "truncated");
  // An ascii PLY whose header declares fewer vertices than the file holds is refused, not read in
  // part; trailing blank lines are fine.
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n";
  write_text(tmp.path("more.ply"), header + "0 0 0\n1 0 0\n0 1 0\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("more.ply")); }, tmp.path("more.ply"), "more values than the header");
  write_text(tmp.path("count.ply"), "ply\nformat ascii 1.0\nelement vertex 2147483647\nproperty float x\n"
                                    "property float y\nproperty float z\nend_header\n0 0 0\n");
  expect_error<IOError>([&] { read_cloud(tmp.path("count.ply")); }, tmp.path("count.ply"),
                        "element 'vertex' count 2147483647 is out of range");
  write_text(tmp.path("blank_tail.ply"), header + "0 0 0\n1 0 0\n\n  \n");
  EXPECT_EQ(read_cloud(tmp.path("blank_tail.ply")).P.rows(), 2);
}

TEST(CloudIO, TruncatedFilesAreReported) {
  TempDir tmp;
  for (const char* name : {"pcl_five_people.pcd", "pcldata_biwi_face_model.pcd", "open3d_cloud_bin_0.pcd",
                           "pcl_car6.pcd", "hippo1.ply", "b9.ply"}) {
    SCOPED_TRACE(name);
    const std::string bytes = read_bytes(test::data_path(std::string("clouds/") + name));
    const std::string p = tmp.path(std::string("half_") + name);
    write_text(p, bytes.substr(0, bytes.size() / 2));
    expect_error<IOError>([&] { read_cloud(p); }, p, "truncated");
  }
}

// Damaged PCD/PLY/XYZ files end in a heatcvt::Error or a valid cloud, never a crash.
TEST(CloudIO, FuzzedFilesNeverCrash) {
  TempDir tmp;
  std::mt19937 rng(2024);
  int errors = 0, successes = 0;
  for (const char* name : {"pcl_car6.pcd", "open3d_cloud_bin_0.pcd", "pcl_bun4.pcd", "hippo2.ply", "oni.pwn"}) {
    const std::string original = read_bytes(test::data_path(std::string("clouds/") + name));
    const std::string ext = fs::path(name).extension().string();
    for (int trial = 0; trial < 40; ++trial) {
      std::string bytes = original;
      if (trial % 2 == 0) {
        const int flips = 1 + static_cast<int>(rng() % 6);
        for (int k = 0; k < flips; ++k) {
          const size_t limit = (rng() % 2) ? std::min<size_t>(bytes.size(), 300) : bytes.size();
          bytes[rng() % limit] = static_cast<char>(rng() % 256);
        }
      } else {
        bytes.resize(rng() % bytes.size());
      }
      const std::string p = tmp.path("fuzz" + ext);
      write_text(p, bytes);
      try {
        const PointCloud c = read_cloud(p);
        EXPECT_TRUE(c.P.allFinite());
        EXPECT_GT(c.P.rows(), 0);
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
