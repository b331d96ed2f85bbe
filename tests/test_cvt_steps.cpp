// The CVT steps on their own, on shapes built in code: the start (cvt/start.h), the Lloyd state
// (cvt/lloyd.h), quality control (cvt/quality.h) and the anisotropic lift (cvt/anisotropic_lift.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "heatcvt/cvt.h"
#include "heatcvt/cvt/anisotropic_lift.h"
#include "heatcvt/cvt/lloyd.h"
#include "heatcvt/cvt/quality.h"
#include "heatcvt/cvt/start.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Lumped CVT energy Σ a_v |x_v − p_label(v)|² of the restricted cells of the sites.
double restricted_energy(const CvtSurface& s, const std::vector<SurfacePoint>& sites) {
  std::vector<Eigen::Vector3d> X(s.num_vertices()), P(sites.size());
  for (int v = 0; v < s.num_vertices(); ++v) X[v] = s.V.row(v).transpose();
  for (size_t i = 0; i < sites.size(); ++i) P[i] = position(s.V, s.F, sites[i]);
  std::vector<int> label;
  std::vector<double> key;
  restricted_labels(s.graph, X, s.F, sites, P, label, key);
  double e = 0;
  for (int v = 0; v < s.num_vertices(); ++v) e += s.vertex_area[v] * key[v];
  return e;
}

// Labels must be edge-connected per cell (restricted cells grow over the edge graph).
bool cells_connected(const EdgeGraph& g, const std::vector<int>& label, int ns) {
  std::vector<int> seen(label.size(), 0);
  std::vector<int> components(ns, 0);
  for (size_t v0 = 0; v0 < label.size(); ++v0) {
    if (seen[v0] || label[v0] < 0) continue;
    ++components[label[v0]];
    std::vector<int> stack = {static_cast<int>(v0)};
    seen[v0] = 1;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (int k = g.off[v]; k < g.off[v + 1]; ++k) {
        const int w = g.nbr[k];
        if (!seen[w] && label[w] == label[v0]) seen[w] = 1, stack.push_back(w);
      }
    }
  }
  return std::all_of(components.begin(), components.end(), [](int c) { return c <= 1; });
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Start
// ---------------------------------------------------------------------------------------------

TEST(CvtStart, FarthestPointSitesAreDistinctVertices) {
  const TriangleMesh m = test::icosphere(3);
  const std::vector<SurfacePoint> sites = initial_sites(m.V, m.F, 40, CvtInitialization::farthest_point, 1);
  ASSERT_EQ(sites.size(), 40u);
  std::set<int> vertices;
  for (const SurfacePoint& p : sites) {
    EXPECT_DOUBLE_EQ(p.bary.maxCoeff(), 1.0);  // at a vertex
    vertices.insert(nearest_corner(m.F, p));
  }
  EXPECT_EQ(vertices.size(), 40u);
  EXPECT_THROW(initial_sites(m.V, m.F, 0, CvtInitialization::random, 1), InvalidInputError);
}

TEST(CvtStart, GraphLloydReachesAFixedPoint) {
  const TriangleMesh m = test::icosphere(3);
  const CvtSurface s(m.V, m.F);
  std::vector<int> sources = {0, 1, 2, 3, 4, 5};  // clustered start
  int done = 0;
  const std::vector<int> out = graph_lloyd(s.graph, m.V, s.vertex_area, sources, 200, &done);
  ASSERT_EQ(out.size(), sources.size());
  EXPECT_GT(done, 1);
  EXPECT_LT(done, 200);  // stopped because no source changed
  // a fixed point: one more iteration changes nothing
  int again = 0;
  EXPECT_EQ(graph_lloyd(s.graph, m.V, s.vertex_area, out, 5, &again), out);
  EXPECT_EQ(again, 1);
  // the sources spread out: every cell of the final graph Voronoi diagram is non-empty
  const std::vector<int> label = graph_voronoi(s.graph, out);
  std::vector<int> count(out.size(), 0);
  for (int l : label) ++count[l];
  for (int c : count) EXPECT_GT(c, 0);
}

