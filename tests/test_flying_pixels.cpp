// Flying pixels of organised clouds (flying_pixels.h): the rule on a depth frame built in code,
// the streamed filter against the whole-grid rule for any chunk size, read_cloud on organised
// and unorganised PCD files, and cloud2mesh on a frame whose edges fly (no curtain in the mesh).
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/flying_pixels.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/pcl/heat_cvt_reconstruction.h"
#include "heatcvt/reconstruct.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A depth frame of a pinhole camera at `eye` looking along +z (W × H pixels, 60° wide): a sphere
// of radius 0.3 at distance 1.5 in front of a wall at z = 2.2 + 0.8 x that turns away from the
// camera (seen at 39–69° from head-on). Every second pixel on the sphere's left or right
// silhouette (a horizontal neighbour on the wall) takes a depth between the two surfaces, as a
// time-of-flight camera mixes them. `flying` lists those pixels.
struct Frame {
  int width = 0, height = 0;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::MatrixX3d P;
  std::vector<int> flying;
  std::vector<char> silhouette;  // sphere pixels with a wall pixel among their 8 neighbours
};

double hit_depth(const Eigen::Vector3d& d, bool& on_sphere) {
  const Eigen::Vector3d c(0, 0, 1.5);
  const double b = d.dot(c), disc = b * b - (c.squaredNorm() - 0.09);
  on_sphere = disc > 0;
  if (on_sphere) return b - std::sqrt(disc);
  // Wall z = 2.2 + 0.8 x, through the ray's parameter t: t dz = 2.2 + 0.8 t dx.
  return 2.2 / (d.z() - 0.8 * d.x());
}

Frame depth_frame(int width, int height, const Eigen::Vector3d& eye) {
  Frame f;
  f.width = width, f.height = height, f.eye = eye;
  f.P.resize(static_cast<Eigen::Index>(width) * height, 3);
  const double focal = 0.5 * width / std::tan(M_PI / 6);
  std::vector<double> t(static_cast<size_t>(width) * height);
  std::vector<char> sphere(t.size());
  std::vector<Eigen::Vector3d> dir(t.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      dir[i] = Eigen::Vector3d((x + 0.5 - 0.5 * width) / focal, (y + 0.5 - 0.5 * height) / focal, 1).normalized();
      bool s = false;
      t[i] = hit_depth(dir[i], s);
      sphere[i] = s;
    }
  f.silhouette.assign(t.size(), 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          const size_t i = static_cast<size_t>(y) * width + x, j = static_cast<size_t>(yy) * width + xx;
          if (xx >= 0 && yy >= 0 && xx < width && yy < height && sphere[i] && !sphere[j]) f.silhouette[i] = 1;
        }
  int edge = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      double depth = t[i];
      const bool left = x > 0 && !sphere[i - 1], right = x + 1 < width && !sphere[i + 1];
      if (sphere[i] && (left || right) && edge++ % 2 == 0) {
        const double other = left ? t[i - 1] : t[i + 1], mix = 0.25 + 0.5 * ((edge * 37) % 11) / 10.0;
        depth = (1 - mix) * depth + mix * other;
        f.flying.push_back(static_cast<int>(i));
      }
      f.P.row(static_cast<Eigen::Index>(i)) = (eye + depth * dir[i]).transpose();
    }
  return f;
}

// Every mixed pixel is marked; the other marks are pixels of the sphere's silhouette whose other
// neighbours are mixed, missing or on the wall (its tips, a pixel or two wide), at most 5 % of it.
void expect_mixed_pixels_marked(const std::vector<char>& mask, const Frame& f) {
  for (int i : f.flying) EXPECT_TRUE(mask[i]) << "mixed pixel " << i << " not marked";
  int extra = 0;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i] && !std::binary_search(f.flying.begin(), f.flying.end(), static_cast<int>(i))) {
      EXPECT_TRUE(f.silhouette[i]) << "pixel " << i << " marked off the silhouette";
      ++extra;
    }
  EXPECT_LE(extra, std::count(f.silhouette.begin(), f.silhouette.end(), 1) / 20);
}

