// Point-cloud Laplacian (point_laplacian.h, METHOD.md §7) and PCA / MST normals (normals.h):
// matrix properties, consistency on planes, the spectrum of the unit sphere, determinism,
// heat-solver compatibility, normal orientation, bad input, timing.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "heatcvt/cloud_io.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/normals.h"
#include "heatcvt/point_laplacian.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// Uniform random points on the unit sphere (normalised Gaussians), seeded.
Eigen::MatrixX3d random_sphere(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixX3d P(n, 3);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d p(g(rng), g(rng), g(rng));
    P.row(i) = p.normalized().transpose();
  }
  return P;
}

/// Uniform random points in [-1,1]² embedded in a tilted plane through `origin` spanned by the
/// orthonormal (a, b). Returns the 3D points and the 2D plane coordinates.
void random_plane(int n, unsigned seed, Eigen::MatrixX3d& P, Eigen::MatrixX2d& uv) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d origin(0.3, -0.2, 0.5);
  const Eigen::Vector3d a = Eigen::Vector3d(1, 2, 0.5).normalized();
  const Eigen::Vector3d b = a.cross(Eigen::Vector3d(0.2, -0.4, 1)).normalized();
  P.resize(n, 3);
  uv.resize(n, 2);
  for (int i = 0; i < n; ++i) {
    uv(i, 0) = u(rng);
    uv(i, 1) = u(rng);
    P.row(i) = (origin + uv(i, 0) * a + uv(i, 1) * b).transpose();
  }
}

/// Asserts the structural guarantees of the Laplacian interface.
void expect_valid_laplacian(const Laplacian& lap, int n) {
  const SpMat& L = lap.L;
  ASSERT_EQ(L.rows(), n);
  ASSERT_EQ(L.cols(), n);
  ASSERT_EQ(lap.M.size(), n);
  SpMat asym = L - SpMat(L.transpose());
  EXPECT_EQ(asym.norm(), 0.0) << "L must be exactly symmetric";
  double max_abs = 0;
  int negative_offdiag = 0, nonfinite = 0;
  for (int c = 0; c < L.outerSize(); ++c)
    for (SpMat::InnerIterator it(L, c); it; ++it) {
      if (!std::isfinite(it.value())) ++nonfinite;
      if (it.row() != it.col() && it.value() < 0) ++negative_offdiag;
      max_abs = std::max(max_abs, std::abs(it.value()));
    }
  EXPECT_EQ(nonfinite, 0);
  EXPECT_EQ(negative_offdiag, 0) << "off-diagonal weights must be non-negative";
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  EXPECT_LT((L * ones).cwiseAbs().maxCoeff(), 1e-12 * max_abs) << "L·1 must vanish";
  EXPECT_GT(lap.M.minCoeff(), 0.0);
  EXPECT_TRUE(lap.M.allFinite());
  EXPECT_GT(lap.mean_edge_length, 0.0);
  // Negative semi-definite on random vectors.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x(n);
    for (int i = 0; i < n; ++i) x[i] = u(rng);
    EXPECT_LE(x.dot(L * x), 1e-12 * max_abs * x.squaredNorm());
  }
}

/// Smallest `count` eigenvalues of −L x = λ M x by shift-invert subspace iteration with
/// Rayleigh–Ritz: the operator (−L + σM)⁻¹ M (σ = 1) applied to a block of `block` vectors.
Eigen::VectorXd smallest_eigenvalues(const Laplacian& lap, int count, int block, int* iterations_used) {
  const int n = lap.num_vertices();
  const SpMat K0 = -lap.L;
  SpMat Mmat(n, n);
  std::vector<Eigen::Triplet<double>> mt;
  for (int i = 0; i < n; ++i) mt.emplace_back(i, i, lap.M[i]);
  Mmat.setFromTriplets(mt.begin(), mt.end());
  const SpMat K = K0 + Mmat;
  Eigen::SimplicialLDLT<SpMat> solver(K);
  EXPECT_EQ(solver.info(), Eigen::Success);

  std::mt19937 rng(11);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd X(n, block);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < block; ++j) X(i, j) = g(rng);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(block), previous = Eigen::VectorXd::Constant(block, 1e300);
  int it = 0;
  for (; it < 300; ++it) {
    Eigen::MatrixXd Y = solver.solve(lap.M.asDiagonal() * X);
    // Orthonormalise Y (Euclidean QR) for a well-conditioned projected problem.
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Y);
    Y = qr.householderQ() * Eigen::MatrixXd::Identity(n, block);
    const Eigen::MatrixXd A = Y.transpose() * (K0 * Y);
    const Eigen::MatrixXd B = Y.transpose() * (lap.M.asDiagonal() * Y);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (A + A.transpose()), 0.5 * (B + B.transpose()));
    theta = es.eigenvalues();
    X = Y * es.eigenvectors();
    double change = 0;
    for (int j = 0; j < count; ++j)
      change = std::max(change, std::abs(theta[j] - previous[j]) / std::max(1.0, std::abs(theta[j])));
    previous = theta;
    if (change < 1e-11) break;
  }
  *iterations_used = it + 1;
  return theta.head(count);
}

}  // namespace

