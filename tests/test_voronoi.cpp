// Heat Voronoi diagrams (paper §4): bookkeeping of the exact tessellation, conformity of the
// refined mesh, unreached components, and the bisector convergence of Fig. 3 (plane and sphere).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/shapes.h"
#include "heatcvt/voronoi.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

// Random sites: random faces, random barycentric coordinates (seeded).
std::vector<SurfacePoint> random_sites(const Eigen::MatrixX3i& F, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> face(0, static_cast<int>(F.rows()) - 1);
  std::uniform_real_distribution<double> unit(0.05, 1.0);
  std::vector<SurfacePoint> sites(count);
  for (auto& s : sites) {
    s.face = face(rng);
    s.bary = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    s.bary /= s.bary.sum();
  }
  return sites;
}

// Every invariant of a diagram that must hold for any input.
void check_diagram(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const VoronoiDiagram& d, bool closed,
                   bool all_reached = true) {
  const int nv = static_cast<int>(V.rows());
  const int nrf = static_cast<int>(d.F.rows());
  ASSERT_GE(d.V.rows(), V.rows());
  EXPECT_EQ((d.V.topRows(nv) - V).cwiseAbs().maxCoeff(), 0.0) << "original vertices keep their indices";
  ASSERT_EQ(d.face_cell.size(), nrf);
  ASSERT_EQ(d.face_parent.size(), nrf);
  ASSERT_EQ(d.face_bary.rows(), 3 * nrf);
  ASSERT_EQ(d.face_area.size(), nrf);
  const double area = surface_area(V, F);

  // every refined face has one cell; parent faces valid; bary coords consistent with positions
  double max_pos_err = 0;
  for (int r = 0; r < nrf; ++r) {
    if (all_reached) {
      ASSERT_GE(d.face_cell[r], 0);
    }
    ASSERT_LT(d.face_cell[r], d.num_cells());
    ASSERT_GE(d.face_parent[r], 0);
    ASSERT_LT(d.face_parent[r], F.rows());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d b = d.face_bary.row(3 * r + k).transpose();
      EXPECT_NEAR(b.sum(), 1.0, 1e-12);
      EXPECT_GE(b.minCoeff(), -1e-12);
      SurfacePoint p{d.face_parent[r], b};
      max_pos_err = std::max(max_pos_err, (position(V, F, p) - d.V.row(d.F(r, k)).transpose()).norm());
    }
    EXPECT_GE(d.face_area[r], -1e-14 * area);
  }
  EXPECT_LT(max_pos_err, 1e-12);

  // total refined area equals the original, per parent face too; cell areas sum to the mesh area
  EXPECT_NEAR(d.face_area.sum(), area, 1e-9 * area);
  Eigen::VectorXd per_parent = Eigen::VectorXd::Zero(F.rows());
  for (int r = 0; r < nrf; ++r) per_parent[d.face_parent[r]] += d.face_area[r];
  EXPECT_LT((per_parent - face_areas(V, F)).cwiseAbs().maxCoeff(), 1e-12 * area);
  EXPECT_NEAR(face_areas(d.V, d.F).sum(), area, 1e-9 * area);
  if (all_reached) {
    EXPECT_NEAR(d.cell_area.sum(), area, 1e-9 * area);
  }

  // conforming refined mesh: same topology as the input (no cracks, no T-junctions)
  const MeshTopology t0 = mesh_topology(F, nv), t1 = mesh_topology(d.F, static_cast<int>(d.V.rows()));
  EXPECT_EQ(t1.boundary_edges == 0, t0.boundary_edges == 0);
  EXPECT_EQ(t1.nonmanifold_edges, 0);
  EXPECT_EQ(t1.inconsistent_edges, 0);
  EXPECT_EQ(t1.euler_characteristic(), t0.euler_characteristic());
  EXPECT_EQ(t1.components, t0.components);
  if (closed) EXPECT_EQ(t1.boundary_edges, 0);

  // load vectors integrate to the cell areas
  const auto loads = cell_load_vectors(d, F);
  for (int c = 0; c < d.num_cells(); ++c) {
    double s = 0;
    for (auto& [v, w] : loads[c]) s += w;
    EXPECT_NEAR(s, d.cell_area[c], 1e-12 * area);
  }
  const auto single = cell_load_vector(d, F, 0);
  ASSERT_EQ(single.size(), loads[0].size());
  for (size_t i = 0; i < single.size(); ++i) {
    EXPECT_EQ(single[i].first, loads[0][i].first);
    EXPECT_NEAR(single[i].second, loads[0][i].second, 1e-15 * area);
  }

  // Voronoi vertices: ≥ 3 distinct cells, located in an original face
  std::vector<std::set<int>> cells_at(d.V.rows());
  for (int r = 0; r < nrf; ++r)
    for (int k = 0; k < 3; ++k)
      if (d.face_cell[r] >= 0) cells_at[d.F(r, k)].insert(d.face_cell[r]);
  int expected_vv = 0;
  for (auto& s : cells_at) expected_vv += s.size() >= 3;
  EXPECT_EQ(static_cast<int>(d.voronoi_vertices.size()), expected_vv);
  for (const VoronoiVertex& vv : d.voronoi_vertices) {
    EXPECT_GE(vv.cells.size(), 3u);
    EXPECT_TRUE(std::is_sorted(vv.cells.begin(), vv.cells.end()));
    EXPECT_LT((position(V, F, vv.location) - vv.position).norm(), 1e-12);
  }

  // adjacency symmetric; every edge polyline runs along refined edges separating its two cells
  std::map<std::pair<int, int>, std::set<int>> edge_cells;
  for (int r = 0; r < nrf; ++r)
    for (int k = 0; k < 3; ++k) {
      int a = d.F(r, k), b = d.F(r, (k + 1) % 3);
      auto& cs = edge_cells[{std::min(a, b), std::max(a, b)}];
      if (d.face_cell[r] >= 0) cs.insert(d.face_cell[r]);
    }
  for (int c = 0; c < d.num_cells(); ++c)
    for (int n : d.cell_adjacency[c]) {
      EXPECT_NE(n, c);
      EXPECT_TRUE(std::binary_search(d.cell_adjacency[n].begin(), d.cell_adjacency[n].end(), c));
    }
  size_t separating = 0;
  for (auto& [e, cs] : edge_cells) separating += cs.size() >= 2;
  size_t chained = 0;
  for (const VoronoiEdge& e : d.edges) {
    EXPECT_LT(e.cell_a, e.cell_b);
    ASSERT_GE(e.polyline.size(), 2u);
    EXPECT_TRUE(std::binary_search(d.cell_adjacency[e.cell_a].begin(), d.cell_adjacency[e.cell_a].end(), e.cell_b));
    for (size_t i = 0; i + 1 < e.polyline.size(); ++i) {
      const int a = e.polyline[i], b = e.polyline[i + 1];
      auto it = edge_cells.find({std::min(a, b), std::max(a, b)});
      ASSERT_NE(it, edge_cells.end()) << "polyline step is not a refined edge";
      EXPECT_TRUE(it->second.count(e.cell_a) && it->second.count(e.cell_b));
      ++chained;
    }
  }
  EXPECT_EQ(chained, separating) << "every separating edge lies on exactly one polyline";
}

}  // namespace

