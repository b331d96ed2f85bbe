// Sharp creases kept as feature lines (mesher/creases.h): detection on shapes built in code, and
// meshcvt's remesh of a cube built in code and of the shared fandisk with and without them.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/creases.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/remesh.h"
#include "heatcvt/validate.h"
#include "test_support.h"

namespace heatcvt {
namespace {

// A box of the given side lengths with a corner at the origin, each side a grid of squares of
// about `step` (at least one per side) split into two triangles, outward oriented.
TriangleMesh box_mesh(const Eigen::Vector3d& size, double step) {
  Eigen::Vector3i cells;
  for (int a = 0; a < 3; ++a) cells[a] = std::max(1, static_cast<int>(std::lround(size[a] / step)));
  std::map<std::tuple<int, int, int>, int> index;
  std::vector<Eigen::Vector3d> points;
  const auto vertex = [&](const Eigen::Vector3i& g) {
    const auto [it, added] = index.emplace(std::make_tuple(g.x(), g.y(), g.z()), static_cast<int>(points.size()));
    if (added) points.push_back(size.cwiseProduct(g.cast<double>().cwiseQuotient(cells.cast<double>())));
    return it->second;
  };
  std::vector<Eigen::Vector3i> faces;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < cells[u]; ++i)
        for (int j = 0; j < cells[w]; ++j) {
          const auto at = [&](int a, int b) {
            Eigen::Vector3i g = Eigen::Vector3i::Zero();
            g[axis] = side * cells[axis], g[u] = a, g[w] = b;
            return vertex(g);
          };
          const int p = at(i, j), q = at(i + 1, j), r = at(i + 1, j + 1), s = at(i, j + 1);
          // u × w points along +axis: counter-clockwise seen from outside on side 1.
          if (side == 1) faces.push_back({p, q, r}), faces.push_back({p, r, s});
          else faces.push_back({p, r, q}), faces.push_back({p, s, r});
        }
    }
  TriangleMesh m;
  m.V.resize(points.size(), 3);
  for (std::size_t v = 0; v < points.size(); ++v) m.V.row(v) = points[v].transpose();
  m.F.resize(faces.size(), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) m.F.row(f) = faces[f].transpose();
  return m;
}

// The unit cube, each side an n×n grid.
TriangleMesh cube_mesh(int n) { return box_mesh(Eigen::Vector3d::Ones(), 1.0 / n); }

