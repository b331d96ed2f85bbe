// Centroidal Voronoi tessellations by Lloyd iteration (paper §7.1): equal cell areas on the unit-area
// sphere and torus, closed duals of the input's genus, determinism, anisotropy, bad input.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <vector>
#include <algorithm>

#include "heatcvt/cvt.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/remesh.h"
#include "heatcvt/subdivision.h"
#include "heatcvt/validate.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

CvtResult run(const TriangleMesh& m, int sites, int iterations, int threads = 0, std::uint32_t seed = 1) {
  CvtOptions o;
  o.sites = sites;
  o.iterations = iterations;
  o.threads = threads;
  o.seed = seed;
  return centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
}

// Relative spread (standard deviation / mean) of the cell areas that a Lloyd-converged CVT
// reaches on a smooth closed unit-area surface after 100 iterations, for 20 to 500 sites: the
// cells of a CVT are near-congruent hexagons whose areas differ by a few per cent where the
// hexagonal pattern must bend around the topology (12 pentagons on a sphere) or the curvature
// varies (the torus's inner and outer sides); measured 3.4 % and 5.7 % on the sphere, 4.4 % and
// 7.0 % on the torus (20 and 500 sites).
constexpr double kMaxRelativeAreaSpread = 0.075;

void expect_equal_areas(const TriangleMesh& m, int sites, const char* name) {
  CvtResult r = run(m, sites, 100);
  const double var = r.final_area_variance;
  const double spread = std::sqrt(var) / (1.0 / sites);  // unit total area: mean cell area 1/sites
  std::printf("[ info ] %s, %d sites, 100 iterations: cell-area variance %.3g (initial %.3g), relative spread "
              "%.3f, %.3f s/iteration\n",
              name, sites, var, r.iterations.front().area_variance, spread,
              (r.total_seconds - r.setup_seconds) / r.iterations.size());
  EXPECT_LE(spread, kMaxRelativeAreaSpread) << name;
  EXPECT_LT(var, 0.05 * r.iterations.front().area_variance) << name << ": Lloyd did not equalise";
  EXPECT_NEAR(r.diagram.cell_area.sum(), 1.0, 1e-9);
  // Lloyd settles: the last moves are much smaller than the first
  EXPECT_LT(r.iterations.back().max_move, 0.2 * r.iterations.front().max_move) << name;
}

// The triangles of F as a set, each rotated to start at its smallest vertex (orientation kept).
std::set<std::array<int, 3>> triangle_set(const Eigen::MatrixX3i& F) {
  std::set<std::array<int, 3>> out;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    int k = 0;
    F.row(f).minCoeff(&k);
    out.insert({F(f, k), F(f, (k + 1) % 3), F(f, (k + 2) % 3)});
  }
  return out;
}

}  // namespace

TEST(Cvt, SphereUnitAreaEqualCellAreas) {
  auto sphere = test::icosphere(5);  // 10k vertices
  test::scale_to_area(sphere, 1.0);
  expect_equal_areas(sphere, 20, "sphere");
  expect_equal_areas(sphere, 500, "sphere");
}

TEST(Cvt, TorusUnitAreaEqualCellAreas) {
  auto torus = test::torus(160, 64);  // 10k vertices
  test::scale_to_area(torus, 1.0);
  expect_equal_areas(torus, 20, "torus");
  expect_equal_areas(torus, 500, "torus");
}

TEST(Cvt, SameSeedSameOutputForAnyThreadCount) {
  auto sphere = test::icosphere(4);
  CvtResult a = run(sphere, 60, 8, 1, 7);
  for (int threads : test::kThreadCounts) {
    SCOPED_TRACE(threads);
    CvtResult b = run(sphere, 60, 8, threads, 7);
    ASSERT_EQ(a.sites.size(), b.sites.size());
    for (size_t s = 0; s < a.sites.size(); ++s) {
      EXPECT_EQ(a.sites[s].face, b.sites[s].face);
      EXPECT_EQ(a.sites[s].bary, b.sites[s].bary);  // bit-identical
    }
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.dual.F, b.dual.F);
    EXPECT_EQ(a.diagram.cell_area, b.diagram.cell_area);
  }
  CvtResult c = run(sphere, 60, 8, 2, 8);
  EXPECT_NE(a.positions, c.positions);  // the seed matters
}