TEST(HeatField, DenseKeepsHottestSorted) {
  Eigen::MatrixXd U(2, 4);
  U << 0.1, 0.5, 0.3, 0.5, 1, 2, 3, 4;
  HeatField h = heat_field_from_dense(U, 3);
  ASSERT_EQ(h.num_vertices(), 2);
  EXPECT_EQ(h.num_sites, 4);
  EXPECT_EQ(std::vector<int>(h.site.begin(), h.site.begin() + 3), (std::vector<int>{1, 3, 2}));
  EXPECT_EQ(std::vector<int>(h.site.begin() + 3, h.site.end()), (std::vector<int>{3, 2, 1}));
  HeatField s = heat_field_from_sparse(2, {{0}, {0, 1}, {1}}, {{0.2}, {0.7, 0.1}, {0.4}}, 8);
  EXPECT_EQ(s.offsets, (std::vector<int>{0, 2, 4}));
  EXPECT_EQ(s.site, (std::vector<int>{1, 0, 2, 1}));
  EXPECT_THROW(heat_field_from_sparse(2, {{5}}, {{1.0}}, 8), InvalidInputError);
}

TEST(HeatVoronoi, InvalidInputIsRejected) {
  auto m = test::icosphere(1);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  EXPECT_THROW(heat_voronoi(m.V, m.F, solver, {}), InvalidInputError);
  EXPECT_THROW(heat_voronoi(m.V, m.F, solver, {SurfacePoint{static_cast<int>(m.F.rows()), {1, 0, 0}}}),
               InvalidInputError);
  EXPECT_THROW(heat_voronoi(m.V, m.F, solver, {SurfacePoint{0, {NAN, 0, 1}}}), InvalidInputError);
  HeatField wrong = heat_field_from_dense(Eigen::MatrixXd::Ones(3, 2));
  EXPECT_THROW(tessellate(m.V, m.F, wrong), InvalidInputError);
}