std::vector<int> marked(const std::vector<char>& mask) {
  std::vector<int> out;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) out.push_back(static_cast<int>(i));
  return out;
}

// An organised cloud in memory, handed out in chunks of `chunk` points (with colours).
class GridSource : public CloudChunkSource {
 public:
  GridSource(const Eigen::MatrixX3d& P, Eigen::Index chunk) : P_(P), chunk_(chunk) {}
  bool next(CloudChunk& c) override {
    const Eigen::Index n = std::min(chunk_, P_.rows() - at_);
    c = CloudChunk{};
    if (n <= 0) return false;
    c.P = P_.middleRows(at_, n);
    c.C.resize(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) c.C.row(i).setConstant(static_cast<double>((at_ + i) % 256) / 255.0);
    at_ += n;
    return true;
  }
  void rewind() override { at_ = 0; }
  const std::string& name() const override { return name_; }

 private:
  const Eigen::MatrixX3d& P_;
  Eigen::Index chunk_, at_ = 0;
  std::string name_ = "grid";
};

void write_pcd(const std::string& path, const Eigen::MatrixX3d& P, int width, int height, const Eigen::Vector3d& eye) {
  std::ofstream s(path);
  s.precision(9);
  s << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << width << "\nHEIGHT " << height
    << "\nVIEWPOINT " << eye.x() << " " << eye.y() << " " << eye.z() << " 1 0 0 0\nPOINTS " << P.rows()
    << "\nDATA ascii\n";
  for (Eigen::Index i = 0; i < P.rows(); ++i) s << P(i, 0) << " " << P(i, 1) << " " << P(i, 2) << "\n";
}

}  // namespace

TEST(FlyingPixels, MarksThePixelsMixedAcrossAnEdgeAndNoOther) {
  const Frame f = depth_frame(160, 120, Eigen::Vector3d::Zero());
  ASSERT_GT(f.flying.size(), 20u);  // the frame has an edge with mixed pixels
  expect_mixed_pixels_marked(flying_pixel_mask(f.P, f.width, f.height, f.eye), f);
  // The wall turned up to 69° away and the sphere keep every pixel but a few silhouette tips.
  Frame clean = f;
  for (int i : f.flying) clean.P.row(i).setConstant(kNaN);
  clean.flying.clear();
  expect_mixed_pixels_marked(flying_pixel_mask(clean.P, f.width, f.height, f.eye), clean);
  // Off, or an unorganised cloud: nothing.
  FlyingPixelOptions off;
  off.neighbour_distance_ratio = 0;
  EXPECT_TRUE(marked(flying_pixel_mask(f.P, f.width, f.height, f.eye, off)).empty());
  EXPECT_TRUE(marked(flying_pixel_mask(f.P, static_cast<int>(f.P.rows()), 1, f.eye)).empty());
  EXPECT_THROW(flying_pixel_mask(f.P, f.width + 1, f.height, f.eye), InvalidInputError);
}

TEST(FlyingPixels, RangesAreMeasuredFromTheSensor) {
  // The same frame taken from (5, -3, 2), the sensor position given: the same pixels.
  const Eigen::Vector3d eye(5, -3, 2);
  const Frame f = depth_frame(160, 120, eye);
  const std::vector<char> mask = flying_pixel_mask(f.P, f.width, f.height, eye);
  expect_mixed_pixels_marked(mask, f);
  EXPECT_EQ(marked(mask), marked(flying_pixel_mask(depth_frame(160, 120, Eigen::Vector3d::Zero()).P, f.width, f.height,
                                                   Eigen::Vector3d::Zero())));
  Eigen::MatrixX3d P = f.P;
  EXPECT_EQ(remove_flying_pixels(P, f.width, f.height, eye), static_cast<std::int64_t>(marked(mask).size()));
  for (int i : marked(mask)) EXPECT_FALSE(P.row(i).allFinite());
}