double point_segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// Largest distance, over points along every crease edge of `input` (its ends and three points
// between), to the nearest edge of `output` running within 30° of that crease edge's direction:
// how far the crease lines are from an edge path of the output.
double crease_gap(const TriangleMesh& input, const TriangleMesh& output) {
  const CreaseLines lines = detect_creases(input.V, input.F);
  std::vector<std::pair<int, int>> edges;
  for (int f = 0; f < output.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (output.F(f, k) < output.F(f, (k + 1) % 3)) edges.emplace_back(output.F(f, k), output.F(f, (k + 1) % 3));
  double worst = 0;
  for (const std::vector<int>& line : lines.lines)
    for (std::size_t i = 1; i < line.size(); ++i) {
      const Eigen::Vector3d a = input.V.row(line[i - 1]).transpose(), b = input.V.row(line[i]).transpose();
      const Eigen::Vector3d dir = (b - a).normalized();
      for (int s = 0; s <= 4; ++s) {
        const Eigen::Vector3d p = a + (b - a) * s / 4.0;
        double best = std::numeric_limits<double>::infinity();
        for (const auto& [u, w] : edges) {
          const Eigen::Vector3d x = output.V.row(u).transpose(), y = output.V.row(w).transpose();
          if (std::abs((y - x).normalized().dot(dir)) < std::cos(30 * M_PI / 180)) continue;
          best = std::min(best, point_segment_distance(p, x, y));
        }
        worst = std::max(worst, best);
      }
    }
  return worst;
}

double diagonal(const TriangleMesh& m) { return (m.V.colwise().maxCoeff() - m.V.colwise().minCoeff()).norm(); }

TEST(Creases, ACubeHasTwelveLinesAndEightCornersASphereNone) {
  const TriangleMesh cube = cube_mesh(6);
  const CreaseLines lines = detect_creases(cube.V, cube.F);
  EXPECT_EQ(lines.lines.size(), 12u);
  EXPECT_EQ(std::count(lines.corner.begin(), lines.corner.end(), 1), 8);
  for (int l = 0; l < static_cast<int>(lines.lines.size()); ++l) {
    EXPECT_NEAR(lines.length(cube.V, l), 1.0, 1e-12) << "line " << l << " runs from corner to corner";
    EXPECT_TRUE(lines.corner[lines.lines[l].front()] && lines.corner[lines.lines[l].back()]);
  }
  // A dihedral threshold above the cube's 90° finds nothing; so does a smooth sphere.
  CreaseOptions steep;
  steep.min_dihedral_deg = 95;
  EXPECT_TRUE(detect_creases(cube.V, cube.F, steep).lines.empty());
  const TriangleMesh sphere = test::icosphere(3);
  EXPECT_TRUE(detect_creases(sphere.V, sphere.F).lines.empty());
}

// A closed crease loop without corners (a cylinder's rim, the crease between its side and a flat
// cap) is one line that ends where it starts.
TEST(Creases, ACornerlessLoopIsOneClosedLine) {
  const int n = 24;
  TriangleMesh m;
  m.V.resize(2 * n + 1, 3);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    m.V.row(i) << std::cos(a), std::sin(a), 0;
    m.V.row(n + i) << std::cos(a), std::sin(a), -0.5;
  }
  m.V.row(2 * n) << 0, 0, 0;
  m.F.resize(3 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    m.F.row(3 * i) << 2 * n, i, j;
    m.F.row(3 * i + 1) << i, n + i, n + j;
    m.F.row(3 * i + 2) << i, n + j, j;
  }
  const CreaseLines lines = detect_creases(m.V, m.F);
  ASSERT_EQ(lines.lines.size(), 1u);
  EXPECT_EQ(lines.lines[0].front(), lines.lines[0].back());
  EXPECT_EQ(lines.lines[0].size(), static_cast<std::size_t>(n + 1));
  EXPECT_EQ(std::count(lines.corner.begin(), lines.corner.end(), 1), 0);
}

// One documented rule for every input: every crease within 0.5 % of the diagonal of an output
// edge path, a valid closed output of the input's genus, φm ≥ 52°; without the crease stage the
// same remesh misses the rule (so the check measures what the stage does).
void expect_creases_kept(const TriangleMesh& input, int sites) {
  RemeshOptions o;
  o.cvt.sites = sites;
  const RemeshResult with = remesh_cvt(input, o);
  EXPECT_TRUE(with.checks.ok()) << with.checks.summary();
  EXPECT_FALSE(with.creases.undone);
  EXPECT_GT(with.creases.lines, 0);
  EXPECT_LE(std::abs(static_cast<int>(with.mesh.V.rows()) - sites), 0.02 * sites);
  EXPECT_GE(with.quality.mean_min_angle_deg, 52);
  EXPECT_LE(crease_gap(input, with.mesh), 0.005 * diagonal(input));
  o.creases.enabled = false;
  const RemeshResult without = remesh_cvt(input, o);
  ASSERT_TRUE(without.checks.ok());
  EXPECT_GT(crease_gap(input, without.mesh), 0.005 * diagonal(input)) << "the rounded creases fail the rule";
}

TEST(Creases, ACubeRemeshKeepsItsEdgesAndCorners) { expect_creases_kept(cube_mesh(30), 1000); }

