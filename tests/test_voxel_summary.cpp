// Voxel summary, voxel size chooser and the streamed reconstruction (voxel_summary.h,
// reconstruct_stream.h), on shapes built in code.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "heatcvt/cloud_io.h"
#include "heatcvt/cloud_stream.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/voxel_summary.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

constexpr double kPi = 3.14159265358979323846;

PointCloud torus_cloud(int count, double noise, std::uint32_t seed = 5) {
  const TriangleMesh torus = test::torus(60, 30);
  PointCloud cloud;
  cloud.P = sample_surface(torus.V, torus.F, count, seed, noise);
  cloud.C = ((cloud.P.array() + 1.5) / 3.0).min(1.0).max(0.0).matrix();
  return cloud;
}

VoxelSummary summarise(const PointCloud& cloud, double h, Eigen::Index chunk, int threads = 0) {
  VoxelSummary summary(h, threads);
  for (Eigen::Index start = 0; start < cloud.P.rows(); start += chunk) {
    const Eigen::Index n = std::min(chunk, cloud.P.rows() - start);
    CloudChunk c;
    c.P = cloud.P.middleRows(start, n);
    c.C = cloud.C.middleRows(start, n);
    summary.add(c);
  }
  return summary;
}

bool identical(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

bool same_mesh(const TriangleMesh& a, const TriangleMesh& b) {
  return identical(a.V, b.V) && a.F.rows() == b.F.rows() && (a.F.array() == b.F.array()).all();
}

void write_ply(const std::string& path, const PointCloud& cloud) {
  MeshAttributes attr;
  attr.vertex_color = cloud.C;
  write_mesh(path, cloud.P, Eigen::MatrixX3i(0, 3), attr);
}

}  // namespace

TEST(VoxelSummary, ChunkSizeDoesNotChangeAnyBit) {
  const PointCloud cloud = torus_cloud(20000, 0.01);
  const VoxelSummary ref = summarise(cloud, 0.05, 1000);
  ASSERT_GT(ref.voxels(), 500);
  ASSERT_TRUE(ref.has_colours());
  for (Eigen::Index chunk : {1, 7}) {
    const VoxelSummary s = summarise(cloud, 0.05, chunk);
    EXPECT_TRUE(identical(s.points(), ref.points())) << chunk;
    EXPECT_TRUE(identical(s.normals(), ref.normals())) << chunk;
    EXPECT_TRUE(identical(s.colours(), ref.colours())) << chunk;
    EXPECT_TRUE((s.counts().array() == ref.counts().array()).all()) << chunk;
  }
  // The same through the streaming reader of a PLY file.
  test::ScratchDir dir("voxel_summary_chunks");
  write_ply(dir.path("torus.ply"), cloud);
  for (std::int64_t chunk : {1, 7, 1000}) {
    StreamReaderOptions o;
    o.chunk_points = chunk;
    CloudChunkReader reader(dir.path("torus.ply"), o);
    VoxelSummary s(0.05);
    CloudChunk c;
    while (reader.next(c)) s.add(c);
    EXPECT_EQ(s.points_added(), 20000);
    // Positions go through the file as doubles: the same summary bit for bit.
    EXPECT_TRUE(identical(s.points(), ref.points())) << chunk;
    EXPECT_TRUE(identical(s.normals(), ref.normals())) << chunk;
  }
}