TEST(HeatVoronoi, BookkeepingOnIcosphere) {
  auto m = test::icosphere(3);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  const auto sites = random_sites(m.F, 25, 7);
  VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  SCOPED_TRACE("icosphere exact");
  check_diagram(m.V, m.F, d, true);
  EXPECT_EQ(d.num_cells(), 25);
  EXPECT_GT(d.F.rows(), m.F.rows());
  EXPECT_TRUE(d.unreached_components.empty());
  for (int c = 0; c < 25; ++c) EXPECT_GT(d.cell_area[c], 0.0);
  // a site's own face lies (mostly) in its cell: each cell is about 50 faces, so the face holding
  // the site is well inside the cell of the site
  for (int c = 0; c < 25; ++c) {
    double own = 0, total = 0;
    for (int r = 0; r < d.F.rows(); ++r)
      if (d.face_parent[r] == sites[c].face) {
        total += d.face_area[r];
        if (d.face_cell[r] == c) own += d.face_area[r];
      }
    ASSERT_GT(total, 0.0) << "site " << c;
    EXPECT_GT(own, 0.5 * total) << "site " << c;
  }
  // sphere: V − E + F = 2 for the cell complex (every cell a disk here)
  size_t adj = 0;
  for (auto& a : d.cell_adjacency) adj += a.size();
  EXPECT_EQ(static_cast<int>(d.num_cells()) - static_cast<int>(adj / 2) + static_cast<int>(d.voronoi_vertices.size()),
            2)
      << "Euler characteristic of the dual (sites, adjacencies, Voronoi vertices)";
  // deterministic: the same result with 1, 2 and 4 threads
  for (int threads : test::kThreadCounts) {
    SCOPED_TRACE(threads);
    VoronoiOptions one;
    one.threads = threads;
    VoronoiDiagram d1 = heat_voronoi(m.V, m.F, solver, sites, one);
    EXPECT_EQ(d1.F, d.F);
    EXPECT_EQ(d1.V, d.V);
    EXPECT_EQ(d1.face_cell, d.face_cell);
  }

  // the cheap labelling: one cell per original face, areas still partition the surface
  VoronoiOptions cheap;
  cheap.exact = false;
  VoronoiDiagram c = heat_voronoi(m.V, m.F, solver, sites, cheap);
  SCOPED_TRACE("icosphere cheap");
  EXPECT_EQ(c.F, m.F);
  check_diagram(m.V, m.F, c, true);
  // the cheap cells agree with the exact ones on most of the area
  double agree = 0;
  for (int r = 0; r < d.F.rows(); ++r)
    if (d.face_cell[r] == c.face_cell[d.face_parent[r]]) agree += d.face_area[r];
  EXPECT_GT(agree / surface_area(m.V, m.F), 0.9);
}