TEST(Creases, TheResultDoesNotDependOnTheThreadCount) {
  const TriangleMesh cube = cube_mesh(30);
  RemeshOptions o;
  o.cvt.sites = 600;
  o.cvt.threads = 1;
  const RemeshResult one = remesh_cvt(cube, o);
  ASSERT_GT(one.creases.snapped, 0);
  ASSERT_FALSE(one.creases.undone);
  o.cvt.threads = 2;
  const RemeshResult two = remesh_cvt(cube, o);
  EXPECT_TRUE(one.mesh.V == two.mesh.V);
  EXPECT_TRUE(one.mesh.F == two.mesh.F);
}

// Largest distance from an input vertex to the surface of `mesh`.
double farthest_input_vertex(const TriangleMesh& input, const TriangleMesh& mesh) {
  const std::vector<SurfacePoint> nearest = closest_surface_points(mesh.V, mesh.F, input.V);
  double farthest = 0;
  for (Eigen::Index v = 0; v < input.V.rows(); ++v)
    farthest = std::max(farthest, (position(mesh.V, mesh.F, nearest[v]) - input.V.row(v).transpose()).norm());
  return farthest;
}

// Coarse organic meshes have 60° dihedral angles at the tips of horns and ears; snapping a tip's
// vertex onto such a short "crease" would cut the tip. The rule for every mesh: with the crease
// stage the input vertex farthest from the output is at most max_crease_gap_growth (1.1) times
// as far as without it.
TEST(Creases, TipsOfOrganicMeshesAreNotCut) {
  for (const char* name : {"meshes/spot.obj", "meshes/elephant.off"}) {
    SCOPED_TRACE(name);
    const TriangleMesh input = read_mesh(test::data_path(name));
    ASSERT_FALSE(detect_creases(input.V, input.F).lines.empty()) << "the mesh has 60° edges";
    RemeshOptions o;
    o.cvt.sites = 1000;
    const RemeshResult with = remesh_cvt(input, o);
    o.creases.enabled = false;
    const RemeshResult without = remesh_cvt(input, o);
    EXPECT_TRUE(with.checks.ok());
    EXPECT_LE(farthest_input_vertex(input, with.mesh), o.max_crease_gap_growth * farthest_input_vertex(input, without.mesh));
  }
}

// casting has creases along parts thinner than the spacing at 3,000 vertices: snapping their
// samples to the nearest vertices folds the mesh there. Those lines are left out one by one, the
// others kept, and no face pair crosses that did not (the smallest-angle guard is off here, so
// that the recovery is kept and measured).
TEST(Creases, LinesAlongThinPartsAreLeftOutAlone) {
  const TriangleMesh input = read_mesh(test::data_path("meshes/casting.obj"));
  RemeshOptions o;
  o.cvt.sites = 3000;
  o.creases.enabled = false;
  const RemeshResult plain = remesh_cvt(input, o);
  const MeshSurfaceProjector surface(input.V, input.F);
  WorkingMesh work = working_mesh_of(plain.mesh, surface);
  const long crossing_before = self_intersecting_pairs(work);
  CreaseOptions co;
  co.min_angle_deg = 0;
  const CreaseStats stats = recover_creases(work, surface, input.V, detect_creases(input.V, input.F), co);
  ASSERT_FALSE(stats.undone) << stats.undone_reason;
  EXPECT_GT(stats.skipped_lines, 0);
  EXPECT_GT(stats.lines, stats.skipped_lines);
  EXPECT_LE(self_intersecting_pairs(work), crossing_before);
}