TEST(PointLaplacian, StructuralPropertiesOnSphere) {
  const Eigen::MatrixX3d P = random_sphere(3000, 1);
  const PointLaplacian pl = point_laplacian(P);
  expect_valid_laplacian(pl.laplacian, 3000);
  // Total mass approximates the sphere area 4π (tangent-plane triangles are chords: slightly less).
  EXPECT_NEAR(pl.laplacian.M.sum(), 4 * M_PI, 0.02 * 4 * M_PI);
  EXPECT_EQ(pl.isolated_points, 0);
  EXPECT_GT(pl.triangles.rows(), 3000);  // a closed surface has ~2 triangles per point
  EXPECT_GE(pl.triangles.minCoeff(), 0);
  EXPECT_LT(pl.triangles.maxCoeff(), 3000);
  // Unit PCA normals, radial on the sphere (up to sign).
  for (int i = 0; i < 3000; ++i) {
    EXPECT_NEAR(pl.normals.row(i).norm(), 1.0, 1e-12);
    ASSERT_GT(std::abs(pl.normals.row(i).dot(P.row(i))), 0.99) << "point " << i;
  }
  // Distinct triangles: no repeated corner sets.
  std::vector<std::array<int, 3>> keys;
  for (int t = 0; t < pl.triangles.rows(); ++t) {
    std::array<int, 3> s = {pl.triangles(t, 0), pl.triangles(t, 1), pl.triangles(t, 2)};
    std::sort(s.begin(), s.end());
    ASSERT_TRUE(s[0] != s[1] && s[1] != s[2]);
    keys.push_back(s);
  }
  std::sort(keys.begin(), keys.end());
  EXPECT_TRUE(std::adjacent_find(keys.begin(), keys.end()) == keys.end());
  std::printf("sphere 3000: %lld triangles, %lld flips, %d clamped edges, %d degenerate, h = %.4f, %.3f s\n",
              static_cast<long long>(pl.triangles.rows()), pl.intrinsic_flips, pl.clamped_edges, pl.degenerate_triangles,
              pl.laplacian.mean_edge_length, pl.build_seconds);
}

class BothModes : public ::testing::TestWithParam<bool> {
 protected:
  PointLaplacianOptions options() const {
    PointLaplacianOptions o;
    o.intrinsic_delaunay = GetParam();
    return o;
  }
  const char* mode() const { return GetParam() ? "intrinsic Delaunay (tufted)" : "local 2D cotan fallback"; }
};
INSTANTIATE_TEST_SUITE_P(PointLaplacian, BothModes, ::testing::Values(true, false));