TEST(Cvt, DualsOfRealMeshesAreClosedManifoldsOfTheInputGenus) {
  // Site counts: the cells must be smaller than the thinnest parts of the shape (otherwise two
  // cells meet on both sides of a thin wall and the dual has an edge with four triangles, which
  // the validation reports), and cover enough mesh vertices to be resolved by the heat.
  // Fertility (4.5k vertices) and casting (5k, thin walls) are Loop-subdivided once (18k, 20k).
  struct Case {
    const char* file;
    int genus;
    int sites;
    int subdivisions;
  };
  for (const Case& k : {Case{"meshes/sphere_ico642.obj", 0, 100, 0}, Case{"meshes/torus.obj", 1, 200, 0},
                        Case{"meshes/fertility.off", 4, 1000, 1}, Case{"meshes/casting.obj", 9, 2000, 1}}) {
    SCOPED_TRACE(k.file);
    TriangleMesh m = read_mesh(test::data_path(k.file));
    for (int i = 0; i < k.subdivisions; ++i) m = loop_subdivide(m);
    ASSERT_EQ(mesh_genus(m.F, static_cast<int>(m.V.rows())), k.genus);
    CvtOptions o;
    o.sites = k.sites;
    o.iterations = 30;
    CvtResult r = centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
    ValidationOptions vo;
    vo.expected_genus = k.genus;
    vo.expected_components = 1;
    ValidationReport rep = validate_triangle_mesh(r.dual.V, r.dual.F, vo);
    EXPECT_TRUE(rep.ok()) << rep.summary();
    EXPECT_TRUE(r.dual.unused_sites.empty());
    EXPECT_EQ(r.dual.flipped_against_input, 0);
    // Euler: F = 2V − 2χ for a closed triangulation
    EXPECT_EQ(r.dual.F.rows(), 2 * r.dual.V.rows() - 2 * (2 - 2 * k.genus));
    TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
    std::printf("[ info ] %s: %d sites, 30 iterations: phi_min %.1f, phi_m %.2f, %.3f s/iteration\n", k.file, k.sites,
                q.min_angle_deg, q.mean_min_angle_deg, (r.total_seconds - r.setup_seconds) / 30);
    EXPECT_GT(q.mean_min_angle_deg, 45.0);
  }
}

// CvtOptions::spatial_site_order only renumbers the sites: with the farthest-point start, the
// surface Lloyd and heat iterations, every site of the ordered run is within 1e-6 of the
// spacing of a site of the plain run and the cell areas agree as multisets; consecutive sites of
// the ordered run are closer than in the plain run (whose farthest-point numbering jumps across
// the sphere; asserted as the precondition).
TEST(Cvt, SpatialSiteOrderOnlyRenumbersTheSites) {
  auto sphere = test::icosphere(4);
  CvtOptions o;
  o.sites = 200;
  o.iterations = 4;
  o.initialization = CvtInitialization::farthest_point;
  o.surface_lloyd_iterations = 20;
  const Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  const CvtResult plain = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.spatial_site_order = true;
  const CvtResult ordered = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  ASSERT_EQ(plain.positions.rows(), ordered.positions.rows());
  const double spacing = std::sqrt(4 * M_PI / o.sites);
  for (Eigen::Index s = 0; s < ordered.positions.rows(); ++s) {
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index t = 0; t < plain.positions.rows(); ++t)
      nearest = std::min(nearest, (ordered.positions.row(s) - plain.positions.row(t)).norm());
    EXPECT_LT(nearest, 1e-6 * spacing) << s;
  }
  std::vector<double> a(plain.diagram.cell_area.begin(), plain.diagram.cell_area.end());
  std::vector<double> b(ordered.diagram.cell_area.begin(), ordered.diagram.cell_area.end());
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-9) << i;
  auto step = [](const Eigen::MatrixX3d& P) {
    double sum = 0;
    for (Eigen::Index s = 1; s < P.rows(); ++s) sum += (P.row(s) - P.row(s - 1)).norm();
    return sum / static_cast<double>(P.rows() - 1);
  };
  ASSERT_GT(step(plain.positions), 2 * spacing);
  EXPECT_LT(step(ordered.positions), 2 * spacing);
}

TEST(Cvt, AnisotropicCellsFollowCurvature) {
  // An elongated ellipsoid: with the R⁶ lift (paper λ = 0.05... here larger for a coarse mesh),
  // cells crowd where the normal turns fast (the tips), compared to the isotropic CVT.
  auto m = test::icosphere(5);
  m.V.col(0) *= 3.0;
  CvtOptions o;
  o.sites = 150;
  o.iterations = 30;
  CvtResult iso = centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
  Eigen::VectorXd metric;
  Laplacian lap = anisotropic_laplacian(m.V, m.F, 0.3, &metric);
  ASSERT_EQ(metric.size(), m.F.rows());
  CvtResult ani = centroidal_voronoi(m.V, m.F, lap, o, {}, {}, metric);
  auto tip_sites = [](const CvtResult& r) {
    int count = 0;
    for (int s = 0; s < r.positions.rows(); ++s) count += std::abs(r.positions(s, 0)) > 2.4;
    return count;
  };
  std::printf("[ info ] sites near the tips: isotropic %d, anisotropic %d\n", tip_sites(iso), tip_sites(ani));
  EXPECT_GT(tip_sites(ani), tip_sites(iso) + 5);
  ValidationOptions vo;
  vo.expected_genus = 0;
  EXPECT_TRUE(validate_triangle_mesh(ani.dual.V, ani.dual.F, vo).ok());
}