TEST(HeatVoronoi, BookkeepingOnMeshFiles) {
  for (const char* file : {"meshes/torus.obj", "meshes/bunny_manifold_3k.obj"}) {
    SCOPED_TRACE(file);
    TriangleMesh m = read_mesh(test::data_path(file));
    HeatSolver solver(cotan_laplacian(m.V, m.F));
    const auto sites = random_sites(m.F, 40, 11);
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
    check_diagram(m.V, m.F, d, mesh_topology(m.F, static_cast<int>(m.V.rows())).boundary_edges == 0);
    EXPECT_TRUE(d.unreached_components.empty());
  }
}

TEST(HeatVoronoi, BookkeepingOnGridWithTiesAndFewSitesPerVertex) {
  // symmetric sites on a regular grid: many exact ties at vertices (eq. 19 tie-break)
  auto m = test::grid(20, -1, 1, -1, 1);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::vector<SurfacePoint> sites;
  for (int v : {0, 20, 440, 420, 220}) {  // the four corners and the centre vertex
    for (int f = 0; f < m.F.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        if (m.F(f, k) == v && (sites.empty() || position(m.V, m.F, sites.back()) != m.V.row(v).transpose())) {
          SurfacePoint p;
          p.face = f;
          p.bary = Eigen::Vector3d::Unit(k);
          sites.push_back(p);
        }
  }
  ASSERT_EQ(sites.size(), 5u);
  for (int keep : {2, 8}) {
    VoronoiOptions opt;
    opt.keep_sites_per_vertex = keep;
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites, opt);
    SCOPED_TRACE("keep " + std::to_string(keep));
    check_diagram(m.V, m.F, d, false);
    // four-fold symmetry: the corner cells have equal areas (when no site is truncated away;
    // with keep = 2 the truncation of tied sites by index breaks the symmetry)
    if (keep >= 5)
      for (int c = 1; c < 4; ++c) EXPECT_NEAR(d.cell_area[c], d.cell_area[0], 1e-9);
  }
}

TEST(HeatVoronoi, UnreachedComponentIsReported) {
  auto a = test::icosphere(2);
  TriangleMesh m;
  m.V.resize(2 * a.V.rows(), 3);
  m.V << a.V, (a.V.rowwise() + Eigen::RowVector3d(5, 0, 0));
  m.F.resize(2 * a.F.rows(), 3);
  m.F << a.F, (a.F.array() + static_cast<int>(a.V.rows())).matrix();
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  const auto sites = random_sites(a.F, 6, 3);  // faces of the first sphere only
  // the solve gives exactly zero heat on the second component: no entries there
  VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  std::vector<std::vector<int>> idx(6);
  std::vector<std::vector<double>> val(6);
  const Eigen::VectorXd dummy;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m.V.rows(), 6);
  for (int s = 0; s < 6; ++s)
    for (int k = 0; k < 3; ++k) rhs(m.F(sites[s].face, k), s) += sites[s].bary[k];
  const Eigen::MatrixXd U = solver.solve(rhs);
  for (int s = 0; s < 6; ++s)
    for (int v = 0; v < m.V.rows(); ++v)
      if (U(v, s) != 0.0) {
        idx[s].push_back(v);
        val[s].push_back(U(v, s));
      }
  VoronoiDiagram sparse = tessellate(m.V, m.F, heat_field_from_sparse(static_cast<int>(m.V.rows()), idx, val));
  for (const VoronoiDiagram* dd : {&d, &sparse}) {
    ASSERT_EQ(dd->unreached_components.size(), 1u);
    check_diagram(m.V, m.F, *dd, true, false);
    double unreached_area = 0;
    for (int r = 0; r < dd->F.rows(); ++r) {
      const bool second = dd->face_parent[r] >= a.F.rows();
      EXPECT_EQ(dd->face_cell[r] < 0, second);
      if (second) unreached_area += dd->face_area[r];
    }
    EXPECT_NEAR(dd->cell_area.sum(), surface_area(a.V, a.F), 1e-9);
    EXPECT_NEAR(unreached_area, surface_area(a.V, a.F), 1e-9);
  }
  // both fields give the same cells
  EXPECT_EQ(d.face_cell, sparse.face_cell);
  EXPECT_EQ(d.F, sparse.F);
}