TEST_P(BothModes, PlaneLinearAndQuadraticFunctions) {
  const int n = 5000;
  Eigen::MatrixX3d P;
  Eigen::MatrixX2d uv;
  random_plane(n, 3, P, uv);
  const PointLaplacian pl = point_laplacian(P, options());
  std::printf("[%s] plane %d points: %lld flips, %lld unflippable, %d clamped edges\n", mode(), n,
              pl.intrinsic_flips, pl.unflippable_edges, pl.clamped_edges);
  const Laplacian& lap = pl.laplacian;
  expect_valid_laplacian(lap, n);
  // Mass of the square [-1,1]² (area 4): boundary fans are incomplete, so a bit less.
  EXPECT_NEAR(lap.M.sum(), 4.0, 0.1);

  std::vector<int> interior;
  for (int i = 0; i < n; ++i)
    if (std::abs(uv(i, 0)) < 0.8 && std::abs(uv(i, 1)) < 0.8) interior.push_back(i);
  ASSERT_GT(interior.size(), 2500u);

  // Linear functions (in plane coordinates, and a 3D linear function) are harmonic.
  // Per interior point: |(Lu)_i| relative to the natural scale Σ_j w_ij |u_j − u_i|.
  const Eigen::VectorXd fx = uv.col(0), fy = uv.col(1);
  const Eigen::VectorXd f3 = P * Eigen::Vector3d(0.7, -1.3, 2.1);
  double worst_linear = 0, mean_linear = 0;
  for (const Eigen::VectorXd* f : {&fx, &fy, &f3}) {
    const Eigen::VectorXd Lf = lap.L * (*f);
    for (int i : interior) {
      double scale = 0;
      for (SpMat::InnerIterator it(lap.L, i); it; ++it)
        if (it.row() != i) scale += it.value() * std::abs((*f)[it.row()] - (*f)[i]);
      const double rel = std::abs(Lf[i]) / scale;
      worst_linear = std::max(worst_linear, rel);
      mean_linear += rel / (3.0 * interior.size());
    }
  }
  std::printf("plane: linear functions, per interior point |Lu|/scale: mean %.2e, max %.2e\n", mean_linear,
              worst_linear);
  // Consistent fans reproduce linear functions exactly; inconsistent ones (a few per cent of
  // the points) leave a small residual (measured mean 1.2e-4 tufted, 8e-5 fallback).
  EXPECT_LT(mean_linear, 0.002);
  EXPECT_LT(worst_linear, 0.5);
  if (GetParam()) {
    EXPECT_EQ(pl.clamped_edges, 0) << "the intrinsic Delaunay weights are non-negative without clamping";
    EXPECT_EQ(pl.most_negative_weight, 0.0);
    EXPECT_EQ(pl.unflippable_edges, 0);
  }

  // Δ(x² + y²) = 4: L u ≈ 4 M. Aggregated over interior points (the lumped barycentric mass
  // makes individual points noisy, see the per-point figures printed below).
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = uv(i, 0) * uv(i, 0) + uv(i, 1) * uv(i, 1);
  const Eigen::VectorXd Lq = lap.L * q;
  double sum_Lq = 0, sum_4M = 0, median_rel = 0;
  std::vector<double> per_point;
  for (int i : interior) {
    sum_Lq += Lq[i];
    sum_4M += 4 * lap.M[i];
    per_point.push_back(std::abs(Lq[i] - 4 * lap.M[i]) / (4 * lap.M[i]));
  }
  std::sort(per_point.begin(), per_point.end());
  median_rel = per_point[per_point.size() / 2];
  const double aggregated = std::abs(sum_Lq - sum_4M) / sum_4M;
  std::printf("plane: L(x²+y²) vs 4M: aggregated interior rel. error %.3e; per point median %.3e, 90%% %.3e\n",
              aggregated, median_rel, per_point[per_point.size() * 9 / 10]);
  EXPECT_LT(aggregated, 0.05);
}

TEST_P(BothModes, UnitSphereSpectrum) {
  const int n = 8000;
  const Eigen::MatrixX3d P = random_sphere(n, 5);
  const PointLaplacian pl = point_laplacian(P, options());
  std::printf("[%s] sphere %d points: %lld flips, %lld unflippable, %d clamped edges, %.3f s\n", mode(), n,
              pl.intrinsic_flips, pl.unflippable_edges, pl.clamped_edges, pl.build_seconds);
  expect_valid_laplacian(pl.laplacian, n);
  int iterations = 0;
  const Eigen::VectorXd lambda = smallest_eigenvalues(pl.laplacian, 16, 36, &iterations);
  std::printf("sphere %d points, k = 30: %d subspace iterations\n", n, iterations);
  EXPECT_LT(std::abs(lambda[0]), 1e-8);
  double worst = 0;
  int m = 1;
  for (int l = 1; l <= 3; ++l)
    for (int r = 0; r < 2 * l + 1; ++r, ++m) {
      const double exact = l * (l + 1.0);
      const double rel = std::abs(lambda[m] - exact) / exact;
      worst = std::max(worst, rel);
      std::printf("  λ_%-2d = %.5f  (l(l+1) = %g, rel. error %.2e)\n", m, lambda[m], exact, rel);
      EXPECT_LT(rel, 0.05) << "eigenvalue " << m;
    }
  std::printf("sphere spectrum: worst rel. error %.3e\n", worst);
}

