// Dense pieces (dense_pieces.h): separate parts holding many points on little area, found on
// triangulated spheres built in code, and meshed on their own sites by reconstruct_surface() and
// cloud2mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "heatcvt/cloud_io.h"
#include "heatcvt/dense_pieces.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/noise_estimate.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "heatcvt/shapes.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

using test::sphere_points;

// Spheres of radii r[k] about centres c[k] (random_sphere_mesh() of `vertices` vertices each) as
// one triangle set, with the weight w[k] on each vertex of sphere k.
struct Spheres {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
  std::vector<int> weight;
};

Spheres spheres(const std::vector<double>& r, const std::vector<Eigen::Vector3d>& c, const std::vector<int>& w,
                int vertices) {
  Spheres s;
  const TriangleMesh unit = random_sphere_mesh(vertices - 6, 3);
  const Eigen::Index nv = unit.V.rows(), nf = unit.F.rows();
  s.V.resize(nv * static_cast<Eigen::Index>(r.size()), 3);
  s.F.resize(nf * static_cast<Eigen::Index>(r.size()), 3);
  for (size_t k = 0; k < r.size(); ++k) {
    const Eigen::Index k_ = static_cast<Eigen::Index>(k);
    s.V.middleRows(k_ * nv, nv) = (r[k] * unit.V).rowwise() + c[k].transpose();
    s.F.middleRows(k_ * nf, nf) = unit.F.array() + static_cast<int>(k_ * nv);
    s.weight.insert(s.weight.end(), static_cast<size_t>(nv), w[k]);
  }
  return s;
}

// The cloud of the reconstruction tests: n points on the unit sphere about the origin (seed),
// then n on the sphere of radius 10 about (30, 0, 0) (seed + 1).
Eigen::MatrixX3d two_spheres(int n, unsigned seed) {
  Eigen::MatrixX3d P(2 * n, 3);
  P << sphere_points(n, 1, Eigen::Vector3d::Zero(), seed), sphere_points(n, 10, Eigen::Vector3d(30, 0, 0), seed + 1);
  return P;
}

// The vertices of `mesh` near the unit sphere about the origin (within 1.5), each expected within
// `tolerance` of it.
int vertices_on_unit_sphere(const TriangleMesh& mesh, double tolerance) {
  int near = 0;
  for (Eigen::Index v = 0; v < mesh.V.rows(); ++v)
    if (mesh.V.row(v).norm() < 1.5) {
      ++near;
      EXPECT_NEAR(mesh.V.row(v).norm(), 1.0, tolerance);
    }
  return near;
}

int count_pieces(const DensePieces& d, int piece) {
  return static_cast<int>(std::count(d.piece.begin(), d.piece.end(), piece));
}