namespace {

// The surface point hit by the ray from the origin in direction `dir` (snap of a generator onto
// the triangulated sphere): the face whose barycentric coordinates of the hit are all ≥ 0 (the
// least negative one when the ray passes exactly through an edge or vertex).
SurfacePoint ray_hit(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const Eigen::Vector3d& dir) {
  SurfacePoint best;
  double best_min = -std::numeric_limits<double>::infinity();
  for (int f = 0; f < F.rows(); ++f) {
    Eigen::Matrix3d A;  // columns: corners; solve A λ = s·dir with Σλ = 1 → λ ∝ A⁻¹ dir
    for (int k = 0; k < 3; ++k) A.col(k) = V.row(F(f, k)).transpose();
    const Eigen::Vector3d l = A.fullPivLu().solve(dir);
    if (!(l.sum() > 0)) continue;
    const Eigen::Vector3d b = l / l.sum();
    if (b.minCoeff() > best_min) {
      best_min = b.minCoeff();
      best.face = f;
      best.bary = b.cwiseMax(0.0) / b.cwiseMax(0.0).sum();
    }
  }
  return best;
}

// Least-squares slope of log(err) against log(h).
double loglog_slope(const std::vector<double>& h, const std::vector<double>& err) {
  const int n = static_cast<int>(h.size());
  double mx = 0, my = 0;
  for (int i = 0; i < n; ++i) {
    mx += std::log(h[i]) / n;
    my += std::log(err[i]) / n;
  }
  double sxy = 0, sxx = 0;
  for (int i = 0; i < n; ++i) {
    sxy += (std::log(h[i]) - mx) * (std::log(err[i]) - my);
    sxx += (std::log(h[i]) - mx) * (std::log(h[i]) - mx);
  }
  return sxy / sxx;
}

struct BisectorError {
  double rms = 0, max = 0;
  int samples = 0;
};

// RMS/max of e(x) = xᵀ(p_i − p_j)/‖p_i − p_j‖ − offset over the points of the Voronoi edges
// (plane: offset = the bisector's distance from the origin; sphere: 0).
BisectorError bisector_error(const VoronoiDiagram& d, const std::vector<Eigen::Vector3d>& p,
                             const std::function<bool(const Eigen::Vector3d&)>& use) {
  BisectorError e;
  double sum = 0;
  for (const VoronoiEdge& edge : d.edges) {
    const Eigen::Vector3d n = (p[edge.cell_a] - p[edge.cell_b]).normalized();
    const double offset = n.dot(0.5 * (p[edge.cell_a] + p[edge.cell_b]));
    for (int v : edge.polyline) {
      const Eigen::Vector3d x = d.V.row(v).transpose();
      if (!use(x)) continue;
      const double err = n.dot(x) - offset;
      sum += err * err;
      e.max = std::max(e.max, std::abs(err));
      ++e.samples;
    }
  }
  e.rms = e.samples ? std::sqrt(sum / e.samples) : 0.0;
  return e;
}

}  // namespace

