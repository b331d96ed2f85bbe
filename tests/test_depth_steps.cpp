// The refit of quantised depth (depth_steps.h) on depth frames built in code: a structured-light
// camera's disparity rounded to 1/8 pixel, so that the depth takes few values and a surface seen at
// an angle becomes a staircase of terraces. One rule for every shape: the refit leaves at most
// half the RMS distance of the quantised frame to the true surface, and moves no point by more than
// a step (the defaults measure about 0.3 of it on the plane and on the sphere below).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "heatcvt/cloud_io.h"
#include "heatcvt/cloud_stream.h"
#include "heatcvt/depth_steps.h"
#include "heatcvt/errors.h"
#include "heatcvt/reconstruct_stream.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// The depth along a ray (u, v, 1) from the origin, or NaN where it misses the scene.
using Scene = std::function<double(double u, double v)>;

// A camera of W × H pixels and focal length f (pixels), its depth rounded as a disparity of
// baseline·focal `bf` (metres · pixels) in 1/8 pixel steps: the step at depth z is about
// z² / (8 bf), 5 cm at 4 m for bf = 40.
struct Camera {
  int width = 160, height = 120;
  double focal = 130, bf = 40;
  double quantised(double z) const { return bf / (std::round(8 * bf / z) / 8); }
  double step(double z) const { return z * z / (8 * bf); }
};

// The frame's rows (row-major pixels; NaN where the ray misses), with true or quantised depth.
Eigen::MatrixX3d frame(const Camera& cam, const Scene& scene, bool quantise) {
  Eigen::MatrixX3d P(cam.width * cam.height, 3);
  for (int r = 0; r < cam.height; ++r)
    for (int c = 0; c < cam.width; ++c) {
      const double u = (c - cam.width / 2.0) / cam.focal, v = (r - cam.height / 2.0) / cam.focal;
      double z = scene(u, v);
      if (std::isfinite(z) && quantise) z = cam.quantised(z);
      P.row(r * cam.width + c) = Eigen::RowVector3d(u * z, v * z, z);
    }
  return P;
}

Eigen::MatrixX3d finite_rows(const Eigen::MatrixX3d& P) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (P.row(i).allFinite()) keep.push_back(i);
  Eigen::MatrixX3d out(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t k = 0; k < keep.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = P.row(keep[k]);
  return out;
}

// A plane z = z0 + slope · y seen from the origin (slope 1: 45° to the view direction).
Scene tilted_plane(double z0, double slope) {
  return [=](double /*u*/, double v) { return z0 / (1 - slope * v); };
}

// A sphere of radius R centred at (0, 0, zc): the nearer intersection, NaN where the ray misses.
Scene sphere(double R, double zc) {
  return [=](double u, double v) {
    const double a = u * u + v * v + 1, b = -2 * zc, c = zc * zc - R * R;
    const double disc = b * b - 4 * a * c;
    return disc < 0 ? std::numeric_limits<double>::quiet_NaN() : (-b - std::sqrt(disc)) / (2 * a);
  };
}

// RMS of `distance` over the rows of P.
double rms(const Eigen::MatrixX3d& P, const std::function<double(const Eigen::Vector3d&)>& distance) {
  double sum = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) sum += std::pow(distance(P.row(i).transpose()), 2);
  return std::sqrt(sum / static_cast<double>(P.rows()));
}

// The distance of x to the plane z = z0 + slope · y.
double plane_distance(const Eigen::Vector3d& x, double z0, double slope) {
  return std::abs(x.z() - z0 - slope * x.y()) / std::sqrt(1 + slope * slope);
}

void write_ascii_pcd(const std::string& path, const Eigen::MatrixX3d& P, int width, int height) {
  std::ofstream s(path);
  s.precision(9);
  s << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << width << "\nHEIGHT " << height
    << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << P.rows() << "\nDATA ascii\n";
  for (Eigen::Index i = 0; i < P.rows(); ++i) s << P(i, 0) << " " << P(i, 1) << " " << P(i, 2) << "\n";
}

}  // namespace