TEST(Cvt, ConvergenceToleranceStopsEarlyAndCallbackCanStop) {
  auto sphere = test::icosphere(4);
  CvtOptions o;
  o.sites = 40;
  o.iterations = 200;
  o.tolerance = 0.02;
  CvtResult r = centroidal_voronoi(sphere.V, sphere.F, cotan_laplacian(sphere.V, sphere.F), o);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.iterations.size(), 200u);
  EXPECT_LT(r.iterations.back().max_move, 0.02 * std::sqrt(surface_area(sphere.V, sphere.F) / 40));
  int calls = 0;
  o.tolerance = 0;
  r = centroidal_voronoi(sphere.V, sphere.F, cotan_laplacian(sphere.V, sphere.F), o, {},
                         [&](const CvtIterationStats& s) {
                           ++calls;
                           EXPECT_EQ(s.iteration, calls);
                           return calls < 5;
                         });
  EXPECT_EQ(calls, 5);
  EXPECT_EQ(r.iterations.size(), 5u);
  EXPECT_FALSE(r.converged);
}

TEST(Cvt, GivenInitialSitesAreUsedAndBadInputThrows) {
  auto sphere = test::icosphere(3);
  Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  CvtOptions o;
  o.iterations = 0;
  std::vector<SurfacePoint> start = initial_sites(sphere.V, sphere.F, 30, CvtInitialization::farthest_point, 3);
  CvtResult r = centroidal_voronoi(sphere.V, sphere.F, lap, o, start);
  ASSERT_EQ(r.sites.size(), 30u);
  for (size_t s = 0; s < 30; ++s) EXPECT_EQ(r.sites[s].face, start[s].face);
  EXPECT_NEAR(r.diagram.cell_area.sum(), surface_area(sphere.V, sphere.F), 1e-9);
  o.sites = 0;
  EXPECT_THROW(centroidal_voronoi(sphere.V, sphere.F, lap, o), InvalidInputError);
  o.sites = static_cast<int>(sphere.V.rows()) + 1;
  EXPECT_THROW(centroidal_voronoi(sphere.V, sphere.F, lap, o), InvalidInputError);
  o.sites = 10;
  o.iterations = -1;
  EXPECT_THROW(centroidal_voronoi(sphere.V, sphere.F, lap, o), InvalidInputError);
  o.iterations = 1;
  auto small = test::icosphere(2);
  EXPECT_THROW(centroidal_voronoi(small.V, small.F, lap, o), InvalidInputError);  // Laplacian size mismatch
  std::vector<SurfacePoint> bad = {SurfacePoint{static_cast<int>(sphere.F.rows()), Eigen::Vector3d(1, 0, 0)}};
  EXPECT_THROW(centroidal_voronoi(sphere.V, sphere.F, lap, o, bad), InvalidInputError);
  EXPECT_THROW(anisotropic_laplacian(sphere.V, sphere.F, -1.0), InvalidInputError);
}

// ---- accelerations (fast_cvt_options) ----

TEST(CvtAcceleration, OverRelaxedLloydEqualisesAtLeastAsFastAsPlainLloyd) {
  // Same random start on the unit-area sphere; after the same number of iterations the
  // over-relaxed (safeguarded) Lloyd step has a cell-area variance no larger than plain Lloyd's.
  const test::UnitSphere unit = test::unit_area_sphere(5);
  const TriangleMesh& sphere = unit.mesh;
  const Laplacian& lap = unit.laplacian;
  CvtOptions o;
  o.sites = 300;
  o.iterations = 12;
  o.seed = 4;
  CvtResult plain = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.relaxation = 1.5;
  CvtResult fast = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  std::printf("[ info ] sphere, 300 sites, 12 iterations: variance plain %.3g, over-relaxed %.3g (start %.3g)\n",
              plain.final_area_variance, fast.final_area_variance, plain.iterations.front().area_variance);
  EXPECT_EQ(plain.iterations.front().area_variance, fast.iterations.front().area_variance);  // same start
  EXPECT_LE(fast.final_area_variance, plain.final_area_variance);
  for (const auto& s : fast.iterations) EXPECT_GE(s.relaxation, 1.0);
  o.relaxation = 1.0;
  o.anderson_depth = 5;
  CvtResult anderson = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  int mixed = 0;
  for (const auto& s : anderson.iterations) mixed += s.anderson_columns > 0;
  std::printf("[ info ] Anderson(5): variance %.3g, %d of 12 steps mixed\n", anderson.final_area_variance, mixed);
  EXPECT_GT(mixed, 0);
  EXPECT_LE(anderson.final_area_variance, plain.final_area_variance);
  // the relaxed sites are on the surface (unit-area sphere: radius 1/sqrt(4 pi), up to the chord error)
  const double radius = std::sqrt(1.0 / (4 * M_PI));
  for (int s = 0; s < fast.positions.rows(); ++s) EXPECT_NEAR(fast.positions.row(s).norm(), radius, 2e-3 * radius);
}