// Plane: two generators near the centre of a triangulated square; the heat bisector converges to
// the perpendicular bisector as the mesh is refined with a fixed time step (t = 0.05, kernel
// width ≈ 0.3 well resolved): the error shrinks at least 3× whenever h̄ halves (asymptotically
// quadratic). With t = h̄² the kernel is never resolved better and the error decays only ~h̄^0.5.
TEST(HeatVoronoi, PlaneBisectorConverges) {
  const std::vector<Eigen::Vector3d> gen = {Eigen::Vector3d(-0.21, 0.07, 0), Eigen::Vector3d(0.23, -0.11, 0)};
  std::vector<double> hs, rms, mx;
  for (int n : {16, 32, 64, 128}) {
    auto m = test::grid(n, -1, 1, -1, 1);
    HeatSolverOptions so;
    so.time_step = 0.05;
    HeatSolver solver(cotan_laplacian(m.V, m.F), so);
    std::vector<SurfacePoint> sites;
    const Eigen::MatrixX3d below = m.V.rowwise() - Eigen::RowVector3d(0, 0, 1);
    for (auto& g : gen) sites.push_back(ray_hit(below, m.F, g - Eigen::Vector3d(0, 0, 1)));
    for (size_t i = 0; i < gen.size(); ++i) ASSERT_LT((position(m.V, m.F, sites[i]) - gen[i]).norm(), 1e-12);
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
    ASSERT_EQ(d.num_cells(), 2);
    check_diagram(m.V, m.F, d, false);
    auto e = bisector_error(d, gen, [](const Eigen::Vector3d& x) { return x.cwiseAbs().maxCoeff() < 0.5; });
    ASSERT_GT(e.samples, n / 2);
    hs.push_back(mean_edge_length(m.V, m.F));
    rms.push_back(e.rms);
    mx.push_back(e.max);
    std::printf("plane t=0.05 n=%d h=%.4g rms=%.3e max=%.3e samples=%d\n", n, hs.back(), e.rms, e.max, e.samples);
  }
  std::printf("plane slope rms %.2f max %.2f\n", loglog_slope(hs, rms), loglog_slope(hs, mx));
  for (size_t i = 2; i < hs.size(); ++i) {
    EXPECT_GE(rms[i - 1] / rms[i], 3.0) << "rms, step " << i;
    EXPECT_GE(mx[i - 1] / mx[i], 3.0) << "max, step " << i;
  }
  EXPECT_LT(rms.back(), 1e-3);
  EXPECT_GE(loglog_slope(hs, rms), 1.7);
}

// Sphere (Fig. 3): generators (1,0,0), (−1,0,0), (0,1,0) on random triangulations; the RMS
// bisector error decreases quadratically with the mean edge length for t = 1 and t = 2⁻⁷.
// Uniform points: 4 resolutions (500–32k points), slope ≥ 1.8 (measured 1.95 / 1.98).
// Density-biased points (x scaled by 4 before normalising, many obtuse triangles): the points
// crowd toward the ±x poles, so the triangles crossed by the bisectors (near x = 0 and x = ±y) are
// coarser than the mean and the quadratic regime starts later: measured over 500–128k points the
// slopes are only 1.78 / 1.69 (the coarse end is pre-asymptotic, local slopes rise 1.5 → 1.9), so
// the biased fit uses the 4 resolutions 8k–256k points: measured 2.04 (t = 1) and 1.82 (t = 2⁻⁷).
TEST(HeatVoronoi, SphereBisectorConvergesQuadratically) {
  const std::vector<Eigen::Vector3d> gen = {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0),
                                            Eigen::Vector3d(0, 1, 0)};
  for (bool biased : {false, true}) {
    std::vector<TriangleMesh> meshes;
    const std::vector<int> sizes =
        biased ? std::vector<int>{8000, 32000, 128000, 256000} : std::vector<int>{500, 2000, 8000, 32000};
    for (int n : sizes) meshes.push_back(random_sphere_mesh(n, 17, biased));
    for (double t : {1.0, std::pow(2.0, -7)}) {
      std::vector<double> hs, rms;
      for (auto& m : meshes) {
        HeatSolverOptions so;
        so.time_step = t;
        HeatSolver solver(cotan_laplacian(m.V, m.F), so);
        std::vector<SurfacePoint> sites;
        for (auto& g : gen) sites.push_back(ray_hit(m.V, m.F, g));
        VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
        ASSERT_EQ(d.cell_adjacency[0].size(), 2u);
        EXPECT_NEAR(d.cell_area.sum(), surface_area(m.V, m.F), 1e-9 * surface_area(m.V, m.F));
        auto e = bisector_error(d, gen, [](const Eigen::Vector3d&) { return true; });
        hs.push_back(mean_edge_length(m.V, m.F));
        rms.push_back(e.rms);
        std::printf("sphere %s t=%g V=%d h=%.4g rms=%.3e max=%.3e samples=%d\n", biased ? "biased" : "uniform", t,
                    static_cast<int>(m.V.rows()), hs.back(), e.rms, e.max, e.samples);
      }
      const double slope = loglog_slope(hs, rms);
      std::printf("sphere %s t=%g slope %.2f\n", biased ? "biased" : "uniform", t, slope);
      EXPECT_GE(slope, 1.8) << (biased ? "biased" : "uniform") << " t=" << t;
    }
  }
}