TEST(DepthSteps, APlaneSeenAtAnAngleComesOutFlat) {
  const Camera cam;
  Eigen::MatrixX3d P = finite_rows(frame(cam, tilted_plane(4, 1), true));
  const Eigen::MatrixX3d quantised = P;
  const auto off_plane = [](const Eigen::Vector3d& x) { return plane_distance(x, 4, 1); };
  const double before = rms(P, off_plane);
  ASSERT_GT(before, 0.01);  // the terraces are there: about a step over √12, steps of 3-7 cm
  const DepthStepReport rep = smooth_depth_steps(P, Eigen::Vector3d::Zero());
  ASSERT_TRUE(rep.quantised);
  EXPECT_EQ(rep.axis, 2);
  EXPECT_LT(rep.distinct_fraction, 0.05);
  EXPECT_NEAR(rep.median_step, cam.step(4), 0.3 * cam.step(4));
  EXPECT_GT(rep.points_moved, P.rows() * 9 / 10);
  EXPECT_LT(rms(P, off_plane), 0.5 * before);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    // Along its ray, by at most a step of its depth.
    const Eigen::Vector3d a = quantised.row(i).transpose(), b = P.row(i).transpose();
    EXPECT_LT(a.normalized().cross(b.normalized()).norm(), 1e-9) << "row " << i;
    EXPECT_LE(std::abs(b.z() - a.z()), cam.step(a.z()) * 1.05 + 1e-12) << "row " << i;
  }
}

TEST(DepthSteps, ACurvedSurfaceGetsNearerItsTruthByLessThanAStep) {
  const Camera cam;
  Eigen::MatrixX3d P = finite_rows(frame(cam, sphere(1.0, 3.5), true));
  const auto off_sphere = [](const Eigen::Vector3d& x) { return std::abs((x - Eigen::Vector3d(0, 0, 3.5)).norm() - 1); };
  const double before = rms(P, off_sphere);
  ASSERT_GT(before, 0.003);  // steps of 2-4 cm
  const Eigen::MatrixX3d quantised = P;
  ASSERT_TRUE(smooth_depth_steps(P, Eigen::Vector3d::Zero()).quantised);
  EXPECT_LT(rms(P, off_sphere), 0.5 * before);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    EXPECT_LE(std::abs(P(i, 2) - quantised(i, 2)), cam.step(quantised(i, 2)) * 1.05 + 1e-12) << "row " << i;
}

TEST(DepthSteps, ADepthEdgeIsNotBlurred) {
  // A plate 0.6 m in front of a tilted wall, the two seen side by side: a point fitted across the
  // edge would be pulled towards the other surface. Every point stays within its quantisation
  // error (half a step, and a little for the fit) of its own surface.
  const Camera cam;
  const Scene wall = tilted_plane(4, 1), plate = tilted_plane(3.4, 1);
  const Scene scene = [&](double u, double v) { return u < 0 ? plate(u, v) : wall(u, v); };
  Eigen::MatrixX3d P = finite_rows(frame(cam, scene, true));
  ASSERT_TRUE(smooth_depth_steps(P, Eigen::Vector3d::Zero()).quantised);
  double worst = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d x = P.row(i).transpose();
    const double z0 = x.x() < 0 ? 3.4 : 4.0;
    worst = std::max(worst, plane_distance(x, z0, 1) / cam.step(x.z()));
  }
  EXPECT_LT(worst, 0.6);
}

TEST(DepthSteps, CloudsWithContinuousDepthOrInAWorldFrameAreLeftAsTheyAre) {
  const Camera cam;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  // Continuous depth: nothing to undo.
  Eigen::MatrixX3d smooth = finite_rows(frame(cam, tilted_plane(4, 1), false));
  const Eigen::MatrixX3d smooth0 = smooth;
  EXPECT_FALSE(smooth_depth_steps(smooth, origin).quantised);
  EXPECT_EQ(smooth, smooth0);
  const Eigen::MatrixX3d quantised = finite_rows(frame(cam, tilted_plane(4, 1), true));
  ASSERT_TRUE(depth_steps_of(quantised, origin).quantised);
  // The same frame in a world frame: rotated (the rounded axis is no coordinate axis any more) ...
  Eigen::MatrixX3d rotated = quantised * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix().transpose();
  const Eigen::MatrixX3d rotated0 = rotated;
  EXPECT_FALSE(smooth_depth_steps(rotated, origin).quantised);
  EXPECT_EQ(rotated, rotated0);
  // ... or seen from a sensor it is not in front of (depths of both signs) ...
  Eigen::MatrixX3d straddling = quantised;
  const Eigen::Vector3d inside(0, 0, 4);
  EXPECT_FALSE(smooth_depth_steps(straddling, inside).quantised);
  EXPECT_EQ(straddling, quantised);
  // ... or wider than a camera's field of view from it.
  const Eigen::Vector3d beside(40, 0, 0);
  EXPECT_FALSE(depth_steps_of(quantised, beside).quantised);
  // ... or millions of metres from it, as UTM coordinates are (a view from afar spanning a few
  // thousandths of a degree, its steps the float precision there).
  const Eigen::MatrixX3d far = quantised.rowwise() + Eigen::RowVector3d(0, 0, 5e6);
  ASSERT_LT(static_cast<double>(depth_steps_of(far, origin).levels), 0.05 * static_cast<double>(far.rows()));
  EXPECT_FALSE(depth_steps_of(far, origin).quantised);
  // Off by the option.
  DepthStepOptions off;
  off.max_distinct_fraction = 0;
  Eigen::MatrixX3d kept = quantised;
  EXPECT_FALSE(smooth_depth_steps(kept, origin, off).quantised);
  EXPECT_EQ(kept, quantised);
}

