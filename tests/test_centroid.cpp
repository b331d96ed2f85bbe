// Heat centroids (paper §5, Fig. 4) and the quadratic sub-vertex refinement of §7.1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "heatcvt/centroid.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/voronoi.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Distance (in mean edge lengths) allowed between the heat centroid of a symmetric cell and its
// symmetry axis: the mirror images agree up to the rounding of the sparse solves and of the
// voronoi tie rule, far below an edge length.
constexpr double kSymmetricCentroidTolerance = 1e-6;

// Unit disk: an n×n grid of [−1,1]² mapped by the elliptical square-to-disk map
// (x√(1 − y²/2), y√(1 − x²/2)); alternating diagonals.
TriangleMesh disk(int n) {
  TriangleMesh m = test::grid(n, -1, 1, -1, 1);
  for (int i = 0; i < m.V.rows(); ++i) {
    const double x = m.V(i, 0), y = m.V(i, 1);
    m.V(i, 0) = x * std::sqrt(1 - y * y / 2);
    m.V(i, 1) = y * std::sqrt(1 - x * x / 2);
  }
  return m;
}

Eigen::Vector3d face_centroid(const TriangleMesh& m, int f) {
  return (m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))).transpose() / 3.0;
}

// Area centroid of a set of faces.
Eigen::Vector3d area_centroid(const TriangleMesh& m, const std::vector<int>& faces) {
  const Eigen::VectorXd A = face_areas(m.V, m.F);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double total = 0;
  for (int f : faces) {
    c += A[f] * face_centroid(m, f);
    total += A[f];
  }
  return c / total;
}

}  // namespace

TEST(HeatCentroid, InvalidInputIsRejected) {
  auto m = test::grid(8);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  EXPECT_THROW(heat_centroid_of_faces(m.V, m.F, solver, {}), InvalidInputError);
  EXPECT_THROW(heat_centroid_of_faces(m.V, m.F, solver, {static_cast<int>(m.F.rows())}), InvalidInputError);
  CentroidOptions bad;
  bad.steps = 0;
  EXPECT_THROW(heat_centroid_of_faces(m.V, m.F, solver, {0}, bad), InvalidInputError);
  auto other = test::grid(4);
  EXPECT_THROW(heat_centroid_of_faces(other.V, other.F, solver, {0}), InvalidInputError);
}

// Fig. 4 (ellipses): with enough implicit steps the heat centroid of a well-shaped polygon is
// within 2 h̄ of its Euclidean (area) centroid.
TEST(HeatCentroid, EllipsePolygonsOnDiskNearEuclideanCentroid) {
  const TriangleMesh m = disk(64);
  const double h = mean_edge_length(m.V, m.F);
  HeatSolver solver(cotan_laplacian(m.V, m.F));  // t = h̄²
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  CentroidOptions few, many;
  few.steps = 1;
  many.steps = 40;
  double worst_many = 0, sum_few = 0, sum_many = 0;
  const int trials = 12;
  for (int trial = 0; trial < trials; ++trial) {
    const double r = 0.35 * std::sqrt(U(rng)), phi = 2 * M_PI * U(rng);
    const Eigen::Vector2d c(r * std::cos(phi), r * std::sin(phi));
    const double a = 0.15 + 0.2 * U(rng), b = 0.08 + 0.12 * U(rng), th = M_PI * U(rng);
    std::vector<int> faces;
    for (int f = 0; f < m.F.rows(); ++f) {
      const Eigen::Vector3d x = face_centroid(m, f);
      const Eigen::Vector2d q(x.x() - c.x(), x.y() - c.y());
      const double u = std::cos(th) * q.x() + std::sin(th) * q.y(), v = -std::sin(th) * q.x() + std::cos(th) * q.y();
      if (u * u / (a * a) + v * v / (b * b) < 1) faces.push_back(f);
    }
    ASSERT_GT(faces.size(), 20u);
    const Eigen::Vector3d truth = area_centroid(m, faces);
    const double e_few = (position(m.V, m.F, heat_centroid_of_faces(m.V, m.F, solver, faces, few)) - truth).norm();
    const double e_many = (position(m.V, m.F, heat_centroid_of_faces(m.V, m.F, solver, faces, many)) - truth).norm();
    std::printf("ellipse %d: faces=%zu error/h: 1 step %.3f, %d steps %.3f\n", trial, faces.size(), e_few / h,
                many.steps, e_many / h);
    EXPECT_LT(e_many, 2 * h);
    worst_many = std::max(worst_many, e_many);
    sum_few += e_few;
    sum_many += e_many;
  }
  std::printf("ellipses: mean error/h 1 step %.3f, %d steps %.3f, worst %.3f\n", sum_few / trials / h, many.steps,
              sum_many / trials / h, worst_many / h);
  EXPECT_LT(sum_many, sum_few) << "more implicit steps (larger effective t) approach the Euclidean centroid";
  EXPECT_LT(sum_many / trials, 0.2 * h) << "mean error with 40 steps (measured 0.10 h)";
}