TEST(VoxelSummary, OneOrTwoThreadsGiveTheSameBits) {
  // A chunk large enough to be binned on every thread (each thread a residue class of voxels);
  // the wide fits of surface_points() on both thread counts are compared in
  // WideFitTakesTheNormalWhereTheNoiseBandFillsTheVoxelNeighbourhood.
  const PointCloud cloud = torus_cloud(60000, 0.01);
  const VoxelSummary one = summarise(cloud, 0.02, 60000, 1);
  const VoxelSummary two = summarise(cloud, 0.02, 60000, 2);
  ASSERT_GT(one.voxels(), 5000);
  EXPECT_TRUE(identical(two.points(), one.points()));
  EXPECT_TRUE(identical(two.normals(), one.normals()));
  EXPECT_TRUE(identical(two.colours(), one.colours()));
  EXPECT_TRUE((two.counts().array() == one.counts().array()).all());
  Eigen::VectorXi w1, w2;
  Eigen::MatrixX3d c1, c2;
  const Eigen::MatrixX3d s1 = one.surface_points(3000, &w1, &c1), s2 = two.surface_points(3000, &w2, &c2);
  ASSERT_GT(s1.rows(), 2000);
  EXPECT_TRUE(identical(s2, s1));
  EXPECT_TRUE(identical(c2, c1));
  EXPECT_TRUE((w1.array() == w2.array()).all());
  // ... and the same as point by point (chunks of one, binned serially).
  EXPECT_TRUE(identical(summarise(cloud, 0.02, 1).points(), one.points()));
  // The voxel size chooser too.
  VoxelSizeOptions o1, o2;
  o1.threads = 1, o2.threads = 2;
  EXPECT_EQ(choose_voxel_size(cloud.P, 500, o1), choose_voxel_size(cloud.P, 500, o2));
}

TEST(VoxelSummary, MomentsMatchTheirVoxelsPoints) {
  const PointCloud cloud = torus_cloud(5000, 0.01, 9);
  const double h = 0.1;
  const VoxelSummary s = summarise(cloud, h, 333);
  // Brute force: group points by cell.
  std::map<std::array<std::int64_t, 3>, std::vector<Eigen::Index>> groups;
  for (Eigen::Index i = 0; i < cloud.P.rows(); ++i)
    groups[{static_cast<std::int64_t>(std::floor(cloud.P(i, 0) / h)), static_cast<std::int64_t>(std::floor(cloud.P(i, 1) / h)),
            static_cast<std::int64_t>(std::floor(cloud.P(i, 2) / h))}]
        .push_back(i);
  ASSERT_EQ(s.voxels(), static_cast<Eigen::Index>(groups.size()));
  const Eigen::MatrixX3d P = s.points();
  std::vector<bool> valid;
  const Eigen::MatrixX3d N = s.normals(&valid);
  const Eigen::VectorXi n = s.counts();
  const auto K = s.cells();
  Eigen::Index r = 0;
  for (const auto& [cell, idx] : groups) {  // std::map order = lexicographic cell order
    for (int k = 0; k < 3; ++k) ASSERT_EQ(K(r, k), cell[static_cast<std::size_t>(k)]);
    ASSERT_EQ(n(r), static_cast<int>(idx.size()));
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    for (auto i : idx) mean += cloud.P.row(i);
    mean /= static_cast<double>(idx.size());
    EXPECT_LT((P.row(r) - mean).norm(), 1e-12);
    EXPECT_EQ(valid[static_cast<std::size_t>(r)], idx.size() >= 3);
    if (idx.size() < 3) {
      EXPECT_TRUE(N.row(r).isZero(0.0));
    } else {
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (auto i : idx) cov += (cloud.P.row(i) - mean).transpose() * (cloud.P.row(i) - mean);
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      // N is a unit eigenvector of the smallest eigenvalue: cov N = λ₀ N.
      const Eigen::Vector3d nr = N.row(r).transpose();
      EXPECT_LT((cov * nr - eig.eigenvalues()(0) * nr).norm(), 1e-9 * (cov.norm() + 1e-300)) << r;
      EXPECT_NEAR(nr.norm(), 1.0, 1e-12);
    }
    ++r;
  }
}