// A sphere of radius 1 beside one of radius 10, their points as dense as each other per vertex
// (1 cloud point per vertex, 500 vertices each): at 300 sites the small one gets 300 / 101 ≈ 3
// sites by area but holds half the points: a dense piece on the floor of 24 sites. With 6 points
// a vertex on the large sphere, the small one holds 1/7 of them: still dense; with 30, 1/31 <
// 5 %: not. The large sphere is never a piece. A part only 2.5 times as dense as its area share
// is not dense (min_density_ratio 4).
TEST(DensePieces, ASmallSphereHoldingMuchOfTheCloudIsAPieceOfItsOwn) {
  const std::vector<double> radii{1, 10};
  const std::vector<Eigen::Vector3d> centres{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(30, 0, 0)};
  const Spheres half = spheres(radii, centres, {1, 1}, 500);
  const DensePieces d = dense_pieces(half.V, half.F, half.weight, 300, 0.01, {});
  ASSERT_EQ(d.count(), 1);
  EXPECT_EQ(d.sites[0], 24);
  EXPECT_EQ(count_pieces(d, 0), 500);
  for (int i = 0; i < 500; ++i) EXPECT_EQ(d.piece[i], 0);  // the small sphere's vertices come first
  EXPECT_EQ(count_pieces(d, -1), 500);

  EXPECT_EQ(dense_pieces(half.V, half.F, spheres(radii, centres, {1, 6}, 500).weight, 300, 0.01, {}).count(), 1);
  EXPECT_EQ(dense_pieces(half.V, half.F, spheres(radii, centres, {1, 30}, 500).weight, 300, 0.01, {}).count(), 0);
  // The floor grows with the mesher's smallest piece: 2 × 1 % of 3,000 sites.
  const DensePieces at3000 = dense_pieces(half.V, half.F, std::vector<int>(1000, 10), 3000, 0.01, {});
  ASSERT_EQ(at3000.count(), 1);
  EXPECT_EQ(at3000.sites[0], 60);
  // Its share by area reaches half the floor of 24 at 12 · 101 = 1,212 sites, and then it is no
  // piece: the mesher keeps a piece of 12 sites as it is.
  DensePieceOptions fixed_floor;
  fixed_floor.min_sites = 24;
  EXPECT_EQ(dense_pieces(half.V, half.F, std::vector<int>(1000, 10), 1300, 0, fixed_floor).count(), 0);
  EXPECT_EQ(dense_pieces(half.V, half.F, std::vector<int>(1000, 10), 1100, 0, fixed_floor).count(), 1);
  fixed_floor.split_below = 1;
  EXPECT_EQ(dense_pieces(half.V, half.F, std::vector<int>(1000, 10), 2300, 0, fixed_floor).count(), 1);
  // Too few points for the floor's sites (504 at 21 a site): no piece.
  DensePieceOptions many_per_site;
  many_per_site.min_points_per_site = 21;
  EXPECT_EQ(dense_pieces(half.V, half.F, half.weight, 300, 0.01, many_per_site).count(), 0);
  // Radii 1 and 3 at 100 sites: the small sphere has a tenth of the area (10 sites). With 2 cloud
  // points a vertex against 1 it holds 2/3 of the points, 6.7 times its area share: dense; with 1
  // against 3, a quarter: 2.5 times, not dense unless min_density_ratio allows it.
  const Spheres near = spheres({1, 3}, centres, {1, 1}, 500);
  EXPECT_EQ(dense_pieces(near.V, near.F, spheres({1, 3}, centres, {2, 1}, 500).weight, 100, 0.01, {}).count(), 1);
  const std::vector<int> quarter = spheres({1, 3}, centres, {1, 3}, 500).weight;
  EXPECT_EQ(dense_pieces(near.V, near.F, quarter, 100, 0.01, {}).count(), 0);
  DensePieceOptions ratio2;
  ratio2.min_density_ratio = 2;
  EXPECT_EQ(dense_pieces(near.V, near.F, quarter, 100, 0.01, ratio2).count(), 1);
  DensePieceOptions off;
  off.min_point_fraction = 0;
  EXPECT_EQ(dense_pieces(half.V, half.F, half.weight, 300, 0.01, off).count(), 0);
  EXPECT_EQ(count_pieces(dense_pieces(half.V, half.F, half.weight, 300, 0.01, off), -1), 1000);
}

// The cheap test before the components: at 3,000 sites a dense piece has less than half of 60 /
// 3,000 of the area, so with 10,000 points of the same area it holds at most 100 of them and 5 %
// of the weight. Equal weights: impossible; 300 points ten times as heavy: possible.
TEST(DensePieces, TheWeightsAloneRuleOutADensePiece) {
  std::vector<int> weight(10000, 1);
  EXPECT_FALSE(dense_piece_possible(weight, 3000, 0.01, {}));
  for (int i = 0; i < 300; ++i) weight[i * 7] = 10;
  EXPECT_TRUE(dense_piece_possible(weight, 3000, 0.01, {}));
  // At 100 sites a piece may hold 12 % of the area: any 12 % of equal weights is more than 5 %.
  EXPECT_TRUE(dense_piece_possible(std::vector<int>(10000, 1), 100, 0.01, {}));
  DensePieceOptions off;
  off.min_point_fraction = 0;
  EXPECT_FALSE(dense_piece_possible(weight, 3000, 0.01, off));
  EXPECT_EQ(dense_piece_sites(3000, 0.01, {}), 60);
  EXPECT_EQ(dense_piece_sites(300, 0.01, {}), 24);
}

// Six small dense spheres beside a large one at 200 sites: each wants 24 sites, the budget of
// half the sites holds 4 of them, those with the most points.
TEST(DensePieces, ThePiecesTakeAtMostTheirShareOfTheSites) {
  std::vector<double> radii{10};
  std::vector<Eigen::Vector3d> centres{Eigen::Vector3d::Zero()};
  std::vector<int> weight{1};
  for (int k = 0; k < 6; ++k) {
    radii.push_back(1);
    centres.emplace_back(20 + 5 * k, 0, 0);
    weight.push_back(k == 2 ? 3 : 2);
  }
  const Spheres s = spheres(radii, centres, weight, 200);
  const DensePieces d = dense_pieces(s.V, s.F, s.weight, 200, 0.01, {});
  ASSERT_EQ(d.count(), 4);
  for (int k = 0; k < d.count(); ++k) EXPECT_EQ(d.sites[k], 24);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(d.piece[i], -1);  // the large sphere is the rest
  EXPECT_EQ(d.piece[3 * 200], 2);  // the sphere with the most points is in, the last one is not
  EXPECT_EQ(d.piece[6 * 200], -1);
  DensePieceOptions wider;
  wider.max_site_fraction = 0.8;
  EXPECT_EQ(dense_pieces(s.V, s.F, s.weight, 200, 0.01, wider).count(), 6);
}