// Degenerate inputs: sites on the 12 icosahedron vertices of a subdivided icosahedron (exact
// ties on bisectors through vertices and along edges), many sites per face, and a localized
// field in which some vertices know no site at all.
TEST(HeatVoronoi, StressTiesManySitesAndLocalizedField) {
  auto m = test::icosphere(3);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  const double area = surface_area(m.V, m.F);
  {
    std::vector<SurfacePoint> sites;
    for (int v = 0; v < 12; ++v)
      for (int f = 0; f < m.F.rows() && static_cast<int>(sites.size()) <= v; ++f)
        for (int k = 0; k < 3; ++k)
          if (m.F(f, k) == v) {
            sites.push_back(SurfacePoint{f, Eigen::Vector3d::Unit(k)});
            break;
          }
    ASSERT_EQ(sites.size(), 12u);
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
    SCOPED_TRACE("icosahedron sites");
    check_diagram(m.V, m.F, d, true);
    // icosahedral symmetry: all cells have the same area, 5 neighbours, 20 Voronoi vertices
    for (int c = 0; c < 12; ++c) {
      EXPECT_NEAR(d.cell_area[c], area / 12, 1e-3 * area / 12);
      EXPECT_EQ(d.cell_adjacency[c].size(), 5u);
    }
    EXPECT_EQ(d.voronoi_vertices.size(), 20u);
  }
  {
    const auto sites = random_sites(m.F, 300, 21);  // about 2 vertices per site
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
    SCOPED_TRACE("300 sites");
    check_diagram(m.V, m.F, d, true);
    // the blocked solve + top-k merge of heat_voronoi equals the field of the full dense matrix
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m.V.rows(), 300);
    for (int s = 0; s < 300; ++s)
      for (int k = 0; k < 3; ++k) rhs(m.F(sites[s].face, k), s) += sites[s].bary[k];
    const HeatField full = heat_field_from_dense(solver.solve(rhs), 8);
    VoronoiDiagram e = tessellate(m.V, m.F, full);
    EXPECT_EQ(e.F, d.F);
    EXPECT_EQ(e.face_cell, d.face_cell);
    EXPECT_EQ(e.V, d.V);
  }
  {
    // localized: each site knows its heat only within a geodesic-ish ball (Euclidean 0.5)
    const auto sites = random_sites(m.F, 30, 8);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m.V.rows(), 30);
    for (int s = 0; s < 30; ++s)
      for (int k = 0; k < 3; ++k) rhs(m.F(sites[s].face, k), s) += sites[s].bary[k];
    const Eigen::MatrixXd U = solver.solve(rhs);
    std::vector<std::vector<int>> idx(30);
    std::vector<std::vector<double>> val(30);
    for (int s = 0; s < 30; ++s) {
      const Eigen::Vector3d p = position(m.V, m.F, sites[s]);
      for (int v = 0; v < m.V.rows(); ++v)
        if ((m.V.row(v).transpose() - p).norm() < 0.5) {
          idx[s].push_back(v);
          val[s].push_back(U(v, s));
        }
    }
    VoronoiDiagram d = tessellate(m.V, m.F, heat_field_from_sparse(static_cast<int>(m.V.rows()), idx, val, 4));
    SCOPED_TRACE("localized");
    int unknown = 0;
    for (int r = 0; r < d.F.rows(); ++r) unknown += d.face_cell[r] < 0;
    std::printf("localized field: %d refined faces without a site\n", unknown);
    check_diagram(m.V, m.F, d, true, unknown == 0);
    EXPECT_TRUE(d.unreached_components.empty());
  }
}