TEST_P(BothModes, DeterministicAcrossRunsAndThreads) {
  const Eigen::MatrixX3d P = random_sphere(4000, 9);
  PointLaplacianOptions one = options();
  one.threads = 1;
  const PointLaplacian a = point_laplacian(P, one);
  std::vector<PointLaplacian> others;  // 1, 2 and 4 threads, and 2 threads once more
  for (int threads : {1, 2, 4, 2}) {
    PointLaplacianOptions o = options();
    o.threads = threads;
    others.push_back(point_laplacian(P, o));
  }
  for (const PointLaplacian* x : {&others[0], &others[1], &others[2], &others[3]}) {
    ASSERT_EQ(a.laplacian.L.nonZeros(), x->laplacian.L.nonZeros());
    EXPECT_TRUE(std::equal(a.laplacian.L.valuePtr(), a.laplacian.L.valuePtr() + a.laplacian.L.nonZeros(),
                           x->laplacian.L.valuePtr()));
    EXPECT_TRUE(std::equal(a.laplacian.L.innerIndexPtr(),
                           a.laplacian.L.innerIndexPtr() + a.laplacian.L.nonZeros(),
                           x->laplacian.L.innerIndexPtr()));
    EXPECT_TRUE(a.laplacian.M == x->laplacian.M);
    EXPECT_TRUE(a.triangles == x->triangles);
    EXPECT_TRUE(a.normals == x->normals);
    EXPECT_EQ(a.laplacian.mean_edge_length, x->laplacian.mean_edge_length);
  }
}

TEST_P(BothModes, HeatSolverFactorsAndDiffuses) {
  const int n = 4000;
  const Eigen::MatrixX3d P = random_sphere(n, 13);
  const PointLaplacian pl = point_laplacian(P, options());
  HeatSolver solver(pl.laplacian);  // throws SolverError if M − tL were not positive definite
  EXPECT_EQ(solver.num_vertices(), n);
  // Heat from the point nearest the north pole decreases with geodesic distance (on average)
  // and conserves the total heat: 1ᵀ M u = 1ᵀ rhs for rhs = e_v (since L·1 = 0).
  int v = 0;
  for (int i = 1; i < n; ++i)
    if (P(i, 2) > P(v, 2)) v = i;
  const Eigen::VectorXd u = solver.diffuse_from_vertex(v);
  EXPECT_NEAR(pl.laplacian.M.dot(u), 1.0, 1e-9);
  double near = 0, far = 0;
  int cn = 0, cf = 0;
  for (int i = 0; i < n; ++i) {
    if (P(i, 2) > 0.9) near += u[i], ++cn;
    if (P(i, 2) < -0.5) far += u[i], ++cf;
  }
  EXPECT_GT(near / cn, 10 * far / cf);
  EXPECT_GT(u.minCoeff(), -1e-12);  // non-negative weights → M-matrix → non-negative heat
}

TEST(Normals, PcaNormalsOnPlaneAndMstOrientationOnSphere) {
  // Plane: PCA normals equal the plane normal up to sign.
  Eigen::MatrixX3d Pp;
  Eigen::MatrixX2d uv;
  random_plane(2000, 21, Pp, uv);
  const Eigen::Vector3d a = Eigen::Vector3d(1, 2, 0.5).normalized();
  const Eigen::Vector3d b = a.cross(Eigen::Vector3d(0.2, -0.4, 1)).normalized();
  const Eigen::Vector3d plane_n = a.cross(b);
  const Eigen::MatrixX3d Np = estimate_normals(Pp, 20);
  for (int i = 0; i < Np.rows(); ++i) ASSERT_NEAR(std::abs(Np.row(i).dot(plane_n)), 1.0, 1e-9);

  // Sphere: randomly flipped normals become all outward (seeded at the top point, +z).
  const Eigen::MatrixX3d P = random_sphere(5000, 17);
  Eigen::MatrixX3d N = estimate_normals(P);
  std::mt19937 rng(3);
  for (int i = 0; i < N.rows(); ++i)
    if (rng() & 1) N.row(i) *= -1.0;
  orient_normals_mst(P, N);
  int outward = 0;
  for (int i = 0; i < N.rows(); ++i) outward += N.row(i).dot(P.row(i)) > 0;
  EXPECT_EQ(outward, N.rows()) << "all MST-oriented normals must point outward";
}