TEST(CvtAcceleration, GraphLloydStartIsCloserToCentroidalThanRandomStart) {
  const test::UnitSphere unit = test::unit_area_sphere(5);
  const TriangleMesh& sphere = unit.mesh;
  const Laplacian& lap = unit.laplacian;
  CvtOptions o;
  o.sites = 300;
  o.iterations = 1;
  CvtResult random_start = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.initialization = CvtInitialization::farthest_point;
  CvtResult fps = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.graph_lloyd_iterations = 20;
  CvtResult graph = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  const double v_random = random_start.iterations.front().area_variance;
  const double v_fps = fps.iterations.front().area_variance;
  const double v_graph = graph.iterations.front().area_variance;
  std::printf("[ info ] initial cell-area variance, 300 sites: random %.3g, farthest point %.3g, + graph Lloyd %.3g (%d it)\n",
              v_random, v_fps, v_graph, graph.graph_lloyd_iterations);
  EXPECT_GT(graph.graph_lloyd_iterations, 0);
  EXPECT_LT(v_fps, 0.5 * v_random);
  EXPECT_LT(v_graph, v_fps);
}

TEST(CvtAcceleration, FastOptionsAreDeterministicAcrossThreadCounts) {
  // the graph Lloyd runs beside the factorisation with 2 threads, inline with 1
  TriangleMesh m = read_mesh(test::data_path("meshes/torus.obj"));
  CvtOptions o = fast_cvt_options(150);
  o.iterations = 6;
  o.target_phi_mean_deg = 60;  // unreachable: run all iterations, evaluating every one
  const Laplacian lap = cotan_laplacian(m.V, m.F);
  o.threads = 1;
  CvtResult a = centroidal_voronoi(m.V, m.F, lap, o);
  for (int threads : {2, 4}) {
    SCOPED_TRACE(threads);
    o.threads = threads;
    CvtResult b = centroidal_voronoi(m.V, m.F, lap, o);
    ASSERT_EQ(a.sites.size(), b.sites.size());
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.dual.F, b.dual.F);
    EXPECT_EQ(a.inserted_sites, b.inserted_sites);
  }
  for (const auto& s : a.iterations) EXPECT_EQ(s.phi_mean_deg >= 0.0, s.iteration % o.quality_every == 0);
}

TEST(CvtAcceleration, ParallelSurfaceLloydMatchesOneThreadOnALargeMesh) {
  // 40,962 vertices: the surface Lloyd's label sweeps, face moments and projections run in
  // parallel (sweeps only above 4,096 active vertices); results are combined in index order.
  auto sphere = test::icosphere(6);
  CvtOptions o = fast_cvt_options(500);
  o.iterations = 2;
  o.target_phi_mean_deg = 60;  // unreachable: the start is evaluated, then 2 heat iterations
  const Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  o.threads = 1;
  CvtResult a = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  EXPECT_GT(a.surface_lloyd_iterations, 10);
  for (int threads : {2, 4}) {
    SCOPED_TRACE(threads);
    o.threads = threads;
    CvtResult b = centroidal_voronoi(sphere.V, sphere.F, lap, o);
    EXPECT_EQ(a.surface_lloyd_iterations, b.surface_lloyd_iterations);
    ASSERT_EQ(a.sites.size(), b.sites.size());
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.dual.F, b.dual.F);
  }
}