TEST(DensePieces, BadOptionsAndInputsThrow) {
  const Spheres s = spheres({1, 10}, {Eigen::Vector3d::Zero(), Eigen::Vector3d(30, 0, 0)}, {1, 1}, 100);
  auto with = [](auto set) {
    DensePieceOptions o;
    set(o);
    return o;
  };
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.min_point_fraction = 2; })), InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.max_site_fraction = -1; })), InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.min_sites = 3; })), InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.min_density_ratio = -1; })),
               InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.split_below = 0; })), InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, s.weight, 300, 0.01, with([](auto& o) { o.min_points_per_site = NAN; })),
               InvalidInputError);
  EXPECT_THROW(dense_pieces(s.V, s.F, std::vector<int>(5, 1), 300, 0.01, {}), InvalidInputError);
  Eigen::MatrixX3i bad = s.F;
  bad(0, 0) = 1000;
  EXPECT_THROW(dense_pieces(s.V, bad, s.weight, 300, 0.01, {}), InvalidInputError);
}

// The cloud of the first test sampled: 2,500 points on each sphere, at 300 sites. Without the
// rule the small sphere gets about 3 sites and is dropped (half the points left out); with it,
// two closed spheres at the count with the shape targets, covering the cloud.
TEST(DensePieces, ASmallDenseSphereBesideALargeOneIsMeshedWithIt) {
  const Eigen::MatrixX3d P = two_spheres(2500, 5);
  ReconstructionOptions options;
  options.sites = 300;
  options.threads = 2;
  ReconstructionOptions off = options;
  off.dense_pieces.min_point_fraction = 0;
  const ReconstructionResult without = reconstruct_surface(P, off);
  ASSERT_EQ(without.validation.components, 1) << "precondition: the small sphere is dropped without the rule";
  ASSERT_TRUE(without.cloud_coverage.partial());

  const ReconstructionResult with = reconstruct_surface(P, options);
  EXPECT_EQ(with.dense_pieces, 1);
  EXPECT_TRUE(with.validation.ok()) << with.validation.summary();
  EXPECT_EQ(with.validation.components, 2);
  EXPECT_EQ(with.validation.boundary_loops, 0);
  EXPECT_EQ(with.validation.genus, 0);
  EXPECT_NEAR(static_cast<double>(with.mesh.V.rows()), 300, 6);
  EXPECT_GE(with.min_angle_deg, 25.0);
  EXPECT_GE(with.mean_min_angle_deg, 52.0);
  EXPECT_FALSE(with.cloud_coverage.partial()) << with.cloud_coverage.uncovered_share;
  EXPECT_EQ(with.points_used, 5000);
  // The small sphere's vertices lie on it: the floor, within the count the piece's own run reaches.
  EXPECT_NEAR(vertices_on_unit_sphere(with.mesh, 0.02), 24, 2);
}

// The same through cloud2mesh: exit 0, every check passed, the report names the piece; with
// --dense-pieces 0 the small sphere is left out and the coverage check fails (exit 3).
TEST(DensePieces, Cloud2meshMeshesTheDensePieceAndSaysSo) {
  test::ScratchDir dir("dense_pieces");
  PointCloud cloud;
  cloud.P = two_spheres(2500, 5);
  write_cloud_xyz(dir.path("two.xyz"), cloud);
  for (const std::string flag : {"", " --dense-pieces 0"}) {
    SCOPED_TRACE(flag);
    const test::CommandResult r = test::run_tool(
        "cloud2mesh", dir.path("two.xyz") + " -n 300 -o " + dir.path("two.ply") + " --report " + dir.path("two.json") + flag);
    const std::string json = test::read_file(dir.path("two.json"));
    const bool on = flag.empty();
    EXPECT_EQ(r.exit_code, on ? 0 : 3) << r.err;
    EXPECT_EQ(test::json_number(json, "dense_pieces"), on ? 1 : 0);
    EXPECT_EQ(test::failed_checks(json), on ? std::vector<std::string>{} : std::vector<std::string>{"covers_cloud"});
    EXPECT_EQ(r.out.find("dense pieces: 1") != std::string::npos, on) << r.out;
    EXPECT_EQ(validate_triangle_mesh(read_mesh(dir.path("two.ply")).V, read_mesh(dir.path("two.ply")).F).components,
              on ? 2 : 1);
  }
}