TEST(CvtStart, SurfaceLloydLowersTheEnergyAndKeepsCellsConnected) {
  const TriangleMesh m = test::icosphere(4);
  const CvtSurface s(m.V, m.F);
  const std::vector<SurfacePoint> start = initial_sites(m.V, m.F, 60, CvtInitialization::random, 3);
  SurfaceLloydOptions o;
  o.iterations = 15;
  o.tolerance = 0;
  o.relaxation = 1.5;
  o.spacing = std::sqrt(s.face_area.sum() / 60);
  int done = 0;
  std::vector<int> labels;
  const std::vector<SurfacePoint> out = surface_lloyd(s, start, o, &done, &labels, []() { return 2; });
  ASSERT_EQ(out.size(), start.size());
  EXPECT_EQ(done, 15);
  EXPECT_LT(restricted_energy(s, out), 0.7 * restricted_energy(s, start));
  ASSERT_EQ(labels.size(), static_cast<size_t>(m.V.rows()));
  EXPECT_TRUE(std::none_of(labels.begin(), labels.end(), [](int l) { return l < 0; }));
  EXPECT_TRUE(cells_connected(s.graph, labels, 60));
  // deterministic for any thread count
  int done1 = 0;
  const std::vector<SurfacePoint> one = surface_lloyd(s, start, o, &done1, nullptr, []() { return 1; });
  ASSERT_EQ(done1, done);
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(one[i].face, out[i].face);
    EXPECT_EQ(one[i].bary, out[i].bary);
  }
}

// Mean |p_after − p_before| over the sites, in units of `spacing`.
double mean_move(const TriangleMesh& m, const std::vector<SurfacePoint>& a, const std::vector<SurfacePoint>& b,
                 double spacing) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) sum += (position(m.V, m.F, a[i]) - position(m.V, m.F, b[i])).norm();
  return sum / static_cast<double>(a.size()) / spacing;
}

TEST(CvtStart, TheMeanMoveRuleStopsTheSurfaceLloydAtTheFirstSmallMeanMove) {
  const TriangleMesh m = test::icosphere(4);
  const CvtSurface s(m.V, m.F);
  const int ns = 200;
  const std::vector<SurfacePoint> start = initial_sites(m.V, m.F, ns, CvtInitialization::random, 3);
  SurfaceLloydOptions o;
  o.iterations = 80;
  o.tolerance = 0;  // the max-move rule off: only the mean rule may stop early
  o.relaxation = 1.5;
  o.spacing = std::sqrt(s.face_area.sum() / ns);
  const auto run = [&](int iterations, double mean_tolerance, int* done) {
    SurfaceLloydOptions r = o;
    r.iterations = iterations;
    r.mean_tolerance = mean_tolerance;
    return surface_lloyd(s, start, r, done, nullptr, []() { return 2; });
  };
  int full_done = 0, done = 0;
  const std::vector<SurfacePoint> full = run(o.iterations, 0, &full_done);
  ASSERT_EQ(full_done, o.iterations);  // precondition: without the rule every iteration runs
  const double tol = 0.005;
  const std::vector<SurfacePoint> stopped = run(o.iterations, tol, &done);
  ASSERT_GT(done, 2);
  EXPECT_LT(done, o.iterations);
  // The rule is the first iteration whose mean move is below tol spacings.
  int d1 = 0, d2 = 0;
  const std::vector<SurfacePoint> before = run(done - 1, 0, &d1), earlier = run(done - 2, 0, &d2);
  EXPECT_LT(mean_move(m, stopped, before, o.spacing), tol);
  EXPECT_GE(mean_move(m, before, earlier, o.spacing), tol);
  // What the remaining iterations would still gain is small.
  EXPECT_LT(restricted_energy(s, stopped), 1.02 * restricted_energy(s, full));
  // A negative tolerance is refused by the CVT.
  CvtOptions bad;
  bad.sites = 10;
  bad.surface_lloyd_iterations = 5;
  bad.surface_lloyd_mean_tolerance = -1;
  const Laplacian lap = cotan_laplacian(m.V, m.F);
  EXPECT_THROW(centroidal_voronoi(m.V, m.F, lap, bad), InvalidInputError);
}