TEST(CvtAcceleration, FastOptionsReachTheQualityTargetOnTheSphere) {
  auto sphere = test::icosphere(5);
  CvtOptions o = fast_cvt_options(400);
  CvtResult r = centroidal_voronoi(sphere.V, sphere.F, cotan_laplacian(sphere.V, sphere.F), o);
  ASSERT_TRUE(r.reached_quality);
  const TriangleQuality q = triangle_quality(r.dual.V, r.dual.F);
  std::printf("[ info ] sphere, 400 sites, fast options: quality after %zu iterations: phi_min %.1f, phi_m %.2f\n",
              r.iterations.size(), q.min_angle_deg, q.mean_min_angle_deg);
  EXPECT_GE(q.mean_min_angle_deg, 51.0);
  EXPECT_GE(q.min_angle_deg, 25.0);
  EXPECT_LT(r.iterations.size(), 30u);
  // the returned dual is the dual of the returned diagram of the returned sites
  const DualMesh again = dual_mesh(r.diagram, r.positions);
  EXPECT_EQ(again.F, r.dual.F);
  EXPECT_EQ(r.diagram.num_cells(), static_cast<int>(r.sites.size()));
  ValidationOptions vo;
  vo.expected_genus = 0;
  EXPECT_TRUE(validate_triangle_mesh(r.dual.V, r.dual.F, vo).ok());
}

TEST(CvtAcceleration, SplittingCellsTooBigForThinPartsGivesAValidDualOfTheInputGenus) {
  // Casting (genus 9, thin walls) with too few sites for its thin parts: the plain run's dual is
  // not a manifold of genus 9; with split_nonmanifold_cells the added sites make it one (the dual
  // of the heat Voronoi diagram of all final sites, checked by CGAL).
  TriangleMesh m = read_mesh(test::data_path("meshes/casting.obj"));
  m = loop_subdivide(m);
  const Laplacian lap = cotan_laplacian(m.V, m.F);
  ValidationOptions vo;
  vo.expected_genus = 9;
  vo.expected_components = 1;
  CvtOptions o;
  o.sites = 700;
  o.iterations = 20;
  o.initialization = CvtInitialization::farthest_point;
  CvtResult plain = centroidal_voronoi(m.V, m.F, lap, o);
  const ValidationReport plain_rep = validate_triangle_mesh(plain.dual.V, plain.dual.F, vo);
  o.split_nonmanifold_cells = true;
  o.quality_every = 1;
  std::string trace;
  CvtResult split = centroidal_voronoi(m.V, m.F, lap, o, {}, [&](const CvtIterationStats& s) {
    trace += " " + std::to_string(s.nonmanifold_spots) + "/+" + std::to_string(s.inserted_sites);
    return true;
  });
  std::printf("[ info ] non-manifold spots / inserted sites per iteration:%s\n", trace.c_str());
  const ValidationReport rep = validate_triangle_mesh(split.dual.V, split.dual.F, vo);
  std::printf("[ info ] casting-L1, 700 sites: plain dual valid %d; split: +%d sites, valid %d\n", plain_rep.ok(),
              split.inserted_sites, rep.ok());
  EXPECT_FALSE(plain_rep.ok());
  EXPECT_GT(split.inserted_sites, 0);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(split.sites.size(), 700u + split.inserted_sites);
  EXPECT_EQ(split.diagram.num_cells(), static_cast<int>(split.sites.size()));
  const DualMesh again = dual_mesh(split.diagram, split.positions);
  EXPECT_EQ(again.F, split.dual.F);
}

TEST(CvtAcceleration, QualityPatienceStopsWhenTheMeanAngleStalls) {
  // 300 sites on a 2.9k-vertex cow with an unreachable φm target: the run stops
  // once φm has not improved for `quality_patience` evaluations, well before the iteration cap.
  TriangleMesh m = read_mesh(std::string(HEATCVT_SOURCE_DIR) + "/examples/data/spot.obj");
  CvtOptions o = fast_cvt_options(300);
  o.iterations = 100;
  o.target_phi_mean_deg = 59.0;  // out of reach (the surface-Lloyd start already meets 51°): φm must stall
  CvtResult r = centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
  std::printf("[ info ] spot, 300 sites: stopped after %zu iterations (stalled %d, reached %d)\n", r.iterations.size(),
              r.stalled, r.reached_quality);
  ASSERT_TRUE(r.stalled);
  EXPECT_FALSE(r.reached_quality);
  EXPECT_LT(r.iterations.size(), 100u);
  // The stall rule (cvt.h): over the last quality_patience evaluations, φm never rose more than
  // 0.02° above the best φm evaluated before them (the start's evaluation included).
  std::vector<double> evaluated;
  for (const auto& s : r.iterations)
    if (s.phi_mean_deg >= 0) evaluated.push_back(s.phi_mean_deg);
  ASSERT_GE(static_cast<int>(evaluated.size()), o.quality_patience);
  const size_t window = evaluated.size() - static_cast<size_t>(o.quality_patience);
  double best_before = r.start_phi_mean_deg;
  for (size_t i = 0; i < window; ++i) best_before = std::max(best_before, evaluated[i]);
  ASSERT_GE(best_before, 0.0) << "no evaluation before the patience window";
  for (size_t i = window; i < evaluated.size(); ++i)
    EXPECT_LE(evaluated[i], best_before + 0.02) << "evaluation " << i << " improved: the run was not stalled";
}

