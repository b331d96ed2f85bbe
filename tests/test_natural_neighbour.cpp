// Natural-neighbour coordinates by area stealing (paper §7.2): positivity, Lagrange property,
// partition of unity, the definition b_i = (a_i − ã_i)/a_q against a diagram with q inserted,
// exact zeros away from q's cell, continuity, Sibson's coordinates on a plane, armadillo handles
// with propagated weights against the direct computation, bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "heatcvt/closest_point.h"
#include "heatcvt/cvt.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/natural_neighbour.h"
#include "heatcvt/voronoi.h"
#include "test_support.h"

using namespace heatcvt;

namespace {

std::vector<SurfacePoint> random_points(const TriangleMesh& m, int count, unsigned seed) {
  return initial_sites(m.V, m.F, count, CvtInitialization::random, seed);
}

Eigen::VectorXd dense(const std::vector<std::pair<int, double>>& w, int n) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (const auto& [s, v] : w) x[s] = v;
  return x;
}

void expect_coordinate_properties(const NaturalNeighbourQuery& r, int n, const char* where) {
  ASSERT_FALSE(r.weights.empty()) << where;
  double sum = 0;
  for (const auto& [s, w] : r.weights) {
    EXPECT_GE(s, 0);
    EXPECT_LT(s, n);
    EXPECT_GE(w, -1e-12) << where << ": negative coordinate of site " << s;
    sum += w;
  }
  EXPECT_NEAR(sum, 1.0, 1e-9) << where << ": no partition of unity";
  EXPECT_GT(r.cell_area, 0) << where;
}

// Unit disk: the centre and `rings` concentric rings of 6r points (ring r at radius r/rings),
// consecutive rings stitched by merging their angles: near-equilateral triangles.
TriangleMesh disk_mesh(int rings) {
  std::vector<Eigen::Vector3d> v = {Eigen::Vector3d::Zero()};
  std::vector<std::vector<int>> ring_ids = {{0}};
  std::vector<std::vector<double>> ring_angles = {{0.0}};
  for (int r = 1; r <= rings; ++r) {
    const int count = 6 * r;
    ring_ids.emplace_back();
    ring_angles.emplace_back();
    for (int k = 0; k < count; ++k) {
      const double a = 2 * M_PI * (k + 0.5 * (r % 2)) / count;
      ring_ids.back().push_back(static_cast<int>(v.size()));
      ring_angles.back().push_back(a);
      v.emplace_back(std::cos(a) * r / rings, std::sin(a) * r / rings, 0.0);
    }
  }
  std::vector<Eigen::Vector3i> f;
  for (int k = 0; k < 6; ++k) f.emplace_back(0, ring_ids[1][k], ring_ids[1][(k + 1) % 6]);
  for (int r = 2; r <= rings; ++r) {
    const auto &in = ring_ids[r - 1], &out = ring_ids[r];
    const auto &ain = ring_angles[r - 1], &aout = ring_angles[r];
    const int ni = static_cast<int>(in.size()), no = static_cast<int>(out.size());
    int i = 0, j = 0;
    // unwrap angles so both walks start at the smallest angle and go once around
    auto angle = [](const std::vector<double>& a, int k) {
      const int n = static_cast<int>(a.size());
      return a[k % n] + 2 * M_PI * (k / n);
    };
    while (i < ni || j < no) {
      const bool advance_out = i >= ni || (j < no && angle(aout, j + 1) <= angle(ain, i + 1));
      if (advance_out) {
        f.emplace_back(in[i % ni], out[j % no], out[(j + 1) % no]);
        ++j;
      } else {
        f.emplace_back(in[i % ni], out[j % no], in[(i + 1) % ni]);
        ++i;
      }
    }
  }
  TriangleMesh m;
  m.V.resize(v.size(), 3);
  m.F.resize(f.size(), 3);
  for (size_t k = 0; k < v.size(); ++k) m.V.row(k) = v[k];
  for (size_t k = 0; k < f.size(); ++k) m.F.row(k) = f[k];
  return m;
}

using Polygon2 = std::vector<Eigen::Vector2d>;