// Coincident and nearly coincident sites: identical heat everywhere (the smaller index takes the
// whole region, the duplicate cell is empty) and near-ties in one face; still a valid diagram.
TEST(HeatVoronoi, CoincidentAndNearlyCoincidentSites) {
  auto m = test::icosphere(3);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::vector<SurfacePoint> sites = random_sites(m.F, 6, 4);
  sites.push_back(sites[2]);  // exact duplicate of site 2
  SurfacePoint near = sites[4];
  near.bary += Eigen::Vector3d(1e-9, -1e-9, 0);  // 1e-9 away from site 4
  sites.push_back(near);
  VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites);
  check_diagram(m.V, m.F, d, true);
  EXPECT_EQ(d.cell_area[6], 0.0) << "the duplicate of site 2 has an empty cell";
  EXPECT_GT(d.cell_area[2], 0.0);
  EXPECT_GT(d.cell_area[4] + d.cell_area[7], 0.0);
}

// Randomised adversarial configurations: duplicated sites, sites 1e-3..1e-14 apart, sites on
// mesh vertices and on edges, truncated fields (keep 1..8). Every diagram must be valid.
TEST(HeatVoronoi, RandomDegenerateConfigurationsStayConforming) {
  auto m = test::icosphere(2);
  HeatSolver solver(cotan_laplacian(m.V, m.F));
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> face(0, static_cast<int>(m.F.rows()) - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 30);
    std::vector<SurfacePoint> sites;
    for (int i = 0; i < n; ++i) {
      const int kind = static_cast<int>(rng() % 5);
      SurfacePoint s;
      if (kind == 0 && !sites.empty()) {
        s = sites[rng() % sites.size()];
      } else if (kind == 1 && !sites.empty()) {
        s = sites[rng() % sites.size()];
        const double e = std::pow(10.0, -3.0 - static_cast<double>(rng() % 12));
        s.bary = (s.bary + Eigen::Vector3d(e, -e, 0)).cwiseMax(0.0);
        s.bary /= s.bary.sum();
      } else if (kind == 2) {
        s.face = face(rng);
        s.bary = Eigen::Vector3d::Unit(static_cast<int>(rng() % 3));
      } else if (kind == 3) {
        s.face = face(rng);
        const double u = unit(rng);
        s.bary = Eigen::Vector3d(u, 1 - u, 0);
      } else {
        s.face = face(rng);
        s.bary = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) + Eigen::Vector3d::Constant(1e-3);
        s.bary /= s.bary.sum();
      }
      sites.push_back(s);
    }
    VoronoiOptions opt;
    opt.keep_sites_per_vertex = 1 + static_cast<int>(rng() % 8);
    VoronoiDiagram d = heat_voronoi(m.V, m.F, solver, sites, opt);
    SCOPED_TRACE("trial " + std::to_string(trial));
    check_diagram(m.V, m.F, d, true);
    if (::testing::Test::HasFailure()) break;
  }
}