// A plate about one spacing thick: the faces across its rim have all three corners on the two
// lines along it. Spread evenly, the samples of the two lines face each other and those faces
// fall below meshcvt's 30°; slid along their lines they are staggered. The rule is meshcvt's for
// every mesh: φmin ≥ 30°, every check, the creases within 0.5 % of the diagonal.
TEST(Creases, VerticesSlideAlongLinesAcrossAThinPlate) {
  const double thickness = 0.05;
  const TriangleMesh plate = box_mesh(Eigen::Vector3d(1, 1, thickness), 1.0 / 40);
  RemeshOptions o;
  o.cvt.sites = 1000;
  const double spacing = std::sqrt((2 + 4 * thickness) / o.cvt.sites);  // area over sites
  ASSERT_LT(thickness, 1.5 * spacing) << "the rim is about one spacing wide";
  o.creases.slide_steps = 0;
  const RemeshResult spread = remesh_cvt(plate, o);
  ASSERT_FALSE(spread.creases.undone) << spread.creases.undone_reason;
  ASSERT_LT(spread.quality.min_angle_deg, 30) << "evenly spread samples across the rim";
  o.creases.slide_steps = RemeshOptions().creases.slide_steps;
  const RemeshResult slid = remesh_cvt(plate, o);
  ASSERT_FALSE(slid.creases.undone) << slid.creases.undone_reason;
  EXPECT_EQ(slid.creases.lines, spread.creases.lines);
  EXPECT_TRUE(slid.checks.ok()) << slid.checks.summary();
  EXPECT_GE(slid.quality.min_angle_deg, 30);
  EXPECT_LE(crease_gap(plate, slid.mesh), 0.005 * diagonal(plate));
}

TEST(Creases, FandiskRemeshKeepsItsCreases) {
  const TriangleMesh fandisk = read_mesh(test::data_path("meshes/fandisk.off"));
  expect_creases_kept(fandisk, 3000);
}

// max_planck_decimated (a decimated scan) at 2,222 sites: its "creases" are ragged edges of the
// decimation, and two of them met at the output's scale at well under a degree. Such a corner
// excused the sliver between them: φmin 0.7°. No face below half of min_angle_deg is excused
// now; the lines next to such faces are left out and the others kept: creases are still
// recovered (most of the lines), with every face at least that half and every check passed.
// The input is refined by midpoint subdivision, on which CVT those two lines meet.
TEST(Creases, TwoRaggedLinesMeetingSharplyExcuseNoSliver) {
  const TriangleMesh input = read_mesh(test::data_path("meshes/max_planck_decimated.obj"));
  RemeshOptions o;
  o.refinement_method = RemeshOptions::Refinement::midpoint;
  o.cvt.sites = 2222;
  o.cvt.threads = 2;
  const RemeshResult r = remesh_cvt(input, o);
  ASSERT_FALSE(r.creases.undone) << r.creases.undone_reason;
  EXPECT_GT(r.creases.dropped_crease_lines, 0);
  EXPECT_GT(r.creases.lines, r.creases.dropped_crease_lines);
  EXPECT_GE(r.quality.min_angle_deg, 0.5 * o.creases.min_angle_deg);
  EXPECT_TRUE(r.checks.ok()) << r.checks.summary();
}


// A flat sheet of n × n unit cells (scaled to side 1) keeping the cells (i, j) with
// i + j < n when `staircase`: a right triangle whose hypotenuse is a staircase of cell steps.
TriangleMesh sheet_mesh(int n, bool staircase) {
  TriangleMesh m;
  m.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.V.row(j * (n + 1) + i) << static_cast<double>(i) / n, static_cast<double>(j) / n, 0;
  std::vector<Eigen::Vector3i> faces;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (staircase && i + j >= n) continue;
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      faces.emplace_back(a, b, d);
      faces.emplace_back(a, d, c);
    }
  m.F.resize(static_cast<int>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) m.F.row(f) = faces[f].transpose();
  // drop the vertices no face uses (the staircase's far half)
  std::vector<int> index(m.V.rows(), -1);
  int used = 0;
  for (int f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (index[m.F(f, k)] < 0) index[m.F(f, k)] = used++;
  Eigen::MatrixX3d V(used, 3);
  for (int v = 0; v < m.V.rows(); ++v)
    if (index[v] >= 0) V.row(index[v]) = m.V.row(v);
  for (int f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) m.F(f, k) = index[m.F(f, k)];
  m.V = V;
  return m;
}