TEST(CvtStart, UpdatedLabelsStayCompleteAndConnected) {
  const TriangleMesh m = test::icosphere(4);
  const CvtSurface s(m.V, m.F);
  std::vector<SurfacePoint> sites = initial_sites(m.V, m.F, 30, CvtInitialization::farthest_point, 1);
  std::vector<Eigen::Vector3d> X(s.num_vertices()), P(sites.size());
  for (int v = 0; v < s.num_vertices(); ++v) X[v] = m.V.row(v).transpose();
  for (size_t i = 0; i < sites.size(); ++i) P[i] = position(m.V, m.F, sites[i]);
  std::vector<int> label;
  std::vector<double> key;
  restricted_labels(s.graph, X, m.F, sites, P, label, key);
  // move every site to the next vertex of its face, then update the labels locally
  for (size_t i = 0; i < sites.size(); ++i) {
    int k = 0;
    sites[i].bary.maxCoeff(&k);
    sites[i].bary = Eigen::Vector3d::Unit((k + 1) % 3);
    P[i] = position(m.V, m.F, sites[i]);
  }
  update_restricted_labels(s.graph, X, m.F, sites, P, label, key, 2);
  for (int v = 0; v < s.num_vertices(); ++v) {
    ASSERT_GE(label[v], 0);
    EXPECT_DOUBLE_EQ(key[v], (X[v] - P[label[v]]).squaredNorm());
  }
  EXPECT_TRUE(cells_connected(s.graph, label, 30));
  // each site's own vertex is in its cell
  for (size_t i = 0; i < sites.size(); ++i) EXPECT_EQ(label[nearest_corner(m.F, sites[i])], static_cast<int>(i));
}

// ---------------------------------------------------------------------------------------------
// Lloyd state
// ---------------------------------------------------------------------------------------------

namespace {

struct LloydFixture {
  explicit LloydFixture(int sites, int subdivisions = 3)
      : sphere(test::unit_area_sphere(subdivisions)), surface(sphere.mesh.V, sphere.mesh.F),
        solver(sphere.laplacian, HeatSolverOptions{}), local(solver) {
    options.sites = sites;
    spacing = std::sqrt(1.0 / sites);
    start = initial_sites(sphere.mesh.V, sphere.mesh.F, sites, CvtInitialization::farthest_point, 1);
  }
  CellNeighbourhoods graph_cells(const std::vector<SurfacePoint>& sites) const {
    std::vector<int> sources;
    for (const SurfacePoint& p : sites) sources.push_back(nearest_corner(sphere.mesh.F, p));
    return cells_from_labels(surface.graph, graph_voronoi(surface.graph, sources), static_cast<int>(sites.size()));
  }
  test::UnitSphere sphere;
  CvtSurface surface;
  HeatSolver solver;
  LocalizedSolver local;
  CvtOptions options;
  double spacing = 0;
  std::vector<SurfacePoint> start;
};

}  // namespace

TEST(CvtLloyd, IterationCellsPartitionTheSurface) {
  LloydFixture fx(40);
  LloydState state(fx.surface, fx.local, fx.options, Eigen::VectorXd(), fx.spacing, 2, fx.start,
                   fx.graph_cells(fx.start), 2);
  const HeatField field = state.heat_field(nullptr);
  ASSERT_EQ(field.num_vertices(), fx.surface.num_vertices());
  const IterationCells ic = iteration_cells(field, fx.sphere.mesh.F, fx.surface.face_area, Eigen::VectorXd(), 40, 2);
  EXPECT_NEAR(ic.area.sum(), 1.0, 1e-12);
  for (int c = 0; c < 40; ++c) {
    EXPECT_GT(ic.area[c], 0.0) << c;
    double load = 0;
    for (const auto& [v, w] : ic.loads[c]) load += w;
    EXPECT_NEAR(load, ic.area[c], 1e-12) << c;  // Σ ∫ φ_v = area of the cell
    for (int a : ic.cells.adjacency[c]) {
      EXPECT_NE(a, c);
      const auto& back = ic.cells.adjacency[a];
      EXPECT_TRUE(std::binary_search(back.begin(), back.end(), c)) << "adjacency not symmetric";
    }
  }
  // the cells are the tessellation's: same areas as the exact diagram of the same field
  const VoronoiDiagram d = tessellate(fx.sphere.mesh.V, fx.sphere.mesh.F, field);
  for (int c = 0; c < 40; ++c) EXPECT_NEAR(ic.area[c], d.cell_area[c], 1e-12) << c;
  // a metric scale multiplies the loads, not the areas
  const Eigen::VectorXd twice = Eigen::VectorXd::Constant(fx.sphere.mesh.F.rows(), 2.0);
  const IterationCells scaled = iteration_cells(field, fx.sphere.mesh.F, fx.surface.face_area, twice, 40, 1);
  EXPECT_NEAR(scaled.area.sum(), 1.0, 1e-12);
  double total = 0;
  for (const auto& l : scaled.loads)
    for (const auto& [v, w] : l) total += w;
  EXPECT_NEAR(total, 2.0, 1e-12);
}