TEST(VoxelSummary, PlaneNormalsAndNonFinitePoints) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  // Random points of a 2 × 2 square of the plane (no three collinear), far from the origin.
  const Eigen::MatrixX2d uv = Eigen::MatrixX2d::Random(40000, 2);
  Eigen::MatrixX3d P(40000, 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) = (1000.0 * Eigen::Vector3d::Ones() + uv(i, 0) * u + uv(i, 1) * v).transpose();
  P(7, 1) = std::numeric_limits<double>::quiet_NaN();
  P(8, 2) = std::numeric_limits<double>::infinity();
  VoxelSummary s(0.1);
  s.add(P);
  EXPECT_EQ(s.non_finite_skipped(), 2);
  EXPECT_EQ(s.points_added(), 40000 - 2);
  EXPECT_FALSE(s.has_colours());
  EXPECT_EQ(s.colours().rows(), 0);
  std::vector<bool> valid;
  const Eigen::MatrixX3d N = s.normals(&valid);
  const Eigen::VectorXi n = s.counts();
  ASSERT_GT((n.array() >= 3).count(), N.rows() / 2);
  for (Eigen::Index r = 0; r < N.rows(); ++r) {
    const bool ok = valid[static_cast<std::size_t>(r)];
    EXPECT_EQ(ok, n(r) >= 3);
    // Far from the origin (coordinates ~1000), the voxel-relative sums keep the plane exact;
    // flagged voxels have a zero row.
    EXPECT_NEAR(std::abs(N.row(r).dot(normal.transpose())), ok ? 1.0 : 0.0, 1e-9);
  }
}

TEST(VoxelSummary, SurfacePointsRemoveTheNoiseLayersAndHitTheTarget) {
  // Unit sphere with noise σ = 0.01 and voxels of 0.02: the noise band (±2σ) spans two voxel layers.
  const TriangleMesh sphere = test::icosphere(5);
  const Eigen::MatrixX3d P = sample_surface(sphere.V, sphere.F, 300000, 4, 0.01);
  VoxelSummary s(0.02);
  s.add(P);
  auto rms_off_sphere = [](const Eigen::MatrixX3d& Q) {
    return std::sqrt((Q.rowwise().norm().array() - 1.0).square().mean());
  };
  const Eigen::MatrixX3d means = s.points();
  Eigen::VectorXi weights;
  const Eigen::MatrixX3d surface = s.surface_points(0, &weights);
  EXPECT_LT(rms_off_sphere(surface), 0.5 * rms_off_sphere(means));
  EXPECT_LT(surface.rows(), means.rows());  // one point per cell of a thin layer
  EXPECT_EQ(weights.sum(), 300000);         // every point accounted for once
  // With a target: at most that many points, and not far below it.
  for (Eigen::Index target : {2000, 10000}) {
    const Eigen::MatrixX3d thin = s.surface_points(target);
    EXPECT_LE(thin.rows(), target);
    EXPECT_GE(thin.rows(), target * 9 / 10);
  }
}

TEST(VoxelSummary, WideFitTakesTheNormalWhereTheNoiseBandFillsTheVoxelNeighbourhood) {
  // Unit sphere, voxels of h = 0.02, noise σ = 0.6 h: a 3×3×3 voxel neighbourhood (3h wide) is
  // about as thick as it is wide (λ0/λ1 ≈ σ²/(0.75 h²) ≈ 0.5), so its normal is mostly noise.
  const double h = 0.02, sigma = 0.6 * h;
  const TriangleMesh sphere = test::icosphere(5);
  const Eigen::MatrixX3d P = sample_surface(sphere.V, sphere.F, 400000, 7, sigma);
  VoxelSummary s(h, 2);
  s.add(P);
  auto rms_off = [](const Eigen::MatrixX3d& Q, double radius) {
    return std::sqrt((Q.rowwise().norm().array() - radius).square().mean());
  };
  VoxelSurfaceFit plain;  // the 3×3×3 voxel fit only
  plain.max_levels = 0;
  plain.shift_steps = 0;
  const double narrow = rms_off(s.surface_points(0, nullptr, nullptr, plain), 1.0);
  const Eigen::MatrixX3d fitted = s.surface_points(0);
  const double wide = rms_off(fitted, 1.0);
  VoxelSummary one_thread(h, 1);
  one_thread.add(P);
  const Eigen::MatrixX3d serial = one_thread.surface_points(0);
  EXPECT_TRUE(identical(serial, fitted)) << "the thread count changed the surface points";
  std::printf("rms off the sphere: voxel fit %.5f, widened normal and mean shift %.5f (sigma %.5f)\n", narrow, wide, sigma);
  EXPECT_LT(wide, 0.75 * narrow);

  // A band thinner than the voxels (σ = 0.1 h): few neighbourhoods are thick, and every voxel
  // keeps its 3×3×3 fit, bit for bit.
  VoxelSummary thin(h);
  thin.add(sample_surface(sphere.V, sphere.F, 200000, 9, 0.1 * h));
  EXPECT_TRUE(identical(thin.surface_points(0), thin.surface_points(0, nullptr, nullptr, plain)));

  // Two concentric spheres 5 h apart, same noise: the widened normal still goes through the local
  // mean, so no point is pulled into the gap between the two sheets.
  const Eigen::MatrixX3d Q = sample_surface(sphere.V, sphere.F, 200000, 8, sigma);
  Eigen::MatrixX3d shells(2 * Q.rows(), 3);
  shells << Q, 1.1 * Q.rowwise().normalized() + (Q - Q.rowwise().normalized());
  VoxelSummary two(h);
  two.add(shells);
  auto in_gap = [&](const Eigen::MatrixX3d& out) {
    Eigen::Index count = 0;
    for (Eigen::Index i = 0; i < out.rows(); ++i) count += std::abs(out.row(i).norm() - 1.05) < h;
    return count;
  };
  const Eigen::Index gap_plain = in_gap(two.surface_points(0, nullptr, nullptr, plain));
  const Eigen::Index gap_wide = in_gap(two.surface_points(0));
  std::printf("points in the gap: %ld plain, %ld widened\n", static_cast<long>(gap_plain), static_cast<long>(gap_wide));
  EXPECT_LE(gap_wide, gap_plain);
}