TEST(FlyingPixels, TheStreamedFilterGivesTheSamePointsForAnyChunkSize) {
  Frame f = depth_frame(160, 120, Eigen::Vector3d::Zero());
  for (int i = 0; i < f.width; i += 5) f.P.row(20 * f.width + i).setConstant(kNaN);  // dropouts
  Eigen::MatrixX3d expected = f.P;
  const std::int64_t removed = remove_flying_pixels(expected, f.width, f.height, f.eye);
  ASSERT_GT(removed, 0);
  for (const Eigen::Index chunk : {Eigen::Index(1), Eigen::Index(7), Eigen::Index(160), Eigen::Index(250), Eigen::Index(50000)}) {
    GridSource grid(f.P, chunk);
    FlyingPixelFilter filter(grid, f.width, f.height, f.eye);
    for (int pass = 0; pass < 2; ++pass) {  // and again after rewind()
      if (pass) filter.rewind();
      Eigen::Index at = 0;
      CloudChunk c;
      while (filter.next(c)) {
        ASSERT_EQ(c.C.rows(), c.P.rows());
        for (Eigen::Index i = 0; i < c.rows(); ++i, ++at) {
          ASSERT_LT(at, expected.rows());
          EXPECT_EQ(c.P.row(i).allFinite(), expected.row(at).allFinite()) << "chunk " << chunk << " point " << at;
          if (expected.row(at).allFinite()) EXPECT_EQ(c.P.row(i), expected.row(at));
          EXPECT_DOUBLE_EQ(c.C(i, 0), static_cast<double>(at % 256) / 255.0);  // colours stay with their points
        }
      }
      EXPECT_EQ(at, expected.rows()) << "chunk " << chunk;
      EXPECT_EQ(filter.removed(), removed) << "chunk " << chunk;
    }
  }
}

TEST(FlyingPixels, ReadCloudDropsThemFromOrganisedPcdFilesOnly) {
  test::ScratchDir dir("flying");
  const Eigen::Vector3d eye(0.5, 0.25, -1);
  const Frame f = depth_frame(160, 120, eye);
  write_pcd(dir.path("organised.pcd"), f.P, f.width, f.height, eye);
  CloudReadReport rep;
  const PointCloud c = read_cloud(dir.path("organised.pcd"), &rep);
  const long marks = static_cast<long>(marked(flying_pixel_mask(f.P, f.width, f.height, eye)).size());
  EXPECT_GE(marks, static_cast<long>(f.flying.size()));
  EXPECT_EQ(rep.flying_pixels_removed, marks);
  EXPECT_EQ(rep.non_finite_dropped, 0);
  EXPECT_EQ(c.P.rows(), f.P.rows() - marks);
  // The same points as one row: no grid, nothing dropped.
  write_pcd(dir.path("row.pcd"), f.P, static_cast<int>(f.P.rows()), 1, eye);
  const PointCloud r = read_cloud(dir.path("row.pcd"), &rep);
  EXPECT_EQ(rep.flying_pixels_removed, 0);
  EXPECT_EQ(r.P.rows(), f.P.rows());
  // Turned off.
  CloudReadOptions keep;
  keep.flying_pixels.neighbour_distance_ratio = 0;
  EXPECT_EQ(read_cloud(dir.path("organised.pcd"), &rep, keep).P.rows(), f.P.rows());
}