TEST(CvtAcceleration, QualityPatienceAlsoEndsSplitsAtSpotsTheCvtCannotResolve) {
  // A range-scan fragment (Redwood, Open3D) with holes and pieces smaller than a cell at 3,000
  // sites, with meshcvt's CVT options: every evaluation finds non-manifold spots around them and
  // splits cells there, while φm falls. The splits stop once φm has not improved for
  // quality_patience evaluations, and the next evaluation ends the run (so its dual is an
  // evaluated one): the run does not go on splitting to the iteration cap.
  TriangleMesh m = read_mesh(test::data_path("meshes/redwood_frag_115_open3d.ply"));
  CvtOptions o = RemeshOptions().cvt;
  o.sites = 3000;
  ASSERT_GT(o.quality_patience, 0);
  ASSERT_TRUE(o.split_nonmanifold_cells);
  CvtResult r = centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
  // The evaluation at which the patience runs out, by the rule of cvt.h (the start's evaluation
  // is the first best).
  double best = r.start_phi_mean_deg;
  int since_best = 0;
  std::size_t exhausted = r.iterations.size();
  for (std::size_t i = 0; i < r.iterations.size() && exhausted == r.iterations.size(); ++i) {
    const CvtIterationStats& s = r.iterations[i];
    if (s.phi_mean_deg < 0) continue;
    if (s.phi_mean_deg > best + o.tuning.patience_gain_deg) best = s.phi_mean_deg, since_best = 0;
    else if (++since_best >= o.quality_patience) exhausted = i;
  }
  std::printf("[ info ] redwood fragment, 3000 sites: %zu iterations, patience out at iteration %d, %d sites inserted\n",
              r.iterations.size(), exhausted < r.iterations.size() ? r.iterations[exhausted].iteration : -1,
              r.inserted_sites);
  ASSERT_LT(exhausted, r.iterations.size()) << "φm kept improving: the patience never ran out";
  ASSERT_GT(r.iterations[exhausted].inserted_sites, 0) << "precondition: cells were still split when it ran out";
  EXPECT_TRUE(r.stalled);
  EXPECT_EQ(r.iterations.back().inserted_sites, 0);
  EXPECT_LE(r.iterations.back().iteration, r.iterations[exhausted].iteration + o.quality_every);
  EXPECT_LT(static_cast<int>(r.iterations.size()), o.iterations);
}

TEST(CvtAcceleration, SurfaceLloydStartIsCloserToCentroidalThanGraphLloyd) {
  // The cheap surface Lloyd (restricted Euclidean cells, projected mass-lumped centroids) brings the
  // farthest-point start closer to a CVT than the vertex-snapped graph Lloyd: smaller cell-area
  // variance of the first heat diagram; its sites lie on the surface; deterministic.
  const test::UnitSphere unit = test::unit_area_sphere(5);
  const TriangleMesh& sphere = unit.mesh;
  const Laplacian& lap = unit.laplacian;
  CvtOptions o;
  o.sites = 300;
  o.iterations = 1;
  o.initialization = CvtInitialization::farthest_point;
  o.graph_lloyd_iterations = 20;
  CvtResult graph = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.graph_lloyd_iterations = 0;
  o.surface_lloyd_iterations = 60;
  o.surface_lloyd_relaxation = 1.5;
  CvtResult surface = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  std::vector<CvtResult> per_thread_count;
  for (int threads : test::kThreadCounts) {
    o.threads = threads;
    per_thread_count.push_back(centroidal_voronoi(sphere.V, sphere.F, lap, o));
  }
  const double v_graph = graph.iterations.front().area_variance;
  const double v_surface = surface.iterations.front().area_variance;
  std::printf("[ info ] initial cell-area variance, 300 sites: graph Lloyd %.3g, surface Lloyd %.3g (%d it, %.3f s)\n",
              v_graph, v_surface, surface.surface_lloyd_iterations, surface.surface_lloyd_seconds);
  EXPECT_GT(surface.surface_lloyd_iterations, 0);
  EXPECT_LE(surface.surface_lloyd_iterations, 60);
  EXPECT_LT(v_surface, 0.5 * v_graph);
  for (const CvtResult& t : per_thread_count) EXPECT_EQ(surface.positions, t.positions);
  // the paper's defaults (the graph run changes only the graph Lloyd): no surface Lloyd and no
  // evaluation of the start
  EXPECT_EQ(graph.surface_lloyd_iterations, 0);
  EXPECT_LT(graph.start_phi_mean_deg, 0.0);
  // bad options throw
  o.surface_lloyd_relaxation = 2.0;
  EXPECT_THROW(centroidal_voronoi(sphere.V, sphere.F, lap, o), InvalidInputError);
}

