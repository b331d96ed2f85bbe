// The noise estimate and the noise limit of the site count (noise_estimate.h), and the streamed
// reconstruction under that limit (reconstruct_stream.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "heatcvt/errors.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/noise_estimate.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/reconstruct_stream.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// `count` points uniform on the unit square of z = 0, heights Gaussian of deviation sigma.
Eigen::MatrixX3d noisy_plane(int count, double sigma, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, sigma);
  Eigen::MatrixX3d P(count, 3);
  for (int i = 0; i < count; ++i) P.row(i) << uni(rng), uni(rng), gauss(rng);
  return P;
}

}  // namespace

TEST(NoiseEstimate, RecoversTheDeviationOnAPlaneAndASphere) {
  // A plane, noise a fifth of the spacing: within 10 %.
  const double sigma = 0.01, spacing = 0.05;
  const NoiseEstimate plane = estimate_noise(noisy_plane(60000, sigma, 3), spacing);
  EXPECT_GT(plane.queries_used, 2500);
  EXPECT_NEAR(plane.sigma, sigma, 0.1 * sigma);
  // A unit sphere: the quadratic takes the curvature, so a clean sphere measures (almost) no
  // noise, and a noisy one its noise (sample_surface's noise is isotropic: σ across the surface).
  const TriangleMesh sphere = test::icosphere(5);
  const double sphere_spacing = 0.1;
  const NoiseEstimate clean = estimate_noise(sample_surface(sphere.V, sphere.F, 60000, 4, 0.0), sphere_spacing);
  EXPECT_LT(clean.sigma, 0.1 * sigma);
  const NoiseEstimate noisy = estimate_noise(sample_surface(sphere.V, sphere.F, 60000, 4, sigma), sphere_spacing);
  EXPECT_NEAR(noisy.sigma, sigma, 0.15 * sigma);
  // Any thread count gives the same figure.
  NoiseEstimateOptions one;
  one.threads = 1;
  EXPECT_EQ(estimate_noise(sample_surface(sphere.V, sphere.F, 60000, 4, sigma), sphere_spacing, one).sigma,
            noisy.sigma);
  // Too few points near every query: no estimate.
  EXPECT_EQ(estimate_noise(noisy_plane(100, sigma, 3), spacing).queries_used, 0);
  EXPECT_THROW(estimate_noise(noisy_plane(100, sigma, 3), 0.0), InvalidInputError);
  EXPECT_THROW(estimate_noise(noisy_plane(100, sigma, 3), std::nan("")), InvalidInputError);
}

TEST(NoiseEstimate, LimitedSitesFollowTheSquareOfTheSpacing) {
  EXPECT_EQ(noise_limited_sites(1000, 1.0, 0.1, 0.17, 8), 1000);   // below the limit
  EXPECT_EQ(noise_limited_sites(1000, 1.0, 0.34, 0.17, 8), 250);   // twice the limit: a quarter
  EXPECT_EQ(noise_limited_sites(1000, 1.0, 1.0, 0.17, 8), 125);    // at most 8 times fewer
  EXPECT_EQ(noise_limited_sites(10, 1.0, 10.0, 0.17, 1000), 4);    // never below 4
  EXPECT_EQ(noise_limited_sites(1000, 2.0, 0.68, 0.17, 8), 250);   // in units of the spacing
}

// Armadillo sampled with noise of 0.71 % of its diagonal (250,000 points, streamed): at 3,000
// sites the noise is about 0.3 site spacings wide, and the dual of a CVT on 3,000 sites breaks
// (open holes, stray pieces). Under the noise limit the CVT runs on fewer sites and the mesh,
// sized to the count, is closed and of genus 0.
TEST(ReconstructStreamed, NoiseWiderThanTheLimitGivesFewerCvtSitesAndAClosedMesh) {
  const TriangleMesh armadillo = read_mesh(test::data_path("meshes/armadillo.obj"));
  const double diagonal = (armadillo.V.colwise().maxCoeff() - armadillo.V.colwise().minCoeff()).norm();
  test::ScratchDir dir("noise_limit");
  const std::string path = dir.path("armadillo_noisy.ply");
  write_mesh(path, sample_surface(armadillo.V, armadillo.F, 250000, 1, 0.0071 * diagonal), Eigen::MatrixX3i(0, 3));
  ReconstructionOptions options;
  options.sites = 3000;
  StreamOptions bad;
  bad.max_noise_reduction = 0.5;
  EXPECT_THROW(reconstruct_surface_streamed(path, options, bad), InvalidInputError);
  bad = StreamOptions{};
  bad.max_noise_spacings = -1;
  EXPECT_THROW(reconstruct_surface_streamed(path, options, bad), InvalidInputError);
  StreamOptions off;
  off.max_noise_spacings = 0;
  const StreamedReconstruction unlimited = reconstruct_surface_streamed(path, options, off);
  ASSERT_TRUE(unlimited.summarised);
  ASSERT_EQ(unlimited.cvt_sites, options.sites);
  // Precondition: without the limit the mesh is not a closed surface of one piece.
  ASSERT_TRUE(unlimited.result.validation.boundary_loops > 0 || unlimited.result.validation.components > 1);

  const StreamedReconstruction limited = reconstruct_surface_streamed(path, options);
  EXPECT_GT(limited.noise_spacings, StreamOptions{}.max_noise_spacings);
  EXPECT_LT(limited.cvt_sites, options.sites);
  EXPECT_GE(limited.cvt_sites, options.sites / 8);
  const ValidationReport& v = limited.result.validation;
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.boundary_loops, 0);
  EXPECT_EQ(v.components, 1);
  EXPECT_EQ(v.genus, 0);
  EXPECT_NEAR(static_cast<double>(limited.result.mesh.V.rows()), options.sites, 0.02 * options.sites);
  // The count asked for is the sizing's target, not the CVT's fewer sites: no retry runs
  // (ReconstructionOptions::count_retries), since the mesh is at the count.
  EXPECT_EQ(limited.result.count_retries, 0);
  // No sliver. (The 25° / 52° targets of the reconstruction are not reached on such a sized mesh
  // yet: 22.6–26.2° and 51.8–53.1° over -n 2,000–6,000, docs/benchmarks.md.)
  EXPECT_GE(limited.result.min_angle_deg, 20.0);
  EXPECT_GE(limited.result.mean_min_angle_deg, 50.0);
}