// Keeps the part of the polygon closer to a than to b.
void clip_bisector(Polygon2& poly, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d n = b - a;
  const double c = 0.5 * (b.squaredNorm() - a.squaredNorm());
  Polygon2 out;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& p = poly[i];
    const Eigen::Vector2d& q = poly[(i + 1) % poly.size()];
    const double gp = c - n.dot(p), gq = c - n.dot(q);
    if (gp >= 0) out.push_back(p);
    if ((gp >= 0) != (gq >= 0)) out.push_back(p + gp / (gp - gq) * (q - p));
  }
  poly.swap(out);
}

double polygon_area(const Polygon2& p) {
  double a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& x = p[i];
    const auto& y = p[(i + 1) % p.size()];
    a += x.x() * y.y() - x.y() * y.x();
  }
  return 0.5 * std::abs(a);
}

// Sibson's coordinates with Voronoi cells clipped to the polygon `domain` (exact for polygons).
std::vector<double> sibson(const std::vector<Eigen::Vector2d>& sites, const Eigen::Vector2d& q, const Polygon2& domain) {
  const int n = static_cast<int>(sites.size());
  Polygon2 cq = domain;
  for (int j = 0; j < n; ++j) clip_bisector(cq, q, sites[j]);
  std::vector<double> b(n, 0.0);
  double total = 0;
  for (int i = 0; i < n; ++i) {
    Polygon2 p = cq;
    for (int j = 0; j < n && p.size() >= 3; ++j)
      if (j != i) clip_bisector(p, sites[i], sites[j]);
    b[i] = p.size() >= 3 ? polygon_area(p) : 0.0;
    total += b[i];
  }
  for (double& x : b) x /= total;
  return b;
}

}  // namespace