TEST(VoxelSizeChooser, AreaOfASphereAndVoxelCountNearTarget) {
  // Unit sphere (area 4π): every orientation, so the mean crossing factor 1.5 holds.
  const TriangleMesh sphere = test::icosphere(5);
  const Eigen::MatrixX3d S = sample_surface(sphere.V, sphere.F, 100000, 2);
  EXPECT_NEAR(estimate_surface_area(S).area / (4 * kPi), 1.0, 0.15);
  // The chosen voxel gives about sites × points_per_site voxel means on a dense cloud, on the
  // sphere and on an axis-aligned 2 × 1 rectangle (crossing factor 1: it cancels in the choice).
  const TriangleMesh rect = test::grid(20, 0, 2, 0, 1);
  const Eigen::MatrixX3d R = sample_surface(rect.V, rect.F, 100000, 2);
  const Eigen::MatrixX3d dense_sphere = sample_surface(sphere.V, sphere.F, 400000, 3);
  const Eigen::MatrixX3d dense_rect = sample_surface(rect.V, rect.F, 400000, 3);
  for (int sites : {500, 2000}) {
    VoxelSizeOptions o;
    VoxelSummary on_sphere(choose_voxel_size(S, sites, o));
    on_sphere.add(dense_sphere);
    EXPECT_NEAR(static_cast<double>(on_sphere.voxels()) / (sites * o.points_per_site), 1.0, 0.25) << sites;
    VoxelSummary on_rect(choose_voxel_size(R, sites, o));
    on_rect.add(dense_rect);
    EXPECT_NEAR(static_cast<double>(on_rect.voxels()) / (sites * o.points_per_site), 1.0, 0.25) << sites;
  }
  EXPECT_THROW(choose_voxel_size(S.topRows(5), 100), InvalidInputError);
  EXPECT_THROW(choose_voxel_size(S, 0), InvalidInputError);
  EXPECT_THROW(VoxelSummary(0.0), InvalidInputError);
}

TEST(ReconstructStreamed, CloudThatFitsGivesTheWholeCloudMesh) {
  test::ScratchDir dir("stream_fits");
  const PointCloud cloud = torus_cloud(6000, 0.002);
  write_ply(dir.path("torus.ply"), cloud);
  ReconstructionOptions options;
  options.sites = 300;
  StreamOptions stream;
  stream.chunk_points = 777;
  const StreamedReconstruction streamed = reconstruct_surface_streamed(dir.path("torus.ply"), options, stream);
  const ReconstructionResult whole = reconstruct_surface(read_cloud(dir.path("torus.ply")).P, options);
  EXPECT_FALSE(streamed.summarised);
  EXPECT_EQ(streamed.passes, 1);
  EXPECT_TRUE(same_mesh(streamed.result.mesh, whole.mesh));
  EXPECT_GT(streamed.result.mesh.F.rows(), 500);
}