// A 50 × 50 organised cloud whose pixel k (row-major) lies at range 1.035^k from the sensor
// (within float range): every grid neighbour is farther than 3.3 % of the range, beyond the
// rule's 3 %, so the rule removes every pixel. The error says so (not "NaN/inf"), and with the
// rule off every point is read.
TEST(FlyingPixels, ACloudWhoseEveryPixelIsFlyingIsNamedAsSuch) {
  test::ScratchDir dir("flying");
  const Eigen::Vector3d eye(0, 0, -5);
  Eigen::MatrixX3d P(2500, 3);
  for (int k = 0; k < 2500; ++k) {
    const Eigen::Vector3d ray = Eigen::Vector3d((k % 50 - 24.5) / 50, (k / 50 - 24.5) / 50, 1).normalized();
    P.row(k) = (eye + std::pow(1.035, k) * ray).transpose();
  }
  const std::string path = dir.path("scattered.pcd");
  write_pcd(path, P, 50, 50, eye);
  CloudReadReport rep;
  try {
    read_cloud(path, &rep);
    ADD_FAILURE() << "read_cloud must refuse a cloud with no point left";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ": no point left"), std::string::npos) << what;
    EXPECT_NE(what.find("the flying-pixel rule removed the 2500 others"), std::string::npos) << what;
    EXPECT_EQ(what.find("are NaN/inf)"), std::string::npos) << what;
  }
  CloudReadOptions keep;
  keep.flying_pixels.neighbour_distance_ratio = 0;
  EXPECT_EQ(read_cloud(path, &rep, keep).P.rows(), 2500);
}

TEST(FlyingPixels, RealDepthFramesLoseFewPixelsAndTheStreamMatchesReadCloud) {
  // The organised Kinect frames of the shared data (structured light: an edge pixel gets no
  // depth rather than a mixed one) lose less than 0.1 % of their pixels, and the filtered stream
  // gives read_cloud's points.
  int frames = 0;
  for (const char* name : {"pcldata_capture0001.pcd", "pcl_five_people.pcd", "pcl_office1.pcd",
                           "pcl_table_scene_mug_stereo_textured.pcd"}) {
    SCOPED_TRACE(name);
    const std::string path = test::data_path(std::string("clouds/") + name);
    CloudReadReport rep;
    CloudReadOptions unrefitted;  // the stream below hands out the depth as the file has it
    unrefitted.depth_steps.max_distinct_fraction = 0;
    const PointCloud whole = read_cloud(path, &rep, unrefitted);
    ASSERT_GT(rep.height, 1);
    ++frames;
    EXPECT_LT(rep.flying_pixels_removed, 0.001 * static_cast<double>(whole.P.rows()));
    CloudChunkReader reader(path);
    FlyingPixelFilter filter(reader, static_cast<int>(reader.grid_width()), static_cast<int>(reader.grid_height()),
                             reader.sensor_origin());
    PointCloud streamed;
    std::vector<Eigen::RowVector3d> rows;
    CloudChunk c;
    while (filter.next(c))
      for (Eigen::Index i = 0; i < c.rows(); ++i) rows.push_back(c.P.row(i));
    streamed.P.resize(static_cast<Eigen::Index>(rows.size()), 3);
    for (size_t i = 0; i < rows.size(); ++i) streamed.P.row(static_cast<Eigen::Index>(i)) = rows[i];
    clean_cloud(streamed);
    EXPECT_EQ(filter.removed(), rep.flying_pixels_removed);
    EXPECT_TRUE(streamed.P == whole.P);
  }
  EXPECT_EQ(frames, 4);
}

// Largest distance from the mesh's vertices to the scene (sphere and wall) of depth_frame.
double farthest_from_scene(const TriangleMesh& m) {
  double worst = 0;
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
    const Eigen::Vector3d p = m.V.row(v);
    const double sphere = std::abs((p - Eigen::Vector3d(0, 0, 1.5)).norm() - 0.3);
    const double wall = std::abs(p.z() - 2.2 - 0.8 * p.x()) / std::sqrt(1.64);
    worst = std::max(worst, std::min(sphere, wall));
  }
  return worst;
}