// The border of a square sheet is four border lines between its four corners; the staircase
// hypotenuse of a triangular sheet turns by 90° at every step, yet at an output spacing of six
// steps it is one straight line: its steps are no corners, the triangle's three corners are.
TEST(Creases, BorderCornersAreSeenAtTheOutputsScale) {
  const TriangleMesh square = sheet_mesh(20, false);
  const CreaseLines lines = detect_creases(square.V, square.F, {}, 0.1);
  EXPECT_EQ(lines.lines.size(), 4u);
  EXPECT_EQ(std::count(lines.border.begin(), lines.border.end(), 1), 4);
  EXPECT_EQ(std::count(lines.corner.begin(), lines.corner.end(), 1), 4);
  for (int l = 0; l < 4; ++l) EXPECT_NEAR(lines.length(square.V, l), 1.0, 1e-12);
  CreaseOptions off;
  off.border_corners = false;
  EXPECT_TRUE(detect_creases(square.V, square.F, off, 0.1).lines.empty());

  const int n = 30;
  const TriangleMesh stairs = sheet_mesh(n, true);
  const CreaseLines fine = detect_creases(stairs.V, stairs.F, {}, 0.0);
  ASSERT_GT(std::count(fine.corner.begin(), fine.corner.end(), 1), n) << "every step is a corner at the edges' scale";
  const CreaseLines coarse = detect_creases(stairs.V, stairs.F, {}, 6.0 / n);
  EXPECT_EQ(std::count(coarse.corner.begin(), coarse.corner.end(), 1), 3);
  EXPECT_EQ(coarse.lines.size(), 3u);
}

// Remeshed, a square sheet keeps its corners exactly (before, the border's relaxation cut each
// corner about half a spacing off) and its border stays on the input's, with the angle targets.
TEST(Creases, ASquareSheetRemeshKeepsItsCorners) {
  const TriangleMesh square = sheet_mesh(40, false);
  RemeshOptions o;
  o.cvt.sites = 300;
  o.creases.border_corners = false;
  const RemeshResult rounded = remesh_cvt(square, o);
  const auto corner_gap = [](const TriangleMesh& m) {
    double worst = 0;
    for (const Eigen::Vector3d c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                    Eigen::Vector3d(1, 1, 0)})
      worst = std::max(worst, (m.V.rowwise() - c.transpose()).rowwise().norm().minCoeff());
    return worst;
  };
  const double spacing = std::sqrt(1.0 / o.cvt.sites);
  ASSERT_GT(corner_gap(rounded.mesh), 0.25 * spacing) << "without the border lines the corners are cut off";
  o.creases.border_corners = true;
  const RemeshResult kept = remesh_cvt(square, o);
  EXPECT_TRUE(kept.creases.border_undone_reason.empty()) << kept.creases.border_undone_reason;
  EXPECT_EQ(kept.creases.border_lines, 4);
  EXPECT_LT(corner_gap(kept.mesh), 1e-9);
  EXPECT_TRUE(kept.checks.ok()) << kept.checks.summary();
  EXPECT_NEAR(kept.mesh.V.rows(), o.cvt.sites, 0.02 * o.cvt.sites);
  EXPECT_GE(kept.quality.min_angle_deg, 30);
  EXPECT_GE(kept.quality.mean_min_angle_deg, 52);
  EXPECT_LT(kept.mesh.V.col(2).cwiseAbs().maxCoeff(), 1e-12) << "the flat sheet stays flat";
  EXPECT_GE(kept.mesh.V.col(0).minCoeff(), -1e-12);
  EXPECT_LE(kept.mesh.V.col(0).maxCoeff(), 1 + 1e-12);
}

}  // namespace
}  // namespace heatcvt