TEST(DepthSteps, TheSameResultForAnyThreadCount) {
  const Camera cam;
  const Scene scene = [&](double u, double v) { return u < 0.1 ? sphere(0.8, 3.0)(u, v) : tilted_plane(4, 0.7)(u, v); };
  const Eigen::MatrixX3d quantised = finite_rows(frame(cam, scene, true));
  DepthStepOptions one, two;
  one.threads = 1;
  two.threads = 2;
  Eigen::MatrixX3d a = quantised, b = quantised;
  const DepthStepReport ra = smooth_depth_steps(a, Eigen::Vector3d::Zero(), one);
  const DepthStepReport rb = smooth_depth_steps(b, Eigen::Vector3d::Zero(), two);
  ASSERT_TRUE(ra.quantised);
  EXPECT_EQ(a, b);
  EXPECT_EQ(ra.points_moved, rb.points_moved);
}

TEST(DepthSteps, BadOptionsAndInputsAreRefused) {
  const Eigen::MatrixX3d P = finite_rows(frame(Camera(), tilted_plane(4, 1), true));
  const auto refused = [&](const std::function<void(DepthStepOptions&)>& change) {
    DepthStepOptions o;
    change(o);
    Eigen::MatrixX3d Q = P;
    EXPECT_THROW(smooth_depth_steps(Q, Eigen::Vector3d::Zero(), o), InvalidInputError);
  };
  refused([](DepthStepOptions& o) { o.max_distinct_fraction = 1.5; });
  refused([](DepthStepOptions& o) { o.max_distinct_fraction = std::nan(""); });
  refused([](DepthStepOptions& o) { o.max_view_angle_deg = 90; });
  refused([](DepthStepOptions& o) { o.start_neighbours = 200; });
  refused([](DepthStepOptions& o) { o.max_neighbours = 5000; });
  refused([](DepthStepOptions& o) { o.max_move_steps = 0; });
  refused([](DepthStepOptions& o) { o.min_view_extent_deg = -1; });
  refused([](DepthStepOptions& o) { o.min_relative_step = 1; });
  refused([](DepthStepOptions& o) { o.window_steps = std::numeric_limits<double>::infinity(); });
  Eigen::MatrixX3d bad = P;
  bad(3, 1) = std::nan("");
  EXPECT_THROW(smooth_depth_steps(bad, Eigen::Vector3d::Zero()), InvalidInputError);
}

TEST(DepthSteps, ReadingAndStreamingADepthFrameRefitIt) {
  // An organised PCD of a quantised frame: read_cloud refits it in the file's own frame, the
  // streamed reconstruction (which reads a depth frame whole) reports the same refit.
  const Camera cam;
  const Eigen::MatrixX3d grid = frame(cam, tilted_plane(4, 1), true);
  const test::ScratchDir dir("depth_steps");
  const std::string path = dir.path("frame.pcd");
  write_ascii_pcd(path, grid, cam.width, cam.height);
  CloudReadReport rep;
  const PointCloud cloud = read_cloud(path, &rep);
  ASSERT_TRUE(rep.depth_steps.quantised);
  EXPECT_GT(rep.depth_steps.points_moved, cloud.P.rows() * 9 / 10);
  const auto off_plane = [](const Eigen::Vector3d& x) { return plane_distance(x, 4, 1); };
  EXPECT_LT(rms(cloud.P, off_plane), 0.5 * rms(finite_rows(grid), off_plane));
  CloudReadOptions off;
  off.depth_steps.max_distinct_fraction = 0;
  CloudReadReport rep_off;
  const PointCloud kept = read_cloud(path, &rep_off, off);
  EXPECT_FALSE(rep_off.depth_steps.quantised);
  EXPECT_EQ(kept.P.rows(), cloud.P.rows());
  ReconstructionOptions opt;
  opt.sites = 150;
  const StreamedReconstruction streamed = reconstruct_surface_streamed(path, opt);
  EXPECT_TRUE(streamed.depth_steps.quantised);
  EXPECT_EQ(streamed.depth_steps.points_moved, rep.depth_steps.points_moved);
  EXPECT_EQ(streamed.points_read, cam.width * cam.height);
  EXPECT_GT(streamed.result.mesh.F.rows(), 0);
}

