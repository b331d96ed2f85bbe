// Properties of the cotan Laplacian and lumped mass (paper eq. 5–6) and of the heat solver.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>
#include <string>

#include "heatcvt/heat_solver.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

void expect_laplacian_properties(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const std::string& name) {
  SCOPED_TRACE(name);
  Laplacian lap = cotan_laplacian(V, F);
  const Eigen::SparseMatrix<double>& L = lap.L;
  ASSERT_EQ(L.rows(), V.rows());
  // symmetric
  Eigen::SparseMatrix<double> asym = L - Eigen::SparseMatrix<double>(L.transpose());
  EXPECT_LT(asym.norm(), 1e-12 * L.norm());
  // constants in the null space
  Eigen::VectorXd ones = Eigen::VectorXd::Ones(V.rows());
  EXPECT_LT((L * ones).cwiseAbs().maxCoeff(), 1e-10 * L.coeffs().cwiseAbs().maxCoeff());
  // finite, positive mass, total = area
  for (int k = 0; k < L.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, k); it; ++it) ASSERT_TRUE(std::isfinite(it.value()));
  EXPECT_GT(lap.M.minCoeff(), 0.0);
  EXPECT_NEAR(lap.M.sum(), surface_area(V, F), 1e-9 * surface_area(V, F));
  // negative semi-definite: xᵀ L x ≤ 0 for random x
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x = Eigen::VectorXd::Random(V.rows());
    EXPECT_LE(x.dot(L * x), 1e-10 * x.squaredNorm() * L.norm());
  }
}

}  // namespace

TEST(Laplacian, PropertiesOnBuiltInShapes) {
  auto sphere = test::icosphere(3);
  expect_laplacian_properties(sphere.V, sphere.F, "icosphere");
  auto plane = test::grid(20);
  expect_laplacian_properties(plane.V, plane.F, "grid");
  auto tor = test::torus(30, 15);
  expect_laplacian_properties(tor.V, tor.F, "torus");
}

TEST(Laplacian, LinearFunctionsHarmonicInsideFlatGrid) {
  auto plane = test::grid(16);
  Laplacian lap = cotan_laplacian(plane.V, plane.F);
  Eigen::VectorXd x = plane.V.col(0) + 2 * plane.V.col(1);
  Eigen::VectorXd Lx = lap.L * x;
  for (int i = 0; i < plane.V.rows(); ++i) {
    const double px = plane.V(i, 0), py = plane.V(i, 1);
    if (px > 1e-9 && px < 1 - 1e-9 && py > 1e-9 && py < 1 - 1e-9) {
      EXPECT_NEAR(Lx[i], 0.0, 1e-12);
    }
  }
}

TEST(Laplacian, DegenerateFacesAreReportedNeverNaN) {
  TriangleMesh m = test::grid(4);
  // a zero-area face (collinear) and a repeated-index face appended
  m.F.conservativeResize(m.F.rows() + 2, 3);
  m.F.row(m.F.rows() - 2) << 0, 1, 2;  // collinear along the bottom edge
  m.F.row(m.F.rows() - 1) << 3, 3, 4;
  Laplacian lap = cotan_laplacian(m.V, m.F);
  EXPECT_EQ(lap.degenerate_faces.size(), 2u);
  EXPECT_TRUE(Eigen::MatrixXd(lap.L).allFinite());
  EXPECT_TRUE(lap.M.allFinite());
  EXPECT_GT(lap.M.minCoeff(), 0.0);
}