TEST(Normals, MstOrientationOnTorusCloud) {
  // Vertices of a torus (R = 1, r = 0.4), normals flipped at random: consistent afterwards.
  const TriangleMesh T = test::torus(120, 48);
  const Eigen::MatrixX3d& P = T.V;
  Eigen::MatrixX3d N = estimate_normals(P, 12);
  std::mt19937 rng(4);
  for (int i = 0; i < N.rows(); ++i)
    if (rng() & 1) N.row(i) *= -1.0;
  orient_normals_mst(P, N, 10);
  int outward = 0;
  for (int i = 0; i < P.rows(); ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    Eigen::Vector3d core(p.x(), p.y(), 0);
    core = core.normalized();  // closest point of the core circle (radius 1)
    outward += N.row(i).dot((p - core).transpose()) > 0;
  }
  EXPECT_TRUE(outward == P.rows() || outward == 0) << outward << " of " << P.rows() << " outward";
}

TEST(PointLaplacian, KnnIsExactAndExcludesSelf) {
  const Eigen::MatrixX3d P = random_sphere(600, 23);
  const Eigen::MatrixXi nb = k_nearest_neighbors(P, 8);
  ASSERT_EQ(nb.rows(), 600);
  ASSERT_EQ(nb.cols(), 8);
  for (int i = 0; i < 600; ++i) {
    std::vector<std::pair<double, int>> d;
    for (int j = 0; j < 600; ++j)
      if (j != i) d.emplace_back((P.row(j) - P.row(i)).squaredNorm(), j);
    std::sort(d.begin(), d.end());
    for (int q = 0; q < 8; ++q) ASSERT_EQ(nb(i, q), d[q].second) << "point " << i << " rank " << q;
  }
}

// A caller's own neighbour table (e.g. reconstruct_surface, which needs it for the normals
// first) gives the same Laplacian as the search inside; a wrong table is refused.
TEST(PointLaplacian, PrecomputedNeighboursGiveTheSameLaplacian) {
  const Eigen::MatrixX3d P = random_sphere(2000, 31);
  PointLaplacianOptions o;
  o.k = 16;
  const PointLaplacian inside = point_laplacian(P, o);
  const Eigen::MatrixXi nb = k_nearest_neighbors(P, 20);  // more columns than k: the first k are used
  o.neighbors = &nb;
  const PointLaplacian given = point_laplacian(P, o);
  EXPECT_EQ((inside.laplacian.L - given.laplacian.L).norm(), 0.0);
  EXPECT_TRUE(inside.laplacian.M == given.laplacian.M);
  EXPECT_TRUE(inside.triangles == given.triangles);
  const Eigen::MatrixXi narrow = nb.leftCols(10);
  o.neighbors = &narrow;
  EXPECT_THROW(point_laplacian(P, o), InvalidInputError);
  Eigen::MatrixXi out_of_range = nb;
  out_of_range(7, 3) = 2000;
  o.neighbors = &out_of_range;
  EXPECT_THROW(point_laplacian(P, o), InvalidInputError);
}

TEST(PointLaplacian, RejectsBadInput) {
  const Eigen::MatrixX3d P = random_sphere(100, 2);
  PointLaplacianOptions o;
  o.k = 2;
  EXPECT_THROW(point_laplacian(P, o), InvalidInputError);
  o.k = 100;  // needs 101 points
  EXPECT_THROW(point_laplacian(P, o), InvalidInputError);
  o.k = 10;
  o.threads = -1;
  EXPECT_THROW(point_laplacian(P, o), InvalidInputError);
  Eigen::MatrixX3d bad = P;
  bad(42, 1) = std::nan("");
  EXPECT_THROW(point_laplacian(bad), InvalidInputError);
  try {
    point_laplacian(bad);
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("42"), std::string::npos) << e.what();
  }
  // Collinear cloud: no local triangle at all.
  Eigen::MatrixX3d line(50, 3);
  for (int i = 0; i < 50; ++i) line.row(i) << i * 0.1, 2 * i * 0.1, -i * 0.1;
  o.threads = 0;
  EXPECT_THROW(point_laplacian(line, o), InvalidInputError);
  Eigen::MatrixX3d N = estimate_normals(P, 10);
  Eigen::MatrixX3d wrong = N.topRows(50);
  EXPECT_THROW(orient_normals_mst(P, wrong), InvalidInputError);
  EXPECT_THROW(estimate_normals(P, 1), InvalidInputError);
}