TEST(NaturalNeighbour, PositivityPartitionOfUnityLagrangeOnASphere) {
  const TriangleMesh m = test::icosphere(4);
  const auto sites = random_points(m, 12, 3);
  NaturalNeighbourOptions o;
  o.keep_sites_per_vertex = 16;
  NaturalNeighbourCoordinates nn(m.V, m.F, sites, o);
  EXPECT_EQ(nn.num_sites(), 12);
  EXPECT_NEAR(nn.diagram().cell_area.sum(), surface_area(m.V, m.F), 1e-9);
  const auto queries = random_points(m, 40, 11);
  const auto batch = nn.query(queries);
  for (size_t i = 0; i < queries.size(); ++i) {
    const auto single = nn.query(queries[i]);
    expect_coordinate_properties(single, 12, "sphere query");
    // batched and single queries agree
    EXPECT_LE((dense(single.weights, 12) - dense(batch[i].weights, 12)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_GE(single.weights.size(), 2u) << "a generic point has several natural neighbours";
  }
  // Lagrange: at every site the coordinates are the unit vector
  for (int s = 0; s < 12; ++s) {
    const auto r = nn.query(sites[s]);
    const Eigen::VectorXd b = dense(r.weights, 12);
    EXPECT_NEAR(b[s], 1.0, 1e-9);
    EXPECT_NEAR(b.sum() - b[s], 0.0, 1e-9);
  }
  // … and they tend to it continuously: a point very close to a site is dominated by it
  for (int s = 0; s < 12; ++s) {
    SurfacePoint p = sites[s];
    p.bary = 0.999 * p.bary + 0.001 * Eigen::Vector3d::Constant(1.0 / 3);
    if ((position(m.V, m.F, p) - position(m.V, m.F, sites[s])).norm() == 0) continue;
    EXPECT_GT(dense(nn.query(p).weights, 12)[s], 0.9);
  }
}

TEST(NaturalNeighbour, AreaStealingMatchesTheDiagramWithTheQueryInsertedAndIsLocal) {
  const TriangleMesh m = test::icosphere(4);
  const int n = 14;
  const auto sites = random_points(m, n, 5);
  NaturalNeighbourOptions o;
  o.keep_sites_per_vertex = 24;  // every site at every vertex: both diagrams see the same heat
  NaturalNeighbourCoordinates nn(m.V, m.F, sites, o);
  const Eigen::VectorXd a = nn.diagram().cell_area;
  int zeros_checked = 0;
  for (const SurfacePoint& q : random_points(m, 12, 21)) {
    const auto r = nn.query(q);
    expect_coordinate_properties(r, n, "inserted query");
    // the diagram of sites ∪ {q}: ã_i and a_q, and q's neighbouring cells
    std::vector<SurfacePoint> with_q = sites;
    with_q.push_back(q);
    VoronoiOptions vo;
    vo.keep_sites_per_vertex = 24;
    const VoronoiDiagram d = heat_voronoi(m.V, m.F, nn.solver(), with_q, vo);
    const double aq = d.cell_area[n];
    EXPECT_NEAR(r.cell_area, aq, 1e-9 * a.sum());
    const Eigen::VectorXd b = dense(r.weights, n);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(b[i], (a[i] - d.cell_area[i]) / aq, 1e-7) << "site " << i;
    // exact zeros for sites whose cells are not neighbours of q's cell
    const auto& adj = d.cell_adjacency[n];
    for (int i = 0; i < n; ++i)
      if (!std::binary_search(adj.begin(), adj.end(), i)) {
        EXPECT_EQ(b[i], 0.0) << "site " << i << " is not a natural neighbour of q";
        ++zeros_checked;
      }
  }
  EXPECT_GT(zeros_checked, 12) << "the test must exercise locality";
}

TEST(NaturalNeighbour, ContinuousInTheQueryPoint) {
  const TriangleMesh m = test::icosphere(4);
  const auto sites = random_points(m, 10, 8);
  NaturalNeighbourCoordinates nn(m.V, m.F, sites);
  const double spacing = std::sqrt(surface_area(m.V, m.F) / 10);
  for (const SurfacePoint& q : random_points(m, 10, 9)) {
    const Eigen::VectorXd b0 = dense(nn.query(q).weights, 10);
    for (double eps : {1e-2, 1e-3, 1e-4}) {
      SurfacePoint p = q;
      p.bary = (1 - eps) * q.bary + eps * Eigen::Vector3d(1, 0, 0);
      const double step = (position(m.V, m.F, p) - position(m.V, m.F, q)).norm();
      const Eigen::VectorXd b1 = dense(nn.query(p).weights, 10);
      // Lipschitz with a constant of the order of 1 / cell size
      EXPECT_LE((b1 - b0).cwiseAbs().maxCoeff(), 10.0 * step / spacing + 1e-12) << "eps " << eps;
    }
  }
}

TEST(NaturalNeighbour, ApproximatesSibsonCoordinatesOnAPlane) {
  const TriangleMesh m = disk_mesh(80);  // 19,441 vertices
  ASSERT_EQ(m.V.rows(), 1 + 3 * 80 * 81);
  EXPECT_NEAR(surface_area(m.V, m.F), M_PI, 0.01);
  const MeshTopology topo = mesh_topology(m.F, static_cast<int>(m.V.rows()));
  ASSERT_EQ(topo.euler_characteristic(), 1);
  ASSERT_EQ(topo.inconsistent_edges, 0);
  ASSERT_EQ(topo.nonmanifold_edges, 0);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> uni(-1, 1);
  auto random_in_disk = [&](double radius) {
    while (true) {
      const Eigen::Vector2d p(uni(rng), uni(rng));
      if (p.norm() < 1) return Eigen::Vector2d(radius * p);
    }
  };
  std::vector<Eigen::Vector2d> s2;
  Eigen::MatrixX3d P(20, 3);
  for (int i = 0; i < 20; ++i) {
    s2.push_back(random_in_disk(0.8));
    P.row(i) << s2.back().x(), s2.back().y(), 0.0;
  }
  Polygon2 domain;
  for (int k = 0; k < 512; ++k) domain.emplace_back(std::cos(2 * M_PI * k / 512), std::sin(2 * M_PI * k / 512));
  NaturalNeighbourCoordinates nn(m.V, m.F, closest_surface_points(m.V, m.F, P));
  double max_err = 0;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector2d q = random_in_disk(0.7);
    Eigen::MatrixX3d Q(1, 3);
    Q << q.x(), q.y(), 0.0;
    const auto r = nn.query(closest_surface_points(m.V, m.F, Q)[0]);
    const Eigen::VectorXd b = dense(r.weights, 20);
    const std::vector<double> ref = sibson(s2, q, domain);
    for (int i = 0; i < 20; ++i) max_err = std::max(max_err, std::abs(b[i] - ref[i]));
  }
  std::printf("[ info ] disk (%ld vertices), 20 sites, 40 queries: max |heat − Sibson| = %.4f\n",
              static_cast<long>(m.V.rows()), max_err);
  EXPECT_LE(max_err, 0.05);
}

TEST(NaturalNeighbour, ArmadilloHandlesPropagatedMatchDirect) {
  const TriangleMesh m = read_mesh(test::data_path("meshes/armadillo.obj"));
  const int nv = static_cast<int>(m.V.rows());
  const auto handles = initial_sites(m.V, m.F, 7, CvtInitialization::farthest_point, 1);
  NaturalNeighbourOptions o;
  o.threads = 2;
  NaturalNeighbourCoordinates nn(m.V, m.F, handles, o);
  std::vector<int> samples;
  const VertexWeights W = nn.vertex_weights({}, &samples);
  ASSERT_EQ(W.rows(), nv);
  ASSERT_EQ(W.cols(), 7);
  for (int v = 0; v < nv; ++v) {
    ASSERT_NEAR(W.row(v).sum(), 1.0, 1e-9) << "vertex " << v;
    for (VertexWeights::InnerIterator it(W, v); it; ++it) ASSERT_GE(it.value(), 0.0);
  }
  // Lagrange at the handles' vertices (the handles are vertices here)
  for (int s = 0; s < 7; ++s) {
    int k = 0;
    handles[s].bary.maxCoeff(&k);
    EXPECT_NEAR(W.coeff(m.F(handles[s].face, k), s), 1.0, 1e-9);
  }
  // exact at the samples, within 1e-2 of the direct computation elsewhere
  std::mt19937 rng(2);
  std::vector<int> probe;
  for (int i = 0; i < 60; ++i) probe.push_back(std::uniform_int_distribution<int>(0, nv - 1)(rng));
  for (int i = 0; i < 5; ++i) probe.push_back(samples[i * samples.size() / 5]);
  const auto direct = nn.query(surface_points_at_vertices(m.F, nv, probe));
  double max_err = 0;
  for (size_t i = 0; i < probe.size(); ++i) {
    expect_coordinate_properties(direct[i], 7, "armadillo direct");
    const Eigen::VectorXd got = Eigen::VectorXd(W.row(probe[i]).transpose());
    const double e = (got - dense(direct[i].weights, 7)).cwiseAbs().maxCoeff();
    max_err = std::max(max_err, e);
    if (std::binary_search(samples.begin(), samples.end(), probe[i])) EXPECT_LE(e, 1e-12);
  }
  std::printf("[ info ] armadillo, 7 handles, %zu samples: max |propagated − direct| = %.2e over %zu vertices\n",
              samples.size(), max_err, probe.size());
  EXPECT_LE(max_err, 1e-2);
  // interpolation reproduces constants (partition of unity)
  const Eigen::MatrixXd c = interpolate_site_values(W, Eigen::MatrixXd::Constant(7, 2, 0.25));
  EXPECT_LE((c.array() - 0.25).abs().maxCoeff(), 1e-9);
}

TEST(NaturalNeighbour, BadInputThrows) {
  const TriangleMesh m = test::icosphere(2);
  const auto sites = random_points(m, 4, 1);
  EXPECT_THROW(NaturalNeighbourCoordinates(m.V, m.F, {sites[0]}), InvalidInputError);
  std::vector<SurfacePoint> bad = sites;
  bad[1].face = static_cast<int>(m.F.rows());
  EXPECT_THROW(NaturalNeighbourCoordinates(m.V, m.F, bad), InvalidInputError);
  bad = sites;
  bad[2].bary = Eigen::Vector3d(NAN, 0, 0);
  EXPECT_THROW(NaturalNeighbourCoordinates(m.V, m.F, bad), InvalidInputError);
  NaturalNeighbourOptions o;
  o.time_coefficient = 0;
  EXPECT_THROW(NaturalNeighbourCoordinates(m.V, m.F, sites, o), InvalidInputError);
  NaturalNeighbourCoordinates nn(m.V, m.F, sites);
  SurfacePoint q;
  q.face = -1;
  EXPECT_THROW(nn.query(q), InvalidInputError);
  const VertexWeights W = nn.vertex_weights();
  EXPECT_THROW(interpolate_site_values(W, Eigen::MatrixXd::Zero(3, 1)), InvalidInputError);
}