TEST(CvtAcceleration, QualityAtStartReturnsTheHeatVoronoiDualOfTheStartSites) {
  // A start good enough for the targets costs no Lloyd iteration; the returned diagram is the heat
  // Voronoi diagram of the returned sites (same cells as full diffusions, §4) and the dual its dual.
  auto sphere = test::icosphere(5);
  const Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  CvtOptions o = fast_cvt_options(400);
  CvtResult r = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  std::printf("[ info ] sphere, 400 sites: start phi_min %.1f phi_m %.2f, reached after %zu iterations\n",
              r.start_phi_min_deg, r.start_phi_mean_deg, r.iterations.size());
  ASSERT_TRUE(r.reached_quality);
  ASSERT_TRUE(r.iterations.empty()) << "the start does not meet the targets: the test needs a start that does";
  EXPECT_GE(r.start_phi_mean_deg, o.target_phi_mean_deg);
  EXPECT_GE(r.start_phi_min_deg, o.target_phi_min_deg);
  const DualMesh again = dual_mesh(r.diagram, r.positions);
  EXPECT_EQ(again.F, r.dual.F);
  HeatSolverOptions so;
  const HeatSolver solver(lap, so);
  const VoronoiDiagram full = heat_voronoi(sphere.V, sphere.F, solver, r.sites);
  ASSERT_EQ(full.num_cells(), r.diagram.num_cells());
  double worst = 0;
  for (int c = 0; c < full.num_cells(); ++c)
    worst = std::max(worst, std::abs(full.cell_area[c] - r.diagram.cell_area[c]) / full.cell_area[c]);
  const DualMesh full_dual = dual_mesh(full, r.positions);
  std::printf("[ info ] largest relative cell-area difference to full diffusions: %.3g; dual triangles %ld vs %ld\n",
              worst, static_cast<long>(r.dual.F.rows()), static_cast<long>(full_dual.F.rows()));
  // With the default voronoi_rings_settled (1 ring) the final diagram's cells agree with full
  // diffusions to a few 1e-3 of their area and give the same dual triangles.
  EXPECT_EQ(triangle_set(full_dual.F), triangle_set(r.dual.F));
  // With the paper's index sets (cell + 2 rings, §6; the target: localized heat within
  // 1e-3 of full diffusions), the cell areas agree to 1e-3.
  CvtOptions two_rings = o;
  two_rings.voronoi_rings_settled = two_rings.voronoi_rings;
  ASSERT_EQ(two_rings.voronoi_rings, 2);
  const CvtResult r2 = centroidal_voronoi(sphere.V, sphere.F, lap, two_rings);
  const VoronoiDiagram full2 = heat_voronoi(sphere.V, sphere.F, solver, r2.sites);
  ASSERT_EQ(full2.num_cells(), r2.diagram.num_cells());
  double worst2 = 0;
  for (int c = 0; c < full2.num_cells(); ++c)
    worst2 = std::max(worst2, std::abs(full2.cell_area[c] - r2.diagram.cell_area[c]) / full2.cell_area[c]);
  std::printf("[ info ] with 2 rings throughout: largest relative cell-area difference %.3g\n", worst2);
  EXPECT_LT(worst2, 1e-3);
  EXPECT_EQ(dual_mesh(full2, r2.positions).F, r2.dual.F);
  EXPECT_EQ(full_dual.F.rows(), r.dual.F.rows());
}