TEST(DepthSteps, TheSharedDepthFramesAreRefittedAndWorldFrameScansAreNot) {
  // The Kinect and stereo frames of ../shared/data/clouds (organised or not) are depth frames in
  // their sensor's frame; the lidar tiles and room scans, whose coordinates are rounded in a world
  // frame or held in float far from the origin, and the scans with continuous depth are not.
  for (const char* name : {"pcl_five_people.pcd", "pcl_office1.pcd", "pcldata_capture0001.pcd", "pcl_milk.pcd",
                           "pcl_table_scene_mug_stereo_textured.pcd"}) {
    SCOPED_TRACE(name);
    CloudReadReport rep;
    const PointCloud cloud = read_cloud(test::data_path(std::string("clouds/") + name), &rep);
    EXPECT_TRUE(rep.depth_steps.quantised);
    EXPECT_EQ(rep.depth_steps.axis, 2);
    EXPECT_GT(rep.depth_steps.points_moved, cloud.P.rows() / 2);
    EXPECT_GT(rep.depth_steps.mean_move_steps, 0.05);
    EXPECT_LE(rep.depth_steps.mean_move_steps, 1.0);
  }
  for (const char* name : {"pcl_car6.pcd", "pcldata_min_cut_segmentation_tutorial.pcd", "pcldata_room_scan1.pcd",
                           "pcldata_terrain_samp11-utm.pcd", "pcldata_terrain_CSite1_red2-utm.pcd",
                           "pcldata_biwi_face_model.pcd", "open3d_cloud_bin_0.pcd", "pcl_cturtle.pcd"}) {
    SCOPED_TRACE(name);
    CloudReadOptions off;
    off.depth_steps.max_distinct_fraction = 0;
    const PointCloud raw = read_cloud(test::data_path(std::string("clouds/") + name), nullptr, off);
    CloudReadReport rep;
    const PointCloud cloud = read_cloud(test::data_path(std::string("clouds/") + name), &rep);
    EXPECT_FALSE(rep.depth_steps.quantised);
    EXPECT_EQ(rep.depth_steps.points_moved, 0);
    EXPECT_TRUE(cloud.P == raw.P);
  }
}

TEST(DepthSteps, AMemorySourceHandsOutTheCloudInChunks) {
  const Eigen::MatrixX3d P = finite_rows(frame(Camera(), tilted_plane(4, 1), false));
  const Eigen::MatrixX3d C = Eigen::MatrixX3d::Constant(P.rows(), 3, 0.5), none;
  for (const std::int64_t chunk : {std::int64_t(1000), std::int64_t(7777), std::int64_t(1) << 20}) {
    MemoryChunkSource source(P, none, C, "memory", chunk);
    for (int pass = 0; pass < 2; ++pass) {
      Eigen::Index at = 0;
      CloudChunk c;
      while (source.next(c)) {
        ASSERT_LE(c.rows(), chunk);
        EXPECT_TRUE(c.P == P.middleRows(at, c.rows()));
        EXPECT_TRUE(c.C == C.middleRows(at, c.rows()));
        EXPECT_EQ(c.N.rows(), 0);
        at += c.rows();
      }
      EXPECT_EQ(at, P.rows());
      source.rewind();
    }
  }
  EXPECT_THROW(MemoryChunkSource(P, none, none, "memory", 0), InvalidInputError);
}

TEST(DepthSteps, Cloud2meshMeshesTheFarWallOfARealDepthFrame) {
  // pcl_five_people.pcd at -n 3000: the wall behind the people lies 5-9 m away, where the depth
  // steps are 10-27 cm, more than the site spacing. With the refit the mesh covers the cloud
  // (the coverage check passes); the run with --depth-steps 0 is the precondition: there the wall
  // falls apart into terraces the dual cannot mesh, and more than a fifth of the points are left.
  const test::ScratchDir dir("depth_steps_tool");
  const std::string in = test::data_path("clouds/pcl_five_people.pcd");
  const auto run = [&](const std::string& extra) {
    const std::string report = dir.path("r.json");
    const auto r = test::run_tool("cloud2mesh", "'" + in + "' -n 3000 -o '" + dir.path("m.ply") + "' --report '" +
                                                    report + "' -q " + extra);
    EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;
    return test::read_file(report);
  };
  const std::string without = run("--depth-steps 0 --count-retries 0 --finer-retry 1");
  ASSERT_NE(without.find("\"depth_quantised\": false"), std::string::npos);
  ASSERT_NE(without.find("\"cloud_covered_in_part\": true"), std::string::npos);
  const std::string with = run("");
  EXPECT_NE(with.find("\"depth_quantised\": true"), std::string::npos);
  EXPECT_NE(with.find("\"cloud_covered_in_part\": false"), std::string::npos);
  EXPECT_NE(with.find("\"all_checks_passed\": true"), std::string::npos);
}