TEST(FlyingPixels, Cloud2meshMakesNoCurtainFromADepthFrameWithMixedEdges) {
  test::ScratchDir dir("flying_tool");
  const Frame f = depth_frame(160, 120, Eigen::Vector3d::Zero());
  write_pcd(dir.path("frame.pcd"), f.P, f.width, f.height, f.eye);
  // Site spacing of 500 sites over the frame's surfaces is about 0.06; a vertex on the curtain
  // between sphere and wall (0.4 deep) lies farther than half of it from both.
  const double bound = 0.03;
  auto run = [&](const std::string& extra, const std::string& out) {
    const auto r = test::run_tool("cloud2mesh", dir.path("frame.pcd") + " -n 500 -q -o " + dir.path(out) + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_mesh(dir.path(out));
  };
  // The precondition: kept, the mixed pixels make a curtain.
  EXPECT_GT(farthest_from_scene(run(" --flying-pixels 0", "kept.ply")), bound);
  EXPECT_LT(farthest_from_scene(run("", "filtered.ply")), bound);
  // The streamed path (summarised) drops the same pixels.
  EXPECT_LT(farthest_from_scene(run(" --stream-above 1000", "streamed.ply")), bound);
}

TEST(FlyingPixels, ThePclClassDropsThemFromAnOrganisedCloudAsReadCloudDoes) {
  test::ScratchDir dir("flying_pcl");
  const Eigen::Vector3d eye(0.5, 0.25, -1);
  const Frame f = depth_frame(160, 120, eye);
  write_pcd(dir.path("frame.pcd"), f.P, f.width, f.height, eye);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  ASSERT_EQ(pcl::io::loadPCDFile(dir.path("frame.pcd"), *cloud), 0);  // as a PCL user loads a frame
  EXPECT_TRUE(cloud->sensor_origin_.head<3>().isApprox(Eigen::Vector3f(0.5f, 0.25f, -1.f)));
  ASSERT_TRUE(cloud->isOrganized());
  auto run = [&](double ratio) {
    heatcvt::HeatCVTReconstruction<pcl::PointXYZ> rec;
    rec.setInputCloud(cloud);
    rec.setNumberOfSites(300);
    FlyingPixelOptions o;
    o.neighbour_distance_ratio = ratio;
    rec.setFlyingPixels(o);
    std::vector<pcl::Vertices> polygons;
    pcl::PointCloud<pcl::PointXYZ> points;
    rec.reconstruct(points, polygons);
    return rec.getReconstructionResult().mesh;
  };
  ReconstructionOptions o;
  o.sites = 300;
  const TriangleMesh from_file = reconstruct_surface(read_cloud(dir.path("frame.pcd")).P, o).mesh;
  const TriangleMesh filtered = run(FlyingPixelOptions{}.neighbour_distance_ratio), kept = run(0);
  ASSERT_GT(from_file.F.rows(), 0);
  EXPECT_TRUE(filtered.V == from_file.V && filtered.F == from_file.F);
  EXPECT_FALSE(kept.V.rows() == from_file.V.rows() && kept.V == from_file.V);  // the rule changed the input
}

TEST(FlyingPixels, BadOptionOrViewpointGivesOneErrorLineAndNoOutput) {
  test::ScratchDir dir("flying_bad");
  const Frame f = depth_frame(40, 30, Eigen::Vector3d::Zero());
  write_pcd(dir.path("frame.pcd"), f.P, f.width, f.height, f.eye);
  auto r = test::run_tool("cloud2mesh", dir.path("frame.pcd") + " -n 50 -o " + dir.path("out.ply") + " --flying-pixels -1");
  test::expect_tool_failure("cloud2mesh", r, {"--flying-pixels", ">= 0"}, dir, 1);
  // A VIEWPOINT that is not seven numbers: the file is named, whole-file and streamed paths alike.
  std::ifstream in(dir.path("frame.pcd"));
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("VIEWPOINT"), 9, "VIEWPOINT x");
  std::ofstream(dir.path("frame.pcd")) << text;
  for (const char* extra : {"", " --stream-above 100"}) {
    r = test::run_tool("cloud2mesh", dir.path("frame.pcd") + " -n 50 -o " + dir.path("out.ply") + extra);
    test::expect_tool_failure("cloud2mesh", r, {"frame.pcd", "VIEWPOINT"}, dir, 1);
  }
}