TEST_P(BothModes, DuplicatePointsKeepMassPositive) {
  // Exact duplicates must not break anything: M > 0 everywhere, valid Laplacian.
  Eigen::MatrixX3d P = random_sphere(2000, 31);
  Eigen::MatrixX3d D(2100, 3);
  D.topRows(2000) = P;
  D.bottomRows(100) = P.topRows(100);
  const PointLaplacian pl = point_laplacian(D, options());
  expect_valid_laplacian(pl.laplacian, 2100);
  HeatSolver solver(pl.laplacian);
  EXPECT_EQ(solver.num_vertices(), 2100);
}

// A cloud of the size of the reconstruction benchmark (50k points): a valid Laplacian (its build
// time is measured by bench/, not here).
TEST_P(BothModes, FiftyThousandPointsGiveAValidLaplacian) {
  const Eigen::MatrixX3d P = random_sphere(50000, 41);
  const PointLaplacian pl = point_laplacian(P, options());
  std::printf("[%s] 50k points, k = 30: %lld triangles, %lld flips, %d clamped\n", mode(),
              static_cast<long long>(pl.triangles.rows()), pl.intrinsic_flips, pl.clamped_edges);
  expect_valid_laplacian(pl.laplacian, 50000);
}

TEST(PointLaplacianRealData, Sphere926Pwn) {
  // sphere926.pwn: 926 points on a sphere (radius ≈ 10) with outward normals in the file.
  const PointCloud cloud = read_cloud(test::data_path("clouds/sphere926.pwn"));
  const Eigen::MatrixX3d& P = cloud.P;
  ASSERT_GT(P.rows(), 900);
  const Eigen::RowVector3d centre = P.colwise().mean();
  const double r = (P.rowwise() - centre).rowwise().norm().mean();
  const PointLaplacian pl = point_laplacian(P);
  expect_valid_laplacian(pl.laplacian, static_cast<int>(P.rows()));
  // Latitude–longitude grid: cocircular quadruples. The intrinsic Delaunay weights may only be
  // negative at rounding level; the soup over-covers (inconsistent diagonals, see the header):
  // ΣM is measured at 1.32 × the area, bounded here on both sides.
  EXPECT_GT(pl.most_negative_weight, -1e-9);
  std::printf("sphere926: ΣM / (4πr²) = %.4f, %d rounding-level clamps (most negative %.2e)\n",
              pl.laplacian.M.sum() / (4 * M_PI * r * r), pl.clamped_edges, pl.most_negative_weight);
  EXPECT_GT(pl.laplacian.M.sum(), 0.97 * 4 * M_PI * r * r);
  EXPECT_LT(pl.laplacian.M.sum(), 1.4 * 4 * M_PI * r * r);
  int iterations = 0;
  const Eigen::VectorXd lambda = smallest_eigenvalues(pl.laplacian, 9, 20, &iterations);
  for (int m = 1; m <= 8; ++m) {
    const double exact = (m <= 3 ? 2.0 : 6.0) / (r * r);
    std::printf("sphere926 (r = %.3f): λ_%d·r² = %.4f (l(l+1) = %g)\n", r, m, lambda[m] * r * r, exact * r * r);
    EXPECT_NEAR(lambda[m], exact, 0.05 * exact) << "eigenvalue " << m;
  }
  HeatSolver solver(pl.laplacian);
  EXPECT_EQ(solver.num_vertices(), P.rows());
  // MST orientation agrees with the file's outward normals everywhere.
  ASSERT_TRUE(cloud.has_normals());
  Eigen::MatrixX3d N = pl.normals;
  orient_normals_mst(P, N);
  int agree = 0;
  for (int i = 0; i < P.rows(); ++i) agree += N.row(i).dot(cloud.N.row(i)) > 0;
  EXPECT_EQ(agree, P.rows());
}