TEST(CvtLloyd, StepsEqualiseTheCellsAndRevivalFillsEmptyCells) {
  LloydFixture fx(30);
  // two sites on the same point: one of the two cells is empty after the first step
  std::vector<SurfacePoint> sites = fx.start;
  sites[1] = sites[0];
  LloydState state(fx.surface, fx.local, fx.options, Eigen::VectorXd(), fx.spacing, 2, sites, fx.graph_cells(sites), 2);
  CvtIterationStats first;
  state.step(state.heat_field(nullptr), first);
  EXPECT_EQ(first.revived_sites, 1);
  const Eigen::MatrixX3d P = state.positions();
  EXPECT_GT((P.row(0) - P.row(1)).norm(), 0.5 * fx.spacing);  // the revived site moved away
  CvtIterationStats st;
  for (int i = 0; i < 15; ++i) {
    st = CvtIterationStats();
    state.step(state.heat_field(nullptr), st);
  }
  EXPECT_EQ(st.revived_sites, 0);
  EXPECT_LT(st.area_variance, 0.1 * first.area_variance);
  EXPECT_LT(st.max_move, first.max_move);
}

TEST(CvtLloyd, OverRelaxationIsSafeguardedAndAddedSitesJoin) {
  LloydFixture fx(30);
  fx.options.relaxation = 1.9;
  LloydState state(fx.surface, fx.local, fx.options, Eigen::VectorXd(), fx.spacing, 2, fx.start,
                   fx.graph_cells(fx.start), 2);
  double omega_min = 2.0;
  for (int i = 0; i < 12; ++i) {
    CvtIterationStats st;
    state.step(state.heat_field(nullptr), st);
    EXPECT_GE(st.relaxation, 1.0);
    EXPECT_LE(st.relaxation, 1.9);
    omega_min = std::min(omega_min, st.relaxation);
  }
  EXPECT_LT(omega_min, 1.9);  // the variance grew at some point and ω was lowered
  // inserted sites get cells at the next step
  const std::vector<SurfacePoint> added = {vertex_point(fx.sphere.mesh.F, fx.surface.vfaces, 5)};
  state.add_sites(added, true);
  ASSERT_EQ(state.num_sites(), 31);
  EXPECT_EQ(state.rings(), fx.options.voronoi_rings);
  const HeatField field = state.heat_field(nullptr);
  EXPECT_EQ(field.num_sites, 31);
  const IterationCells ic = iteration_cells(field, fx.sphere.mesh.F, fx.surface.face_area, Eigen::VectorXd(), 31, 2);
  EXPECT_GT(ic.area[30], 0.0);
}

// ---------------------------------------------------------------------------------------------
// Quality control
// ---------------------------------------------------------------------------------------------

namespace {

DualMesh dual_of(const Eigen::MatrixX3i& F, int n) {
  DualMesh d;
  d.V = Eigen::MatrixX3d::Zero(n, 3);
  d.F = F;
  return d;
}

Eigen::MatrixX3i tetrahedron() {
  Eigen::MatrixX3i F(4, 3);
  F << 0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3;
  return F;
}

}  // namespace

TEST(CvtQuality, NonmanifoldCellsOfHandMadeDuals) {
  int spots = -1;
  EXPECT_TRUE(nonmanifold_cells(dual_of(tetrahedron(), 4), 4, true, &spots).empty());
  EXPECT_EQ(spots, 0);
  // an open tetrahedron (face 2 0 3 removed): its three boundary edges are spots on a closed
  // input, none on an open one
  const Eigen::MatrixX3i open = tetrahedron().topRows(3);
  EXPECT_EQ(nonmanifold_cells(dual_of(open, 4), 4, true, &spots), (std::vector<int>{0, 2, 3}));
  EXPECT_EQ(spots, 3);
  EXPECT_TRUE(nonmanifold_cells(dual_of(open, 4), 4, false, &spots).empty());
  // a fin: edge (0, 1) with three triangles
  Eigen::MatrixX3i fin(3, 3);
  fin << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  const std::vector<int> fin_cells = nonmanifold_cells(dual_of(fin, 5), 5, false, &spots);
  EXPECT_TRUE(std::find(fin_cells.begin(), fin_cells.end(), 0) != fin_cells.end());
  EXPECT_TRUE(std::find(fin_cells.begin(), fin_cells.end(), 1) != fin_cells.end());
  // a bow tie: two triangles sharing only vertex 0; a site in no triangle
  Eigen::MatrixX3i bow(2, 3);
  bow << 0, 1, 2, 0, 3, 4;
  DualMesh d = dual_of(bow, 6);
  d.unused_sites = {5};
  EXPECT_EQ(nonmanifold_cells(d, 6, false, &spots), (std::vector<int>{0, 5}));
  EXPECT_EQ(spots, 2);
}