TEST(ReconstructStreamed, SummarisedCloudChunkSizeDoesNotChangeTheMesh) {
  test::ScratchDir dir("stream_summary");
  const PointCloud cloud = torus_cloud(120000, 0.002);
  write_ply(dir.path("torus.ply"), cloud);
  ReconstructionOptions options;
  options.sites = 400;
  StreamOptions stream;
  stream.max_raw_points = 50000;  // the cloud is larger: summarised
  int last_pass = 0;
  stream.progress = [&](int pass, const StreamProgress&) { last_pass = pass; };
  TriangleMesh reference;
  for (std::int64_t chunk : {1000, 100000}) {
    stream.chunk_points = chunk;
    const StreamedReconstruction r = reconstruct_surface_streamed(dir.path("torus.ply"), options, stream);
    EXPECT_TRUE(r.summarised);
    EXPECT_EQ(r.passes, 2);
    EXPECT_EQ(last_pass, 2);
    EXPECT_EQ(r.points_read, 120000);
    EXPECT_TRUE(r.cloud.has_colours());
    // About points_per_site voxel means per site.
    EXPECT_NEAR(static_cast<double>(r.cloud.P.rows()) / (options.sites * stream.voxel.points_per_site), 1.0, 0.3);
    EXPECT_EQ(r.result.validation.genus, 1);
    EXPECT_TRUE(r.result.validation.boundary_loops == 0);
    // The noise was measured, and it is far below the limit: the CVT ran on every site asked for.
    EXPECT_GT(r.noise_spacings, 0.0);
    EXPECT_LT(r.noise_spacings, stream.max_noise_spacings);
    EXPECT_EQ(r.cvt_sites, options.sites);
    if (chunk == 1000) reference = r.result.mesh;
    else EXPECT_TRUE(same_mesh(r.result.mesh, reference));
  }
}

TEST(ReconstructStreamed, PushInterfaceGivesTheStreamedMesh) {
  test::ScratchDir dir("stream_push");
  const PointCloud cloud = torus_cloud(30000, 0.002);
  write_ply(dir.path("torus.ply"), cloud);
  ReconstructionOptions options;
  options.sites = 300;
  StreamOptions stream;
  stream.max_raw_points = 0;
  stream.voxel_size = 0.04;
  const StreamedReconstruction streamed = reconstruct_surface_streamed(dir.path("torus.ply"), options, stream);
  EXPECT_EQ(streamed.passes, 1);
  const VoxelSummary pushed = summarise(cloud, 0.04, 4096);  // a PCL user's pieces
  const StreamedReconstruction from_push = reconstruct_surface_from_summary(pushed, options, stream);
  EXPECT_TRUE(same_mesh(streamed.result.mesh, from_push.result.mesh));
  EXPECT_THROW(reconstruct_surface_from_summary(VoxelSummary(0.1), options), InvalidInputError);
}

TEST(ReconstructStreamed, TruncatedFileGivesOneIOErrorAndNoMesh) {
  test::ScratchDir dir("stream_truncated");
  const PointCloud cloud = torus_cloud(30000, 0.002);
  write_ply(dir.path("torus.ply"), cloud);
  std::string data;
  {
    std::ifstream in(dir.path("torus.ply"), std::ios::binary);
    data.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string cut = dir.path("cut.ply");
  {
    std::ofstream out(cut, std::ios::binary);
    out.write(data.data(), static_cast<std::streamsize>(data.size() * 3 / 4));
  }
  ReconstructionOptions options;
  options.sites = 300;
  for (std::int64_t max_raw : {std::int64_t(0), std::int64_t(100000)}) {
    StreamOptions stream;
    stream.max_raw_points = max_raw;
    int errors = 0;
    std::string message;
    try {
      reconstruct_surface_streamed(cut, options, stream);
    } catch (const IOError& e) {
      ++errors;
      message = e.what();
    }
    EXPECT_EQ(errors, 1);
    EXPECT_EQ(message.rfind(cut + ": truncated", 0), 0u) << message;
  }
}