// 25,000 points on each sphere at 300 sites: 167 points a site, so the cloud is streamed into a
// voxel summary, whose evenly spaced voxel points give the small sphere about 3 sites' worth. Its
// voxels (26-connected) hold half the points: it is read again into a summary of its own and
// meshed on 24 sites. Chunk sizes do not change the mesh.
TEST(DensePieces, AStreamedCloudReadsItsDensePieceAgain) {
  test::ScratchDir dir("dense_stream");
  PointCloud cloud;
  cloud.P = two_spheres(25000, 7);
  write_cloud_xyz(dir.path("two.xyz"), cloud);
  ReconstructionOptions options;
  options.sites = 300;
  options.threads = 2;
  StreamOptions stream;
  // Precondition: the cloud is past the raw limit (40 points a site), so it is summarised.
  ASSERT_LT(raw_point_limit(stream, options.sites), 50000);
  ReconstructionOptions off = options;
  off.dense_pieces.min_point_fraction = 0;
  const StreamedReconstruction without = reconstruct_surface_streamed(dir.path("two.xyz"), off, stream);
  ASSERT_TRUE(without.summarised);
  ASSERT_EQ(without.result.validation.components, 1) << "precondition: the small sphere is dropped without the rule";

  const StreamedReconstruction with = reconstruct_surface_streamed(dir.path("two.xyz"), options, stream);
  const ReconstructionResult& r = with.result;
  EXPECT_TRUE(with.summarised);
  EXPECT_EQ(with.passes, without.passes + 1);
  EXPECT_EQ(r.dense_pieces, 1);
  EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
  EXPECT_EQ(r.validation.components, 2);
  EXPECT_EQ(r.validation.boundary_loops, 0);
  EXPECT_NEAR(static_cast<double>(r.mesh.V.rows()), 300, 6);
  EXPECT_GE(r.min_angle_deg, 25.0);
  EXPECT_GE(r.mean_min_angle_deg, 52.0);
  EXPECT_FALSE(r.cloud_coverage.partial());
  // The small sphere's vertices lie on it, within 5 % of its radius: the summary's points sit
  // inside a curved surface by part of the sagitta of their 3×3×3-voxel plane fits, and 24 sites
  // on a unit sphere are 0.7 radii apart.
  EXPECT_NEAR(vertices_on_unit_sphere(r.mesh, 0.05), 24, 2);
  StreamOptions small_chunks = stream;
  small_chunks.chunk_points = 777;
  const StreamedReconstruction chunked = reconstruct_surface_streamed(dir.path("two.xyz"), options, small_chunks);
  EXPECT_EQ(chunked.result.mesh.V, r.mesh.V);
  EXPECT_EQ(chunked.result.mesh.F, r.mesh.F);
}

// The noise estimate fits at most max_fit_points per query: on a noisy plane with about 3,000
// points within each query's radius, the strided 1,000 give the deviation within 5 % of every
// point's, and a cluster far smaller than the radius no longer costs a fit of all its points.
TEST(DensePieces, TheNoiseEstimateFitsAStrideOfALargeNeighbourhood) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 0.01);
  Eigen::MatrixX3d P(30000, 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << u(rng), u(rng), g(rng);
  NoiseEstimateOptions all;
  all.max_fit_points = 0;
  const NoiseEstimate every = estimate_noise(P, 0.18, all);
  const NoiseEstimate strided = estimate_noise(P, 0.18);
  ASSERT_GT(every.sigma, 0.0);
  EXPECT_NEAR(strided.sigma, every.sigma, 0.05 * every.sigma);
  EXPECT_NEAR(strided.sigma, 0.01, 0.0015);
  NoiseEstimateOptions bad;
  bad.max_fit_points = 10;  // fewer than min_neighbors
  EXPECT_THROW(estimate_noise(P, 0.18, bad), InvalidInputError);
  bad.max_fit_points = -1;
  EXPECT_THROW(estimate_noise(P, 0.18, bad), InvalidInputError);
}

}  // namespace
}  // namespace heatcvt