// A square block of faces centred in the middle of a grid cell: the hottest vertex is at least
// h/√2 away from the centroid, the quadratic refinement gets much closer.
TEST(HeatCentroid, QuadraticRefinementBeatsHottestVertexOnSymmetricPolygon) {
  const int n = 40;
  const TriangleMesh m = test::grid(n, -1, 1, -1, 1);
  const double cell = 2.0 / n;
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  for (const Eigen::Vector2d centre : {Eigen::Vector2d(cell / 2, cell / 2), Eigen::Vector2d(-cell / 2, 3 * cell / 2)}) {
    std::vector<int> faces;
    for (int f = 0; f < m.F.rows(); ++f) {
      const Eigen::Vector3d x = face_centroid(m, f);
      if (std::abs(x.x() - centre.x()) < 0.2 && std::abs(x.y() - centre.y()) < 0.2) faces.push_back(f);
    }
    const Eigen::Vector3d truth = area_centroid(m, faces);
    EXPECT_LT((truth.head<2>() - centre).norm(), 1e-12);
    CentroidOptions plain, refined;
    plain.quadratic_refinement = false;
    plain.steps = refined.steps = 10;
    const double e_vertex = (position(m.V, m.F, heat_centroid_of_faces(m.V, m.F, solver, faces, plain)) - truth).norm();
    const double e_refined =
        (position(m.V, m.F, heat_centroid_of_faces(m.V, m.F, solver, faces, refined)) - truth).norm();
    std::printf("symmetric block: hottest vertex error %.4g, refined %.4g (cell %.4g)\n", e_vertex, e_refined, cell);
    EXPECT_GE(e_vertex, cell / std::sqrt(2.0) - 1e-12);
    EXPECT_LT(e_refined, 0.5 * e_vertex);
  }
}

// The refinement recovers the maximum of an exact quadratic placed anywhere in the one-ring.
TEST(HeatCentroid, RefinementRecoversMaximumOfQuadratic) {
  const TriangleMesh m = test::grid(10, -1, 1, -1, 1);
  const auto vf = vertex_faces(static_cast<int>(m.V.rows()), m.F);
  const Eigen::MatrixX3d N = vertex_normals(m.V, m.F);
  const int v = 5 * 11 + 5;  // centre vertex (0, 0)
  ASSERT_LT(m.V.row(v).norm(), 1e-12);
  for (const Eigen::Vector2d peak : {Eigen::Vector2d(0.05, -0.03), Eigen::Vector2d(-0.07, 0.02)}) {
    Eigen::VectorXd heat(m.V.rows());
    for (int i = 0; i < m.V.rows(); ++i) {
      const double dx = m.V(i, 0) - peak.x(), dy = m.V(i, 1) - peak.y();
      heat[i] = 1 - 2 * dx * dx - dx * dy - 3 * dy * dy;
    }
    const SurfacePoint p = refine_hottest_vertex(m.V, m.F, vf, N, heat, v);
    EXPECT_LT((position(m.V, m.F, p).head<2>() - peak).norm(), 1e-10);
  }
  // a saddle has no maximum: fall back to the vertex
  Eigen::VectorXd saddle = m.V.col(0).cwiseProduct(m.V.col(0)) - m.V.col(1).cwiseProduct(m.V.col(1));
  EXPECT_LT(position(m.V, m.F, refine_hottest_vertex(m.V, m.F, vf, N, saddle, v)).norm(), 1e-14);
  // a maximum outside the one-ring: clamped onto the incident faces
  Eigen::VectorXd far(m.V.rows());
  for (int i = 0; i < m.V.rows(); ++i) far[i] = -std::pow(m.V(i, 0) - 0.9, 2) - std::pow(m.V(i, 1), 2);
  const SurfacePoint q = refine_hottest_vertex(m.V, m.F, vf, N, far, v);
  EXPECT_NE(std::find(vf[v].begin(), vf[v].end(), q.face), vf[v].end());
  EXPECT_NEAR(position(m.V, m.F, q).x(), 0.2, 1e-12);  // the one-ring reaches x = 0.2
}