TEST(CvtAcceleration, SplitRoundsAtTheStartKeepTheDualOfTheFinalSites) {
  // Casting (genus 9, thin walls), fast options with the split rounds at the start: sites added
  // where cells are too big for thin parts are relaxed by the surface Lloyd and evaluated again;
  // the result is the dual of the heat Voronoi diagram of all final sites, a valid genus-9 surface.
  // 1,000 sites: enough for the insertions to stay within max_inserted_fraction (with 500 the 25 %
  // budget runs out and the dual keeps non-manifold edges).
  TriangleMesh m = read_mesh(test::data_path("meshes/casting.obj"));
  m = loop_subdivide(m);
  CvtOptions o = fast_cvt_options(1000);
  o.iterations = 10;
  CvtResult r = centroidal_voronoi(m.V, m.F, cotan_laplacian(m.V, m.F), o);
  std::printf("[ info ] casting-L1, 1000 sites: start rounds %d, +%d sites, start spots %d, phi_min %.1f phi_m %.2f, "
              "reached %d after %zu iterations\n",
              r.start_rounds, r.inserted_sites, r.start_spots, r.start_phi_min_deg, r.start_phi_mean_deg,
              r.reached_quality, r.iterations.size());
  EXPECT_LE(r.start_rounds, o.surface_lloyd_split_rounds);
  EXPECT_EQ(r.sites.size(), 1000u + r.inserted_sites);
  EXPECT_EQ(r.diagram.num_cells(), static_cast<int>(r.sites.size()));
  EXPECT_EQ(dual_mesh(r.diagram, r.positions).F, r.dual.F);
  ValidationOptions vo;
  vo.expected_genus = 9;
  vo.expected_components = 1;
  const ValidationReport rep = validate_triangle_mesh(r.dual.V, r.dual.F, vo);
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

TEST(CvtAcceleration, SmallAngleRefinementRaisesPhiMinOnArmadillo) {
  // Armadillo (43k vertices), 1,000 sites, fast options: the start misses the 25° φmin target by
  // a few small-angle triangles; the refinement inserts sites at their Voronoi vertices and the
  // start's φmin rises above the plain start's. The result is the dual of the heat Voronoi diagram
  // of all final sites, a valid genus-0 surface.
  TriangleMesh m = read_mesh(test::data_path("meshes/armadillo.obj"));
  const Laplacian lap = cotan_laplacian(m.V, m.F);
  CvtOptions o = fast_cvt_options(1000);
  o.iterations = 2;  // the refinement runs in the start rounds (only when heat iterations follow)
  ASSERT_TRUE(o.refine_small_angles);
  CvtResult r = centroidal_voronoi(m.V, m.F, lap, o);
  CvtOptions plain = o;
  plain.refine_small_angles = false;
  CvtResult p = centroidal_voronoi(m.V, m.F, lap, plain);
  std::printf("[ info ] armadillo, 1000 sites: start phi_min %.1f phi_m %.2f with refinement (+%d sites in %d rounds, "
              "%d inserted), %.1f / %.2f without\n",
              r.start_phi_min_deg, r.start_phi_mean_deg, r.refined_sites, r.start_rounds, r.inserted_sites,
              p.start_phi_min_deg, p.start_phi_mean_deg);
  ASSERT_GE(p.start_phi_min_deg, 0.0);
  ASSERT_LT(p.start_phi_min_deg, o.target_phi_min_deg) << "the plain start must miss the target for the test";
  EXPECT_GT(r.refined_sites, 0);
  EXPECT_EQ(p.refined_sites, 0);
  EXPECT_GT(r.start_phi_min_deg, p.start_phi_min_deg);
  EXPECT_EQ(r.sites.size(), 1000u + r.inserted_sites);
  EXPECT_EQ(dual_mesh(r.diagram, r.positions).F, r.dual.F);
  ValidationOptions vo;
  vo.expected_genus = 0;
  EXPECT_TRUE(validate_triangle_mesh(r.dual.V, r.dual.F, vo).ok());
}

TEST(CvtAcceleration, SmallAngleRefinementTowardAFarTargetKeepsTheDualOfTheFinalSites) {
  // A φmin target far above what a sphere's start gives (many bad triangles): the start rounds
  // insert sites where the cells of the small-angle triangles meet, relax and evaluate again. This
  // does not raise φmin here (measured 44.8° without, 37.8° with: the inserted sites do not settle
  // in a few surface-Lloyd iterations; cvt.h documents it); what the refinement guarantees is
  // that sites are inserted and the result is still the dual of the heat Voronoi diagram of all
  // final sites, a valid sphere.
  auto sphere = test::icosphere(5);
  const Laplacian lap = cotan_laplacian(sphere.V, sphere.F);
  CvtOptions o = fast_cvt_options(200);
  o.iterations = 2;
  o.target_phi_mean_deg = 40.0;
  o.target_phi_min_deg = 50.0;  // out of reach: refinement runs through its rounds
  o.refine_small_angles = true;
  CvtResult r = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  CvtOptions plain = o;
  plain.refine_small_angles = false;
  CvtResult p = centroidal_voronoi(sphere.V, sphere.F, lap, plain);
  std::printf("[ info ] sphere, 200 sites, phi_min target 50: refined +%d sites in %d rounds; start phi_min %.1f "
              "(without refinement %.1f)\n",
              r.refined_sites, r.start_rounds, r.start_phi_min_deg, p.start_phi_min_deg);
  EXPECT_GT(r.refined_sites, 0);
  EXPECT_EQ(p.refined_sites, 0);
  EXPECT_EQ(r.sites.size(), 200u + r.inserted_sites);
  EXPECT_EQ(r.diagram.num_cells(), static_cast<int>(r.sites.size()));
  EXPECT_EQ(dual_mesh(r.diagram, r.positions).F, r.dual.F);
  ValidationOptions vo;
  vo.expected_genus = 0;
  EXPECT_TRUE(validate_triangle_mesh(r.dual.V, r.dual.F, vo).ok());
}