TEST(PointLaplacianRealData, KittenXyz) {
  const PointCloud cloud = read_cloud(test::data_path("clouds/kitten.xyz"));
  const Eigen::MatrixX3d& P = cloud.P;
  ASSERT_GT(P.rows(), 5000);
  for (bool intrinsic : {true, false}) {
    PointLaplacianOptions o;
    o.intrinsic_delaunay = intrinsic;
    const PointLaplacian pl = point_laplacian(P, o);
    std::printf("kitten %lld points [%s]: %lld triangles, %lld flips, %d clamped, %d isolated, %.3f s\n",
                static_cast<long long>(P.rows()), intrinsic ? "tufted" : "fallback",
                static_cast<long long>(pl.triangles.rows()), pl.intrinsic_flips, pl.clamped_edges,
                pl.isolated_points, pl.build_seconds);
    expect_valid_laplacian(pl.laplacian, static_cast<int>(P.rows()));
    HeatSolver solver(pl.laplacian);
    const Eigen::VectorXd u = solver.diffuse_from_vertex(0);
    EXPECT_NEAR(pl.laplacian.M.dot(u), 1.0, 1e-9);
    EXPECT_GT(u.minCoeff(), -1e-12);
  }
  // Orientation: consistent with the file normals (all agree or all disagree, up to a few
  // points on thin parts where kNN neighbourhoods straddle both sides).
  if (cloud.has_normals()) {
    Eigen::MatrixX3d N = estimate_normals(P);
    orient_normals_mst(P, N);
    int agree = 0;
    for (int i = 0; i < P.rows(); ++i) agree += N.row(i).dot(cloud.N.row(i)) > 0;
    const double frac = static_cast<double>(agree) / P.rows();
    std::printf("kitten: %.4f of the MST-oriented normals agree with the file normals\n", frac);
    EXPECT_TRUE(frac > 0.98 || frac < 0.02) << frac;
  }
}

TEST(PointLaplacianRealData, EveryCloudInTheSharedData) {
  // Scans, synthetic shapes, organised PCD frames, terrain: the construction must succeed and
  // give a valid Laplacian that the heat solver can factor, on every shared cloud.
  // (Clouds above 60k points are left out to keep the test fast; measured separately, all
  // 7 of them, up to 290k points, build with 0 unflippable edges.)
  const char* files[] = {"b9.ply", "blobby.xyz", "building.xyz", "cube.pwn", "elephant.pwn",
                         "fin90_with_PCA_normals.xyz", "hippo1.ply", "hippo2.ply", "oni.pwn",
                         "open3d_cloud_bin_0.pcd", "pcl_bun0.pcd", "pcl_car6.pcd", "pcl_milk.pcd",
                         "pcl_noisy_slice_displaced.pcd", "pcl_sac_plane_test.pcd",
                         "pcldata_room_scan1.pcd", "pcldata_rops_points.pcd", "poste_france.xyz",
                         "sphere.pwn"};
  for (const char* f : files) {
    SCOPED_TRACE(f);
    PointCloud cloud = read_cloud(test::data_path(std::string("clouds/") + f));
    if (cloud.P.rows() < 31) continue;  // too small for k = 30 (none of the listed files)
    normalize_cloud(cloud);  // UTM coordinates otherwise lose precision in the projections
    const PointLaplacian pl = point_laplacian(cloud.P);
    std::printf("%-42s %7lld pts %7lld tris %6lld flips %4d clamped (min %.1e) %3d isolated %.2f s\n", f,
                static_cast<long long>(cloud.P.rows()), static_cast<long long>(pl.triangles.rows()),
                pl.intrinsic_flips, pl.clamped_edges, pl.most_negative_weight, pl.isolated_points,
                pl.build_seconds);
    expect_valid_laplacian(pl.laplacian, static_cast<int>(cloud.P.rows()));
    EXPECT_EQ(pl.unflippable_edges, 0);
    HeatSolver solver(pl.laplacian);
    EXPECT_EQ(solver.num_vertices(), cloud.P.rows());
  }
}

TEST(PointLaplacian, OneOrTwoThreadsGiveTheSameBits) {
  // 20,000 points: the tufted cover's sorts are large enough to run on both threads.
  const Eigen::MatrixX3d P = random_sphere(20000, 31);
  PointLaplacianOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const PointLaplacian a = point_laplacian(P, one), b = point_laplacian(P, two);
  ASSERT_TRUE(one.intrinsic_delaunay);
  ASSERT_EQ(a.laplacian.L.nonZeros(), b.laplacian.L.nonZeros());
  EXPECT_EQ((SpMat(a.laplacian.L - b.laplacian.L)).norm(), 0.0);
  EXPECT_EQ((a.laplacian.M - b.laplacian.M).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.intrinsic_flips, b.intrinsic_flips);
}