TEST(CvtQuality, EdgeTopologyOfShapes) {
  const TriangleMesh sphere = test::icosphere(1);
  const EdgeTopology closed = edge_topology(sphere.F, static_cast<int>(sphere.V.rows()));
  EXPECT_TRUE(closed.closed);
  EXPECT_TRUE(closed.manifold_edges);
  const TriangleMesh plane = test::grid(4);
  const EdgeTopology open = edge_topology(plane.F, static_cast<int>(plane.V.rows()));
  EXPECT_FALSE(open.closed);
  EXPECT_TRUE(open.manifold_edges);
  Eigen::MatrixX3i fin(3, 3);
  fin << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  EXPECT_FALSE(edge_topology(fin, 5).manifold_edges);
}

TEST(CvtQuality, SplitPutsTheNewSiteAtTheFarthestVertexOfTheCell) {
  LloydFixture fx(2);
  // two antipodal sites: each cell is a hemisphere; its farthest vertex lies on the equator
  std::vector<SurfacePoint> sites;
  int top = 0, bottom = 0;
  fx.sphere.mesh.V.col(2).maxCoeff(&top);
  fx.sphere.mesh.V.col(2).minCoeff(&bottom);
  sites.push_back(vertex_point(fx.sphere.mesh.F, fx.surface.vfaces, top));
  sites.push_back(vertex_point(fx.sphere.mesh.F, fx.surface.vfaces, bottom));
  LloydState state(fx.surface, fx.local, fx.options, Eigen::VectorXd(), fx.spacing, 1, sites, fx.graph_cells(sites), 2);
  const HeatField field = state.heat_field(nullptr);
  const Eigen::MatrixX3d P = state.positions();
  const std::vector<SurfacePoint> added = split_cells(fx.surface, field, P, {0}, 1e-9);
  ASSERT_EQ(added.size(), 1u);
  const Eigen::Vector3d x = position(fx.sphere.mesh.V, fx.sphere.mesh.F, added[0]);
  const double radius = fx.sphere.mesh.V.row(top).norm();
  EXPECT_GT((x - P.row(0).transpose()).norm(), 1.2 * radius);  // beyond 90° from the pole (chord √2 r)
  EXPECT_LE(std::abs(x.z()), 0.25 * radius);                     // near the equator
  // nothing to split closer than the minimum distance
  EXPECT_TRUE(split_cells(fx.surface, field, P, {0}, 10.0).empty());
}

TEST(CvtQuality, EvaluationMatchesTheDualAndRefinementAddsAtMostTheBudget) {
  LloydFixture fx(60);
  fx.options.quality_every = 1;
  fx.options.target_phi_mean_deg = 89.0;  // out of reach
  fx.options.target_phi_min_deg = 60.0;
  fx.options.refine_small_angles = true;
  LloydState state(fx.surface, fx.local, fx.options, Eigen::VectorXd(), fx.spacing, 2, fx.start,
                   fx.graph_cells(fx.start), 2);
  CvtQualityControl quality(fx.surface, fx.options, 60, fx.spacing, 2);
  CvtResult result;
  CvtIterationStats st;
  EXPECT_FALSE(quality.evaluate(state, st, 0, result));
  // the evaluated φ are those of the dual of the exact diagram of the same sites
  const VoronoiDiagram d = tessellate(fx.sphere.mesh.V, fx.sphere.mesh.F, state.heat_field(nullptr));
  const DualMesh dual = dual_mesh(d, state.positions());
  const TriangleQuality q = triangle_quality(dual.V, dual.F);
  EXPECT_DOUBLE_EQ(st.phi_min_deg, q.min_angle_deg);
  EXPECT_DOUBLE_EQ(st.phi_mean_deg, q.mean_min_angle_deg);
  EXPECT_TRUE(quality.has_field());
  // small-angle sites: at most `count`, at distinct input vertices
  const std::vector<SurfacePoint> some = small_angle_sites(fx.surface, d, dual, 60.0, 3);
  EXPECT_GE(some.size(), 1u);
  EXPECT_LE(some.size(), 3u);
  std::set<int> at;
  for (const SurfacePoint& p : some) at.insert(nearest_corner(fx.sphere.mesh.F, p));
  EXPECT_EQ(at.size(), some.size());
  // reached targets make the evaluated diagram the result
  CvtOptions easy = fx.options;
  easy.target_phi_mean_deg = 1.0;
  easy.target_phi_min_deg = 0.1;
  CvtQualityControl lenient(fx.surface, easy, 60, fx.spacing, 2);
  CvtResult done;
  CvtIterationStats st2;
  EXPECT_TRUE(lenient.evaluate(state, st2, 0, done));
  EXPECT_TRUE(done.reached_quality);
  EXPECT_EQ(done.dual.F.rows(), dual.F.rows());
}