// Heat centroids of the cells of a Voronoi diagram on the sphere lie near the (normalised) area
// centroids of the cells.
TEST(HeatCentroid, CellsOnIcosphereNearAreaCentroid) {
  auto m = test::icosphere(4);
  const double h = mean_edge_length(m.V, m.F);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> face(0, static_cast<int>(m.F.rows()) - 1);
  std::vector<SurfacePoint> sites(20);
  for (auto& s : sites) s.face = face(rng);
  VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  CentroidOptions opt;
  opt.steps = 5;
  const auto cents = heat_centroids(m.V, m.F, solver, d, opt);
  ASSERT_EQ(cents.size(), sites.size());
  const auto faces = cell_faces(d);
  double worst = 0;
  for (int c = 0; c < d.num_cells(); ++c) {
    Eigen::Vector3d ac = Eigen::Vector3d::Zero();
    for (int r : faces[c])
      ac += d.face_area[r] * (d.V.row(d.F(r, 0)) + d.V.row(d.F(r, 1)) + d.V.row(d.F(r, 2))).transpose() / 3.0;
    ac.normalize();
    const double e = (position(m.V, m.F, cents[c]) - ac).norm();
    worst = std::max(worst, e);
    EXPECT_LT(e, 3 * h) << "cell " << c;
  }
  std::printf("icosphere cells: worst |heat centroid - normalised area centroid| = %.3f h\n", worst / h);
}

// The exact cell load vectors integrate linear functions exactly (∫_cell f = Σ_v w_v f(v) for
// linear f, the integral summed here over the refined pieces of the cell).
TEST(HeatCentroid, LoadVectorsIntegrateLinearFunctionsExactly) {
  auto m = test::icosphere(3);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> face(0, static_cast<int>(m.F.rows()) - 1);
  std::vector<SurfacePoint> sites(12);
  for (auto& s : sites) s.face = face(rng);
  VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  const auto faces = cell_faces(d);
  for (int c = 0; c < d.num_cells(); ++c) {
    Eigen::Vector3d exact = Eigen::Vector3d::Zero();  // ∫_cell (x, y, z) over the refined pieces
    for (int r : faces[c])
      exact += d.face_area[r] * (d.V.row(d.F(r, 0)) + d.V.row(d.F(r, 1)) + d.V.row(d.F(r, 2))).transpose() / 3.0;
    Eigen::Vector3d via_load = Eigen::Vector3d::Zero();
    for (auto& [v, w] : cell_load_vector(d, m.F, c)) via_load += w * m.V.row(v).transpose();
    EXPECT_LT((exact - via_load).norm(), 1e-12);
  }
}

// Analytic centroids: six sites on the coordinate axes of an icosphere, which is symmetric under
// the reflections x → −x, y → −y, z → −z and the cyclic permutation of the axes. Each cell is then
// symmetric under the two reflections that fix its axis, so its centroid (the heat centroid as
// well as the area centroid) lies on that axis: it is the site itself.
TEST(HeatCentroid, SymmetricCellsHaveTheirSiteAsCentroid) {
  const auto m = test::icosphere(4);
  const double h = mean_edge_length(m.V, m.F);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::vector<SurfacePoint> sites;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {1.0, -1.0}) {
      Eigen::Vector3d target = Eigen::Vector3d::Zero();
      target[axis] = sign;
      SurfacePoint site;
      for (int f = 0; f < m.F.rows() && site.face < 0; ++f)
        for (int k = 0; k < 3; ++k)
          if ((m.V.row(m.F(f, k)).transpose() - target).norm() < 1e-12) {
            site.face = f;
            site.bary = Eigen::Vector3d::Zero();
            site.bary[k] = 1;
          }
      ASSERT_GE(site.face, 0) << "the icosphere has a vertex on every coordinate axis";
      sites.push_back(site);
    }
  const VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  CentroidOptions opt;
  opt.steps = 5;
  const auto cents = heat_centroids(m.V, m.F, solver, d, opt);
  ASSERT_EQ(cents.size(), sites.size());
  double worst = 0;
  for (size_t c = 0; c < sites.size(); ++c) {
    const double e = (position(m.V, m.F, cents[c]) - position(m.V, m.F, sites[c])).norm();
    worst = std::max(worst, e);
    EXPECT_LT(e, kSymmetricCentroidTolerance * h) << "cell " << c;
  }
  std::printf("[ info ] six axis cells: worst |heat centroid - axis point| = %.3g h\n", worst / h);
}