// A face across the sphere whose third corner is the midpoint of the other two, written to 9
// significant digits as in a text file: collinear to rounding, with a nonzero area of rounding
// size and an angle within 1e-5 rad of 180°. It is skipped like a zero-area face, and M − tL
// stays positive definite: the heat solver factors it and the heat stays positive.
TEST(Laplacian, AFaceCollinearToRoundingIsSkippedAndTheHeatSolverFactors) {
  TriangleMesh m = test::icosphere(2);
  const int a = 0, b = static_cast<int>(m.V.rows()) / 2, mid = static_cast<int>(m.V.rows());
  Eigen::RowVector3d midpoint = 0.5 * (m.V.row(a) + m.V.row(b));
  for (int k = 0; k < 3; ++k) midpoint[k] = std::stod(std::to_string(midpoint[k]).substr(0, 11));
  m.V.conservativeResize(mid + 1, 3);
  m.V.row(mid) = midpoint;
  m.F.conservativeResize(m.F.rows() + 1, 3);
  m.F.row(m.F.rows() - 1) << a, b, mid;
  const Eigen::Vector3d u = (m.V.row(a) - m.V.row(mid)).transpose(), v = (m.V.row(b) - m.V.row(mid)).transpose();
  ASSERT_GT(u.cross(v).norm(), 0.0) << "the face must keep an area of rounding size";
  ASSERT_LT(std::atan2(u.cross(v).norm(), u.dot(v)), 3.14159265358979 + 1e-12);
  ASSERT_GT(std::atan2(u.cross(v).norm(), u.dot(v)), 3.14159265358979 - 1e-5) << "its corner must be near 180°";
  const Laplacian lap = cotan_laplacian(m.V, m.F);
  ASSERT_EQ(lap.degenerate_faces.size(), 1u);
  EXPECT_EQ(lap.degenerate_faces[0], m.F.rows() - 1);
  const HeatSolver solver(lap);
  const Eigen::VectorXd heat = solver.diffuse_from_vertex(a);
  EXPECT_TRUE(heat.allFinite());
  EXPECT_GT(heat.head(mid).minCoeff(), 0.0);
}

TEST(HeatSolver, MatchesEigenCholeskyAndConservesHeat) {
  auto sphere = test::icosphere(3);
  Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  HeatSolver solver(lap);
  Eigen::SparseMatrix<double> A = -solver.time_step() * lap.L;
  for (int i = 0; i < A.rows(); ++i) A.coeffRef(i, i) += lap.M[i];
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ref(A);
  Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
  Eigen::VectorXd u = solver.solve(b), r = ref.solve(b);
  EXPECT_LT((u - r).norm(), 1e-10 * r.norm());
  // 1ᵀ(M − tL)u = 1ᵀ M u = 1ᵀ b since L·1 = 0: total heat is conserved by implicit Euler.
  Eigen::VectorXd heat = solver.diffuse_from_vertex(7);
  EXPECT_NEAR(lap.M.dot(heat), 1.0, 1e-10);
  EXPECT_GT(heat.minCoeff(), 0.0);  // positivity of heat on a Delaunay mesh
  // batched solves equal single solves
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 11);
  Eigen::MatrixXd U = solver.solve(B);
  for (int c = 0; c < B.cols(); ++c) EXPECT_LT((U.col(c) - solver.solve(Eigen::VectorXd(B.col(c)))).norm(), 1e-12 * U.col(c).norm());
}

TEST(HeatSolver, BlasThreadCountDoesNotChangeTheFactorAndIsRestored) {
  // icosphere(5): 10k vertices, large enough for CHOLMOD's supernodal path to call the BLAS.
  auto sphere = test::icosphere(5);
  Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  const std::string before = blas_description();
  HeatSolverOptions one, library_setting;
  one.blas_threads = 1;
  library_setting.blas_threads = 0;
  HeatSolver a(lap, one), b(lap, library_setting);
  EXPECT_EQ(blas_description(), before);  // the scoped setting was undone
  ASSERT_EQ(a.factor().nonzeros(), b.factor().nonzeros());
  Eigen::VectorXd rhs = Eigen::VectorXd::Random(lap.L.rows());
  Eigen::VectorXd ua = a.solve(rhs), ub = b.solve(rhs);
  EXPECT_LT((ua - ub).norm(), 1e-12 * ub.norm());
}

TEST(HeatSolver, FillOrderingsSolveTheSameSystem) {
  auto sphere = test::icosphere(5);
  Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  HeatSolverOptions amd, metis;
  amd.ordering = FillOrdering::amd;
  metis.ordering = FillOrdering::metis;
  HeatSolver a(lap, amd), b(lap, metis);
  Eigen::VectorXd rhs = Eigen::VectorXd::Random(lap.L.rows());
  Eigen::VectorXd ua = a.solve(rhs), ub = b.solve(rhs);
  EXPECT_LT((ua - ub).norm(), 1e-10 * ub.norm());
  std::printf("[ info ] icosphere(5) factor entries: AMD %zu, METIS %zu\n", a.factor().nonzeros(), b.factor().nonzeros());
  EXPECT_LT(b.factor().nonzeros(), a.factor().nonzeros());  // nested dissection fills less on a 2-manifold
}

TEST(HeatSolver, RejectsNonPositiveTimeStep) {
  auto sphere = test::icosphere(1);
  Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  HeatSolverOptions opt;
  opt.time_coefficient = -1;
  EXPECT_THROW(HeatSolver(lap, opt), InvalidInputError);
}