// ---------------------------------------------------------------------------------------------
// Anisotropic lift
// ---------------------------------------------------------------------------------------------

TEST(CvtLift, ZeroLambdaIsTheCotanLaplacianAndTheMeshPathScalesFirst) {
  const TriangleMesh m = test::torus(24, 12);
  Eigen::VectorXd area;
  const Laplacian flat = lifted_laplacian(m.V, vertex_normals(m.V, m.F), m.F, 0.0, &area);
  const Laplacian cot = cotan_laplacian(m.V, m.F);
  EXPECT_LT((Eigen::MatrixXd(flat.L) - Eigen::MatrixXd(cot.L)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((area - face_areas(m.V, m.F)).cwiseAbs().maxCoeff(), 1e-14);
  // λ > 0 lengthens the edges across curved parts: lifted areas are never smaller
  Eigen::VectorXd lifted;
  lifted_laplacian(m.V, vertex_normals(m.V, m.F), m.F, 0.5, &lifted);
  for (Eigen::Index f = 0; f < area.size(); ++f) EXPECT_GE(lifted[f], area[f] * (1 - 1e-12));
  EXPECT_GT(lifted.sum(), 1.01 * area.sum());
  // anisotropic_laplacian() = the lift of the mesh scaled into the unit bounding box
  const double extent = (m.V.colwise().maxCoeff() - m.V.colwise().minCoeff()).maxCoeff();
  const Eigen::MatrixX3d unit = (m.V.rowwise() - m.V.colwise().minCoeff()) / extent;
  Eigen::VectorXd a1, a2;
  const Laplacian mesh_path = anisotropic_laplacian(m.V, m.F, 0.05, &a1);
  const Laplacian point_path = lifted_laplacian(unit, vertex_normals(m.V, m.F), m.F, 0.05, &a2);
  EXPECT_EQ((Eigen::MatrixXd(mesh_path.L) - Eigen::MatrixXd(point_path.L)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((a1 - a2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_THROW(lifted_laplacian(m.V, vertex_normals(m.V, m.F), m.F, -1.0), InvalidInputError);
  EXPECT_THROW(lifted_laplacian(m.V, Eigen::MatrixX3d::Zero(3, 3), m.F, 0.1), InvalidInputError);
}

TEST(CvtDriver, RejectsBadTuningAndTolerances) {
  const test::UnitSphere sphere = test::unit_area_sphere(2);
  CvtOptions o;
  o.sites = 10;
  o.iterations = 1;
  o.tuning.relaxation_decay = 1.0;
  EXPECT_THROW(centroidal_voronoi(sphere.mesh.V, sphere.mesh.F, sphere.laplacian, o), InvalidInputError);
  o.tuning = CvtTuning();
  o.tuning.empty_cell_radius = std::nan("");
  EXPECT_THROW(centroidal_voronoi(sphere.mesh.V, sphere.mesh.F, sphere.laplacian, o), InvalidInputError);
  o.tuning = CvtTuning();
  o.tuning.face_blocks_per_thread = 0;
  EXPECT_THROW(centroidal_voronoi(sphere.mesh.V, sphere.mesh.F, sphere.laplacian, o), InvalidInputError);
  o.tuning = CvtTuning();
  const CvtResult r = centroidal_voronoi(sphere.mesh.V, sphere.mesh.F, sphere.laplacian, o);
  EXPECT_EQ(r.sites.size(), 10u);
  VoronoiOptions vo;
  vo.weld_tolerance = -1;
  EXPECT_THROW(tessellate(sphere.mesh.V, sphere.mesh.F, heat_field_from_sparse(static_cast<int>(sphere.mesh.V.rows()), {{0}}, {{1.0}}), vo),
               InvalidInputError);
}
