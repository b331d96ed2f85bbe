#include "heatcvt/remesh.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesh_orientation.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/coverage_repair.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/normalize.h"
#include "heatcvt/parallel.h"
#include "heatcvt/subdivision.h"

namespace heatcvt {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The checks a dual must pass to be a 2-manifold (with the input's boundary): the ones whose
// offending elements name cells (dual vertices) that break the closed-ball property.
const char* const kManifoldChecks[] = {"manifold_edges", "manifold_vertices", "closed", "all_vertices_used"};

// Validation options of the dual against the input's topology.
ValidationOptions dual_checks(const SurfaceDescription& input) {
  ValidationOptions o;
  o.require_closed = input.closed();
  o.expected_genus = input.genus;
  // The loop count, like the genus, only where the input is an edge manifold: where its border
  // pinches at a vertex or an edge has more than two faces, a remesh that is a manifold separates
  // or joins the loops there.
  o.expected_boundary_loops = input.genus >= 0 || input.non_orientable ? input.topology.boundary_loops : -1;
  o.allow_non_orientable = input.non_orientable;
  return o;
}

// Cells of the dual's vertices at non-manifold spots: the endpoints of edges with more than two
// triangles (or border edges of a closed input), vertices whose triangles do not form one fan and
// sites in no triangle. Empty when the dual is a 2-manifold with the input's boundary.
std::vector<int> cells_breaking_closed_ball(const DualMesh& dual, const SurfaceDescription& input) {
  ValidationOptions o = dual_checks(input);
  o.check_self_intersections = false;
  o.expected_genus = -1;
  o.max_listed = static_cast<int>(dual.V.rows());
  std::vector<int> cells;
  if (dual.F.rows() == 0) {  // no Voronoi vertex at all (e.g. every cell a ring around a thin tube)
    for (int s = 0; s < static_cast<int>(dual.V.rows()); ++s) cells.push_back(s);
    return cells;
  }
  const ValidationReport rep = validate_triangle_mesh(dual.V, dual.F, o);
  for (const char* name : kManifoldChecks) {
    const MeshCheck* c = rep.find(name);
    if (!c || c->passed) continue;
    for (const auto& where : c->where) cells.insert(cells.end(), where.begin(), where.end());
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

// For each cell in `cells`, the point of the tessellation (a corner of a refined face of the
// cell) farthest from its site: where a cell that wraps a thin part or is split needs a new site.
// Cells without such a point (no faces, or all within `min_distance` of the site) get none.
std::vector<SurfacePoint> farthest_points_of_cells(const VoronoiDiagram& d, const Eigen::MatrixX3d& site_positions,
                                                   const std::vector<int>& cells, double min_distance) {
  std::vector<int> slot(static_cast<std::size_t>(d.num_cells()), -1);
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (cells[i] >= 0 && cells[i] < d.num_cells()) slot[static_cast<std::size_t>(cells[i])] = static_cast<int>(i);
  std::vector<double> best(cells.size(), min_distance * min_distance);
  std::vector<SurfacePoint> found(cells.size());
  for (Eigen::Index r = 0; r < d.F.rows(); ++r) {
    const int c = d.face_cell[r];
    if (c < 0 || slot[static_cast<std::size_t>(c)] < 0) continue;
    const int i = slot[static_cast<std::size_t>(c)];
    for (int k = 0; k < 3; ++k) {
      const double dist = (d.V.row(d.F(r, k)) - site_positions.row(c)).squaredNorm();
      if (dist <= best[static_cast<std::size_t>(i)]) continue;
      best[static_cast<std::size_t>(i)] = dist;
      found[static_cast<std::size_t>(i)].face = d.face_parent[r];
      found[static_cast<std::size_t>(i)].bary = d.face_bary.row(3 * r + k).transpose();
    }
  }
  found.erase(std::remove_if(found.begin(), found.end(), [](const SurfacePoint& p) { return p.face < 0; }), found.end());
  return found;
}

// The boundary loops of a mesh: the loop of each vertex (boundary_loop_labels(), −1 off the
// border) and the length of each loop.
struct BoundaryLoops {
  Eigen::VectorXi of_vertex;
  std::vector<double> length;
  int shorter_than(double min_length) const {
    return static_cast<int>(std::count_if(length.begin(), length.end(), [&](double l) { return l < min_length; }));
  }
};

BoundaryLoops boundary_loops_of(const TriangleMesh& mesh) {
  BoundaryLoops b;
  b.length.assign(static_cast<std::size_t>(boundary_loop_labels(static_cast<int>(mesh.V.rows()), mesh.F, b.of_vertex)), 0.0);
  for (const auto& [u, v] : boundary_edges(mesh.F))
    b.length[static_cast<std::size_t>(b.of_vertex[u])] += (mesh.V.row(u) - mesh.V.row(v)).norm();
  return b;
}

// Where the cells of d touch the border of `work` (the mesh d tessellates): for every cell and
// every boundary loop it touches (loop labels of boundary_loop_labels()), the point of the loop
// in the cell nearest to the cell's site.
struct LoopContact {
  int cell = -1, loop = -1;
  SurfacePoint point;
  double distance = 0;
};

std::vector<LoopContact> loop_contacts(const VoronoiDiagram& d, const TriangleMesh& work, const Eigen::VectorXi& loop,
                                       const Eigen::MatrixX3d& site_positions) {
  constexpr double kOnEdge = 1e-9;  // a refined corner whose barycentric weight opposite an edge is below this lies on it
  std::set<std::pair<int, int>> border;
  for (const auto& e : boundary_edges(work.F)) border.insert(e);
  std::map<std::pair<int, int>, LoopContact> nearest;  // (cell, loop) -> contact
  for (Eigen::Index r = 0; r < d.F.rows(); ++r) {
    const int c = d.face_cell[r], p = d.face_parent[r];
    if (c < 0) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = work.F(p, k), b = work.F(p, (k + 1) % 3);
      if (loop[a] < 0 || !border.count(std::minmax(a, b))) continue;
      for (int j = 0; j < 3; ++j) {
        const Eigen::Vector3d bary = d.face_bary.row(3 * r + j).transpose();
        if (std::abs(bary[(k + 2) % 3]) > kOnEdge) continue;
        LoopContact t{c, loop[a], SurfacePoint{p, bary}, 0};
        t.distance = (position(work.V, work.F, t.point) - site_positions.row(c).transpose()).norm();
        auto [it, added] = nearest.emplace(std::make_pair(c, t.loop), t);
        if (!added && t.distance < it->second.distance) it->second = t;
      }
    }
  }
  std::vector<LoopContact> out;
  for (const auto& [key, t] : nearest) out.push_back(t);
  return out;  // sorted by cell, then loop
}

// New sites that give every boundary loop of the input at least `min_length` long cells of its
// own, as the closed-ball property asks at the border: the dual keeps a loop only where at least
// three cells touch it, and a cell touching two loops joins them in the dual (or pinches them at
// its site). A cell touching several such loops gets a site on each but the one nearest to its
// site, at the cell's point of that loop nearest to the site (unless that is within
// `min_separation` of the site: a near-duplicate site makes a sliver); a loop touched by fewer
// than three cells gets sites at its vertices farthest from the points where cells touch it.
std::vector<SurfacePoint> sites_for_boundary_loops(const VoronoiDiagram& d, const TriangleMesh& work,
                                                   const BoundaryLoops& loops, double min_length,
                                                   const Eigen::MatrixX3d& site_positions, double min_separation) {
  constexpr int kMinCellsPerLoop = 3;
  const int count = static_cast<int>(loops.length.size());
  std::vector<SurfacePoint> added;
  std::vector<LoopContact> contacts = loop_contacts(d, work, loops.of_vertex, site_positions);
  contacts.erase(std::remove_if(contacts.begin(), contacts.end(),
                                [&](const LoopContact& c) { return loops.length[static_cast<std::size_t>(c.loop)] < min_length; }),
                 contacts.end());
  std::vector<std::vector<Eigen::Vector3d>> touched(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < contacts.size();) {
    std::size_t j = i;
    while (j < contacts.size() && contacts[j].cell == contacts[i].cell) ++j;
    std::size_t keep = i;  // the cell keeps its nearest loop
    for (std::size_t q = i; q < j; ++q)
      if (contacts[q].distance < contacts[keep].distance) keep = q;
    for (std::size_t q = i; q < j; ++q) {
      touched[static_cast<std::size_t>(contacts[q].loop)].push_back(position(work.V, work.F, contacts[q].point));
      if (q != keep && contacts[q].distance >= min_separation) added.push_back(contacts[q].point);
    }
    i = j;
  }
  std::vector<std::vector<int>> loop_vertices(static_cast<std::size_t>(count));
  for (int v = 0; v < static_cast<int>(loops.of_vertex.size()); ++v)
    if (loops.of_vertex[v] >= 0) loop_vertices[static_cast<std::size_t>(loops.of_vertex[v])].push_back(v);
  std::vector<int> face_of(static_cast<std::size_t>(work.V.rows()), -1), corner_of(face_of.size(), -1);
  for (Eigen::Index f = 0; f < work.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) face_of[static_cast<std::size_t>(work.F(f, k))] = static_cast<int>(f), corner_of[static_cast<std::size_t>(work.F(f, k))] = k;
  for (int l = 0; l < count; ++l) {
    if (loops.length[static_cast<std::size_t>(l)] < min_length) continue;
    std::vector<Eigen::Vector3d>& points = touched[static_cast<std::size_t>(l)];
    for (int n = static_cast<int>(points.size()); n < kMinCellsPerLoop; ++n) {
      int far = -1;
      double best = -1;
      for (int v : loop_vertices[static_cast<std::size_t>(l)]) {
        double near = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& q : points) near = std::min(near, (work.V.row(v).transpose() - q).squaredNorm());
        if (near > best) best = near, far = v;
      }
      if (far < 0 || !(best > 0)) break;
      SurfacePoint p{face_of[static_cast<std::size_t>(far)], Eigen::Vector3d::Zero()};
      p.bary[corner_of[static_cast<std::size_t>(far)]] = 1;
      added.push_back(p);
      points.push_back(work.V.row(far).transpose());
    }
  }
  return added;
}

// Whether (V, F) has edges with more than two faces (then no manifold dual exists).
bool has_nonmanifold_edges(const SurfaceDescription& input) { return input.topology.nonmanifold_edges > 0; }

// Site spacing of `sites` sites on the surface of `mesh`.
double site_spacing(const TriangleMesh& mesh, int sites) { return std::sqrt(surface_area(mesh.V, mesh.F) / std::max(1, sites)); }

// The CVT's weights (centroidal_voronoi()): the anisotropic lift's face areas and the adaptive
// sizing's density (empty where not used).
struct CvtWeights {
  Eigen::VectorXd face_metric_area, vertex_density;
};

// Closed-ball repair (RemeshOptions::repair_rounds, loop_repair_rounds): while the dual of out.cvt
// is not a manifold or a boundary loop of the input lacks cells of its own
// (sites_for_boundary_loops()),
// a new site at the farthest point of every cell at a non-manifold spot and on such loops, the sites in no triangle
// (cells enclosed by another cell, which is then an annulus) dropped, and the CVT again from
// these sites with a few surface-Lloyd iterations (as after the CVT's own splits).
void repair_closed_ball(const TriangleMesh& work, const Laplacian& laplacian, const CvtWeights& weights,
                        const RemeshOptions& options, const CvtCallback& progress, RemeshResult& out) {
  const int budget = static_cast<int>(options.max_repair_fraction * options.cvt.sites);
  CvtOptions again = options.cvt;
  again.surface_lloyd_iterations = std::min(again.surface_lloyd_iterations, again.surface_lloyd_split_iterations);
  again.iterations = std::min(again.iterations, options.repair_iterations);
  const double spacing = site_spacing(work, options.cvt.sites);
  // A site added on a loop no nearer than this many spacings to the site of its cell.
  constexpr double kMinSiteSeparation = 0.1;
  const BoundaryLoops loops = out.input.closed() ? BoundaryLoops() : boundary_loops_of(work);
  int ball_rounds = 0, loop_rounds = 0;  // rounds for non-manifold spots, rounds for loops alone
  while (out.repair_sites < budget) {
    const int ns = static_cast<int>(out.cvt.sites.size());
    std::vector<int> bad = cells_breaking_closed_ball(out.cvt.dual, out.input);
    std::vector<SurfacePoint> on_loops;
    if (!out.input.closed())
      on_loops = sites_for_boundary_loops(out.cvt.diagram, work, loops, options.min_loop_spacings * spacing,
                                          out.cvt.positions, kMinSiteSeparation * spacing);
    if (bad.empty() && on_loops.empty()) break;
    // Rounds for the non-manifold spots (and the loops) while they last; then rounds for the loops
    // alone.
    const bool ball_round = !bad.empty() && ball_rounds < options.repair_rounds;
    if (!ball_round) {
      if (on_loops.empty() || loop_rounds >= options.loop_repair_rounds) break;
      bad.clear();
    }
    ++(ball_round ? ball_rounds : loop_rounds);
    // A loop round splits no cell and runs no heat iteration; its surface-Lloyd iterations settle
    // the new sites, except in the last loop round, where they stay where they are put (Lloyd
    // steps can draw them off a loop again).
    CvtOptions round = again;
    if (!ball_round) {
      round.split_nonmanifold_cells = false;
      round.iterations = 0;
      if (loop_rounds == options.loop_repair_rounds) round.surface_lloyd_iterations = 0;
    }
    std::vector<unsigned char> drop(static_cast<std::size_t>(ns), 0);
    if (out.cvt.dual.F.rows() > 0)
      for (int s : out.cvt.dual.unused_sites) drop[static_cast<std::size_t>(s)] = 1;
    bad.erase(std::remove_if(bad.begin(), bad.end(), [&](int s) { return drop[static_cast<std::size_t>(s)] != 0; }),
              bad.end());
    if (static_cast<int>(bad.size()) > budget - out.repair_sites) bad.resize(static_cast<std::size_t>(budget - out.repair_sites));
    std::vector<SurfacePoint> added = farthest_points_of_cells(out.cvt.diagram, out.cvt.positions, bad, 1e-6 * spacing);
    const int room = std::max(0, budget - out.repair_sites - static_cast<int>(added.size()));
    if (static_cast<int>(on_loops.size()) > room) on_loops.resize(static_cast<std::size_t>(room));
    added.insert(added.end(), on_loops.begin(), on_loops.end());
    std::vector<SurfacePoint> start;
    for (int s = 0; s < ns; ++s)
      if (!drop[static_cast<std::size_t>(s)]) start.push_back(out.cvt.sites[static_cast<std::size_t>(s)]);
    const int dropped = ns - static_cast<int>(start.size());
    if (added.empty() && dropped == 0) break;
    start.insert(start.end(), added.begin(), added.end());
    out.cvt = centroidal_voronoi(work.V, work.F, laplacian, round, start, progress, weights.face_metric_area,
                                 weights.vertex_density);
    out.repair_sites += static_cast<int>(added.size());
    out.repair_dropped_sites += dropped;
    ++out.repair_rounds;
  }
}

// The input's vertices that faces use (the samples of its surface).
Eigen::MatrixX3d face_vertices(const TriangleMesh& input) {
  std::vector<char> used(static_cast<std::size_t>(input.V.rows()), 0);
  for (Eigen::Index k = 0; k < input.F.size(); ++k) used[static_cast<std::size_t>(input.F.data()[k])] = 1;
  Eigen::MatrixX3d samples(std::count(used.begin(), used.end(), 1), 3);
  for (Eigen::Index v = 0, r = 0; v < input.V.rows(); ++v)
    if (used[static_cast<std::size_t>(v)]) samples.row(r++) = input.V.row(v);
  return samples;
}

// Diagonal of the bounding box of P (0 for no rows).
double bounding_diagonal(const Eigen::MatrixX3d& P) {
  return P.rows() > 0 ? (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm() : 0.0;
}

// Checks of a result against the input's topology; a mesh without triangles gets the one failed
// check "has_triangles". "spans_input": a remesh lies on the input's surface and spreads its
// vertices over it, so its bounding box has a diagonal of the input's order; a result below
// kMinSpan of it has collapsed (a few sites run together at a very small count).
ValidationReport check_result(const TriangleMesh& result, const SurfaceDescription& input, bool built) {
  constexpr double kMinSpan = 0.1;
  ValidationReport rep;
  if (built && result.F.rows() > 0) {
    rep = validate_triangle_mesh(result.V, result.F, dual_checks(input));
    MeshCheck span;
    span.name = "spans_input";
    const double ratio = input.diagonal > 0 ? bounding_diagonal(face_vertices(result)) / input.diagonal : 1.0;
    span.passed = ratio >= kMinSpan;
    span.detail = span.passed ? "ok"
                              : "the result's bounding box is " + std::to_string(ratio) +
                                    " of the input's: its vertices ran together";
    rep.checks.push_back(span);
    return rep;
  }
  if (built) {
    MeshCheck empty;
    empty.name = "has_triangles";
    empty.detail = "the dual has no triangles (no point where three cells meet)";
    rep.checks.push_back(empty);
  }
  return rep;
}


// Distance from `mesh` to the sample (an input vertex of a face, face_vertices()) farthest from
// it: how well it covers the input.
double farthest_input_vertex(const Eigen::MatrixX3d& samples, const TriangleMesh& mesh) {
  if (mesh.F.rows() == 0) return std::numeric_limits<double>::infinity();
  const std::vector<SurfacePoint> nearest = closest_surface_points(mesh.V, mesh.F, samples);
  double farthest = 0;
  for (Eigen::Index v = 0; v < samples.rows(); ++v)
    farthest = std::max(farthest, (position(mesh.V, mesh.F, nearest[static_cast<std::size_t>(v)]) - samples.row(v).transpose()).norm());
  return farthest;
}

// The share of the area of `input` (each vertex a third of its faces' area) farther than
// `distance` from `mesh`; 1 where `mesh` has no faces.
double uncovered_area_share(const TriangleMesh& input, const TriangleMesh& mesh, double distance) {
  if (mesh.F.rows() == 0) return 1.0;
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(input.V.rows());
  for (Eigen::Index f = 0; f < input.F.rows(); ++f) {
    const Eigen::Vector3d a = input.V.row(input.F(f, 0)), b = input.V.row(input.F(f, 1)), c = input.V.row(input.F(f, 2));
    const double third = (b - a).cross(c - a).norm() / 6.0;
    for (int k = 0; k < 3; ++k) weight(input.F(f, k)) += third;
  }
  const double total = weight.sum();
  if (!(total > 0)) return 0.0;
  const std::vector<SurfacePoint> nearest = closest_surface_points(mesh.V, mesh.F, input.V);
  double uncovered = 0;
  for (Eigen::Index v = 0; v < input.V.rows(); ++v)
    if ((position(mesh.V, mesh.F, nearest[static_cast<std::size_t>(v)]) - input.V.row(v).transpose()).norm() > distance)
      uncovered += weight(v);
  return uncovered / total;
}

// The final check "covers_input" (RemeshOptions::max_uncovered_area_share) added to out.checks,
// the share in out.uncovered_area_share; `input` in the frame of out.mesh. Not for a bare dual
// that was not built.
void add_input_coverage_check(const TriangleMesh& input, const RemeshOptions& options, RemeshResult& out) {
  if (!options.cvt.build_dual) return;
  const double spacing = site_spacing(input, options.cvt.sites);
  out.uncovered_area_share = uncovered_area_share(input, out.mesh, options.covered_spacings * spacing);
  MeshCheck c;
  c.name = "covers_input";
  c.passed = out.uncovered_area_share <= options.max_uncovered_area_share;
  std::ostringstream detail;
  detail.precision(3);
  detail << out.uncovered_area_share * 100 << " % of the input's area is farther than " << options.covered_spacings
         << " site spacings from the result";
  c.detail = c.passed ? "ok" : detail.str();
  out.checks.checks.push_back(c);
}

// The first check that `before` ran and passed and `after` does not pass; null where none.
const MeshCheck* check_lost(const ValidationReport& before, const ValidationReport& after) {
  for (const MeshCheck& c : before.checks) {
    const MeshCheck* now = after.find(c.name);
    if (c.ran && c.passed && !(now && now->ran && now->passed)) return &c;
  }
  return nullptr;
}

// Whether the checks found every edge and vertex manifold.
bool is_manifold(const ValidationReport& r) {
  for (const char* name : {"manifold_edges", "manifold_vertices"}) {
    const MeshCheck* c = r.find(name);
    if (!(c && c->ran && c->passed)) return false;
  }
  return true;
}

// How far the vertex count of `mesh` is off the `sites` asked for, as a fraction of them.
double count_error(const TriangleMesh& mesh, int sites) {
  return std::abs(static_cast<double>(mesh.V.rows()) - sites) / sites;
}

// Which of the targets of mesher.sizing a result meets: its vertex count within count_tolerance
// of the `sites` asked for, φmin ≥ min_angle_deg, φm ≥ mean_angle_deg.
struct TargetsMet {
  bool count = false, min_angle = false, mean_angle = false;
  bool all() const { return count && min_angle && mean_angle; }
  bool covers(const TargetsMet& o) const {
    return (count || !o.count) && (min_angle || !o.min_angle) && (mean_angle || !o.mean_angle);
  }
  bool operator==(const TargetsMet& o) const {
    return count == o.count && min_angle == o.min_angle && mean_angle == o.mean_angle;
  }
};

TargetsMet targets_met(const RemeshResult& r, int sites, const IsotropicRemeshOptions& targets) {
  const TriangleQuality q = triangle_quality(r.mesh.V, r.mesh.F);
  TargetsMet m;
  m.count = count_error(r.mesh, sites) <= targets.count_tolerance;
  m.min_angle = q.min_angle_deg >= targets.min_angle_deg;
  m.mean_angle = q.mean_min_angle_deg >= targets.mean_angle_deg;
  return m;
}

// Whether the dual of a closed input already is what the post-CVT stages aim at: every check
// passed (closed, manifold, the input's genus, no self-intersection), the vertex count within the
// sizing's tolerance of the sites asked for, φmin and φm at the sizing's targets. The stages
// would only move its vertices, and their relaxation rounds off tips. (On an open input they
// also bring the dual's border, inset by about a cell, onto the input's.)
bool dual_meets_targets(const RemeshResult& out, const RemeshOptions& options) {
  if (out.input.topology.boundary_edges > 0 || !out.checks.ok() || out.mesh.F.rows() == 0) return false;
  return targets_met(out, options.cvt.sites, options.mesher.sizing).all();
}

// Why the post-CVT stages' result `post` (its checks `after`) does not replace the dual
// (out.mesh, out.checks), or "" where it does: a manifold result replaces a dual that is none;
// otherwise it must pass every check the dual passed, keep
// the input's topology (components, Euler characteristic) where the dual has it (the stages must
// not open, close or cut the surface), and cover the input as well as a dual that is a manifold
// (RemeshOptions::max_coverage_ratio, max_coverage_spacings).
// `for_coverage` (optional) tells whether the coverage was the reason.
std::string post_cvt_refusal(const Eigen::MatrixX3d& samples, double spacing, const TriangleMesh& post,
                             const ValidationReport& after, const RemeshOptions& options, const RemeshResult& out,
                             bool* for_coverage = nullptr) {
  if (for_coverage) *for_coverage = false;
  // A dual that is no manifold is no alternative to a result that is one, whatever else it passes.
  if (!is_manifold(out.checks) && is_manifold(after)) return "";
  const auto input_topology = [&](const ValidationReport& r) {
    return r.components == out.input.topology.components &&
           r.euler_characteristic == out.input.topology.euler_characteristic();
  };
  if (input_topology(out.checks) && !input_topology(after))
    return "it has " + std::to_string(after.components) + " components and Euler characteristic " +
           std::to_string(after.euler_characteristic) + ", the input " + std::to_string(out.input.topology.components) +
           " and " + std::to_string(out.input.topology.euler_characteristic());
  if (const MeshCheck* lost = check_lost(out.checks, after)) {
    const MeshCheck* now = after.find(lost->name);
    return "it fails " + lost->name + (now ? " (" + now->detail + ")" : std::string()) + ", which the dual passed";
  }
  if (!is_manifold(out.checks)) return "";  // a dual that is no manifold is no alternative
  // Nor is a dual far off the vertex count asked for (sites added for thin parts), where the
  // stages' result has the count and the dual's components and Euler characteristic: its
  // coverage is that of a coarser mesh.
  const bool same_topology = after.components == out.checks.components &&
                             after.euler_characteristic == out.checks.euler_characteristic;
  if (same_topology && count_error(out.mesh, options.cvt.sites) > options.far_count_error &&
      count_error(post, options.cvt.sites) <= options.mesher.sizing.count_tolerance)
    return "";
  const double post_gap = farthest_input_vertex(samples, post), dual_gap = farthest_input_vertex(samples, out.mesh);
  const double absolute = std::max(options.max_coverage_spacings * spacing, dual_gap);
  if (post_gap > options.max_coverage_ratio * dual_gap + options.coverage_slack * spacing || post_gap > absolute) {
    if (for_coverage) *for_coverage = true;
    return "it covers the input less well: an input vertex is " + std::to_string(post_gap / spacing) +
           " site spacings from it, " + std::to_string(dual_gap / spacing) + " from the dual";
  }
  return "";
}

// Coverage repair (mesher/coverage_repair.h) of the post-CVT stages' result `mesh` against the
// input's vertices `samples` (face_vertices()), at the site spacing `spacing`.
void cover_input(const Eigen::MatrixX3d& samples, double spacing, const SurfaceProjector& surface,
                 const RemeshOptions& options, TriangleMesh& mesh, RemeshResult& out) {
  if (options.coverage.rounds <= 0 || mesh.F.rows() == 0) return;
  const auto t = Clock::now();
  WorkingMesh work = working_mesh_of(mesh, surface);
  out.coverage = repair_coverage(work, surface, samples, spacing, options.coverage);
  if (out.coverage.moves > 0) mesh = compact_mesh(work);
  out.stage_seconds.emplace_back("coverage repair", seconds_since(t));
}

// Where the result `mesh` of cover_input() is refused for its coverage (a tip still cut off):
// the repair again on the stages' result `unrepaired` with each moved vertex's ring dragged along
// (RemeshOptions::coverage_retry_ring_drag). Where that result is not refused and its φm is at
// mesher.sizing's target and at most 1° below that of `mesh` (the cloud path's rule for the
// same repair), it replaces `mesh` and `checks` and true is returned; otherwise out.coverage is
// that of the first repair again. The time of its checks is added to `check_seconds`.
bool retry_with_ring_drag(const Eigen::MatrixX3d& samples, double spacing, const SurfaceProjector& surface,
                          const RemeshOptions& options, const TriangleMesh& unrepaired, TriangleMesh& mesh,
                          ValidationReport& checks, RemeshResult& out, double& check_seconds) {
  if (!(options.coverage_retry_ring_drag > 0)) return false;
  RemeshOptions dragged = options;
  dragged.coverage.ring_drag = options.coverage_retry_ring_drag;
  TriangleMesh retry = unrepaired;
  const CoverageRepairStats first = out.coverage;
  cover_input(samples, spacing, surface, dragged, retry, out);
  const auto t = Clock::now();
  ValidationReport retry_checks = check_result(retry, out.input, true);
  // The dragged rings must also keep φm at the target and within 1° of the first repair's.
  const double target = options.mesher.sizing.mean_angle_deg;
  const double phi_m = triangle_quality(retry.V, retry.F).mean_min_angle_deg;
  const bool kept = phi_m >= target && phi_m >= triangle_quality(mesh.V, mesh.F).mean_min_angle_deg - 1.0 &&
                    post_cvt_refusal(samples, spacing, retry, retry_checks, options, out).empty();
  check_seconds += seconds_since(t);
  if (!kept) {
    out.coverage = first;
    return false;
  }
  mesh = std::move(retry);
  checks = std::move(retry_checks);
  out.coverage_ring_dragged = true;
  return true;
}

// The input as the post-CVT stages and the crease recovery read it: the mesh, its projector
// (closest points, normals, border) and the vertices of its faces (face_vertices(), the samples
// of the coverage checks). The last two are built on first use, once per remesh, and shared by
// every run of the stages, also by runs on other threads (they are read only).
class InputSurface {
 public:
  explicit InputSurface(const TriangleMesh& m) : mesh(m) {}
  const TriangleMesh& mesh;
  const MeshSurfaceProjector& projector() const {
    build();
    return *projector_;
  }
  const Eigen::MatrixX3d& samples() const {
    build();
    return samples_;
  }

 private:
  void build() const {
    std::call_once(built_, [this] {
      projector_ = std::make_unique<MeshSurfaceProjector>(mesh.V, mesh.F);
      samples_ = face_vertices(mesh);
    });
  }
  mutable std::once_flag built_;
  mutable std::unique_ptr<MeshSurfaceProjector> projector_;
  mutable Eigen::MatrixX3d samples_;
};

// Results of run_post_cvt_stages() as a run without the coverage repair's retry with dragged rings
// (RemeshOptions::coverage_retry_ring_drag = 0) leaves them, kept for the runs of remesh_cvt()'s
// crease retry, which differ from the first runs only by that retry: the same dual, the same
// tips held (mesher tips' min_defect_deg) and the same CVT target give the same result.
// Read and written by the runs on every thread. The runs leave the CVT's result as it was, so it
// is not kept: what find() gives has an empty `cvt`, which is before.cvt.
class StageRunMemo {
 public:
  void record(const RemeshResult& before, const RemeshOptions& options, RemeshResult after) {
    after.cvt = CvtResult{};
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!find_locked(before, options))
      entries_.push_back({before.cvt.dual.V, before.cvt.dual.F, key(options), std::move(after)});
  }
  // The recorded result of a run from `before` with `options` (its `cvt` empty); false where
  // there is none.
  bool find(const RemeshResult& before, const RemeshOptions& options, RemeshResult& after) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    const Entry* e = find_locked(before, options);
    if (!e) return false;
    after = e->after;
    return true;
  }

 private:
  using Key = std::pair<double, double>;  // tips held, CVT's target φmin
  struct Entry {
    Eigen::MatrixX3d V;
    Eigen::MatrixX3i F;
    Key key;
    RemeshResult after;
  };
  static Key key(const RemeshOptions& o) { return {o.mesher.polish.tips.min_defect_deg, o.cvt.target_phi_min_deg}; }
  const Entry* find_locked(const RemeshResult& before, const RemeshOptions& options) const {
    for (const Entry& e : entries_)
      if (e.key == key(options) && e.V.rows() == before.cvt.dual.V.rows() && e.F.rows() == before.cvt.dual.F.rows() &&
          e.V == before.cvt.dual.V && e.F == before.cvt.dual.F)
        return &e;
    return nullptr;
  }
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
};

// The shared post-CVT stages on out.cvt.dual with the input mesh as the projector (the refined
// mesh is the same surface). Their result replaces out.mesh unless it fails a check that the dual
// passed (the stages, made for clouds, may open or fill a thin handle): then the dual is kept and
// out.post_cvt_kept is false. Returns out.post_cvt_kept. With `memo`, a run without the retry
// with dragged rings that was run before is taken from it, and every run records its result
// without that retry there.
bool run_post_cvt_stages(const InputSurface& in, const RemeshOptions& options, RemeshResult& out,
                         StageRunMemo* memo = nullptr) {
  if (memo && !(options.coverage_retry_ring_drag > 0)) {
    RemeshResult found;
    if (memo->find(out, options, found)) {
      found.cvt = std::move(out.cvt);
      found.stage_seconds = std::move(out.stage_seconds);
      found.stage_seconds.emplace_back("post-CVT stages, the same run as before", 0.0);
      out = std::move(found);
      return out.post_cvt_kept;
    }
  }
  const TriangleMesh& input = in.mesh;
  const MeshSurfaceProjector& surface = in.projector();
  SurfaceMesherOptions mo = options.mesher;
  mo.threads = options.cvt.threads;
  if (mo.sizing.target_vertices == 0) mo.sizing.target_vertices = options.cvt.sites;
  // Loops below the resolution asked for (RemeshOptions::min_loop_spacings) may close: each one
  // closed adds one to the Euler characteristic.
  const int short_loops = boundary_loops_of(input).shorter_than(options.min_loop_spacings * site_spacing(input, options.cvt.sites));
  mo.keep_topology = {out.input.topology.components, out.input.topology.boundary_loops - short_loops,
                      out.input.topology.euler_characteristic() + short_loops};
  DualSurfaceResult post;
  try {
    post = mesh_dual_surface(out.cvt.dual.V, out.cvt.dual.F, surface, mo);
    throw_if_cancelled(mo.cancelled);
  } catch (const Error& e) {  // nothing extracted (a dual of very few sites): the dual stays
    out.post_cvt_kept = false;
    out.post_cvt_refusal = std::string("nothing extracted: ") + e.what();
    return false;
  }
  out.mesher = std::move(post.stats);
  // the mesher validates its result as an open surface; the checks below use the input's topology
  for (const auto& stage : out.mesher.stage_seconds)
    if (stage.first != "validate") out.stage_seconds.push_back(stage);
  const Eigen::MatrixX3d& samples = in.samples();
  const double spacing = site_spacing(input, options.cvt.sites);
  const TriangleMesh unrepaired = options.coverage_retry_ring_drag > 0 ? post.mesh : TriangleMesh{};
  cover_input(samples, spacing, surface, options, post.mesh, out);
  throw_if_cancelled(mo.cancelled);
  const auto t = Clock::now();
  ValidationReport checks = check_result(post.mesh, out.input, true);
  bool for_coverage = false;
  std::string refusal = post_cvt_refusal(samples, spacing, post.mesh, checks, options, out, &for_coverage);
  double check_seconds = seconds_since(t);
  // The result kept or refused: out.mesh and out.checks are the stages' where it is kept.
  const auto finish = [](RemeshResult& r, const std::string& refused, TriangleMesh&& mesh, ValidationReport&& report) {
    r.post_cvt_kept = refused.empty();
    if (!r.post_cvt_kept) r.post_cvt_refusal = "result not kept: " + refused;
    if (r.post_cvt_kept) {
      r.mesh = std::move(mesh);
      r.checks = std::move(report);
    }
  };
  if (memo) {
    CvtResult cvt = std::move(out.cvt);  // not recorded (StageRunMemo): not copied
    RemeshResult without_retry = out;
    out.cvt = std::move(cvt);
    finish(without_retry, refusal, TriangleMesh(post.mesh), ValidationReport(checks));
    memo->record(out, options, std::move(without_retry));
  }
  if (for_coverage && retry_with_ring_drag(samples, spacing, surface, options, unrepaired, post.mesh, checks, out,
                                            check_seconds))
    refusal.clear();
  finish(out, refusal, std::move(post.mesh), std::move(checks));
  out.stage_seconds.emplace_back("post-CVT checks", check_seconds);
  return out.post_cvt_kept;
}

// Sharp creases of the input kept as lines of out.mesh (mesher/creases.h). The result replaces
// out.mesh only where it fails no check that out.mesh passed.
void keep_creases(const InputSurface& in, const RemeshOptions& options, RemeshResult& out) {
  const TriangleMesh& input = in.mesh;
  if (!options.creases.enabled || out.mesh.F.rows() == 0 || out.input.non_orientable) return;
  const CreaseLines lines = detect_creases(input.V, input.F, options.creases, site_spacing(input, options.cvt.sites));
  if (lines.lines.empty()) return;
  const auto t = Clock::now();
  const MeshSurfaceProjector& surface = in.projector();
  WorkingMesh work = working_mesh_of(out.mesh, surface);
  CreaseOptions co = options.creases;
  co.threads = options.cvt.threads;
  out.creases = recover_creases(work, surface, input.V, lines, co);
  if (!out.creases.undone) {
    TriangleMesh result = compact_mesh(work);
    ValidationReport checks = check_result(result, out.input, true);
    // Snapping a tip's vertex onto a short crease near it would cut the tip off.
    std::string refusal;
    const Eigen::MatrixX3d& samples = in.samples();
    if (farthest_input_vertex(samples, result) > options.max_crease_gap_growth * farthest_input_vertex(samples, out.mesh))
      refusal = "an input vertex would be farther from the output";
    if (const MeshCheck* lost = check_lost(out.checks, checks)) refusal = "it would fail " + lost->name;
    if (refusal.empty()) {
      out.mesh = std::move(result);
      out.checks = std::move(checks);
    } else {
      out.creases.undone = true;
      out.creases.undone_reason = refusal;
    }
  }
  out.stage_seconds.emplace_back("creases", seconds_since(t));
}

}  // namespace

std::string SurfaceDescription::genus_text() const {
  if (genus >= 0) return "genus " + std::to_string(genus);
  if (non_orientable) return "non-orientable, Euler characteristic " + std::to_string(topology.euler_characteristic());
  return "genus undefined (not a manifold)";
}

SurfaceDescription describe_surface(const TriangleMesh& mesh) {
  SurfaceDescription d;
  const int nv = static_cast<int>(mesh.V.rows());
  d.topology = mesh_topology(mesh.F, nv);
  d.genus = mesh_genus(mesh.F, nv);
  d.diagonal = bounding_diagonal(face_vertices(mesh));
  if (d.topology.inconsistent_edges > 0 && d.topology.nonmanifold_edges == 0) {
    ValidationOptions o;
    o.check_self_intersections = false;
    o.allow_non_orientable = true;
    d.non_orientable = validate_triangle_mesh(mesh.V, mesh.F, o).orientable == 0;
  }
  return d;
}

namespace {

// The CVT of options.cvt from `start` (none: generated sites), its closed-ball repair, and its
// dual with the checks against the input's topology as out.mesh / out.checks.
void run_cvt(const TriangleMesh& work, const Laplacian& laplacian, const CvtWeights& weights,
             const RemeshOptions& options, const std::vector<SurfacePoint>& start, const CvtCallback& progress,
             RemeshResult& out) {
  auto t = Clock::now();
  out.cvt = centroidal_voronoi(work.V, work.F, laplacian, options.cvt, start, progress, weights.face_metric_area,
                               weights.vertex_density);
  out.stage_seconds.emplace_back("cvt", seconds_since(t));
  t = Clock::now();
  if (options.cvt.build_dual && !has_nonmanifold_edges(out.input)) repair_closed_ball(work, laplacian, weights, options, progress, out);
  out.stage_seconds.emplace_back("repair", seconds_since(t));
  t = Clock::now();
  out.mesh.V = out.cvt.dual.V;
  out.mesh.F = out.cvt.dual.F;
  out.checks = check_result(out.mesh, out.input, options.cvt.build_dual);
  out.stage_seconds.emplace_back("checks", seconds_since(t));
}

// Whether the result `after` is better than `before` (both of `sites` sites asked for): it passes
// every check that `before` passed and meets every target (targets_met()) that `before` meets;
// then it is better where it meets one more, or the same ones with a larger φmin.
bool improves_on(const RemeshResult& after, const RemeshResult& before, int sites, const IsotropicRemeshOptions& targets) {
  if (check_lost(before.checks, after.checks)) return false;
  const TargetsMet a = targets_met(after, sites, targets), b = targets_met(before, sites, targets);
  if (!a.covers(b)) return false;
  if (!(a == b)) return true;
  return triangle_quality(after.mesh.V, after.mesh.F).min_angle_deg >
         triangle_quality(before.mesh.V, before.mesh.F).min_angle_deg;
}

// A run of the post-CVT stages on `dual` (the state before the stages) with the vertices whose
// angle defect exceeds `defect_deg` held (mesher/tips.h): its result, with only its own stage
// times, and whether the stages' result was kept. `cancelled` (optional) may stop it, as may the
// caller's options.mesher.cancelled (SurfaceMesherOptions::cancelled).
struct TipsHeldRun {
  RemeshResult result;
  bool kept = false;
};

TipsHeldRun run_with_tips_held(const InputSurface& input, const RemeshOptions& options, double defect_deg,
                               const RemeshResult& dual, StageRunMemo* memo,
                               const CancelQuery& cancelled = {}) {
  RemeshOptions with_tips = options;
  if (cancelled)
    with_tips.mesher.cancelled = [caller = options.mesher.cancelled, cancelled] {
      return cancelled() || (caller && caller());
    };
  with_tips.mesher.polish.tips.min_defect_deg = defect_deg;
  with_tips.mesher.sizing.tips.min_defect_deg = defect_deg;
  TipsHeldRun run{dual, false};
  run.result.stage_seconds.clear();
  run.kept = run_post_cvt_stages(input, with_tips, run.result, memo);
  return run;
}

// The result of run_with_tips_held() replaces `out` where it is kept, improves on it
// (improves_on()) and reaches every input vertex within RemeshOptions::max_tip_run_gap site
// spacings. Its stage times are added to out's either way. Returns whether it replaced `out`.
bool replace_with_tips_held(const InputSurface& input, const RemeshOptions& options, double defect_deg,
                            TipsHeldRun&& held, RemeshResult& out) {
  std::vector<std::pair<std::string, double>> times = std::move(out.stage_seconds);
  times.insert(times.end(), held.result.stage_seconds.begin(), held.result.stage_seconds.end());
  const double spacing = site_spacing(input.mesh, options.cvt.sites);
  const bool replaces = held.kept && improves_on(held.result, out, options.cvt.sites, options.mesher.sizing) &&
                        farthest_input_vertex(input.samples(), held.result.mesh) <= options.max_tip_run_gap * spacing;
  if (replaces) {
    out = std::move(held.result);
    out.tips_held_deg = defect_deg;
  }
  out.stage_seconds = std::move(times);
  return replaces;
}

// The runs with tips held of run_stages() (run_with_tips_held(), one per defect in order) on a
// thread of their own, started before the first run of the stages: they depend only on the dual,
// not on the first result; whether they are used does. Once the object is destroyed, a run not yet
// started is skipped and the one under way stops after its current stage.
class TipsHeldAhead {
 public:
  TipsHeldAhead(const InputSurface& input, const RemeshOptions& options, const std::vector<double>& defects,
                const RemeshResult& dual, StageRunMemo* memo)
      : promised_(defects.size()) {
    for (std::promise<TipsHeldRun>& p : promised_) results_.push_back(p.get_future());
    thread_ = std::thread([&input, &options, defects, &dual, memo, this] {
      for (std::size_t i = 0; i < defects.size() && !stop_; ++i) {
        try {
          promised_[i].set_value(run_with_tips_held(input, options, defects[i], dual, memo, [this] { return stop_.load(); }));
        } catch (...) {
          promised_[i].set_exception(std::current_exception());
        }
      }
    });
  }
  TipsHeldAhead(const TipsHeldAhead&) = delete;
  TipsHeldAhead& operator=(const TipsHeldAhead&) = delete;
  ~TipsHeldAhead() {
    stop_ = true;
    thread_.join();
  }
  // The run of the i-th defect, once it is done.
  TipsHeldRun get(std::size_t i) { return results_[i].get(); }

 private:
  std::vector<std::promise<TipsHeldRun>> promised_;
  std::vector<std::future<TipsHeldRun>> results_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The post-CVT stages (run_post_cvt_stages()); where their result is refused or misses a target,
// once more on the same dual with the tips of thin parts held (RemeshOptions::tip_defect_deg),
// and where that result does not replace it or still misses a target, once more with the tips
// of a lower defect held (RemeshOptions::tip_defect_retry_deg): replace_with_tips_held().
// With more than one thread (RemeshOptions::cvt.threads) the runs with tips held go ahead beside
// the first run (TipsHeldAhead), whose stages are mostly serial; the same results are used in the
// same order, so the output does not depend on the thread count. Every run goes through `memo`
// (run_post_cvt_stages()). Returns whether a result of the stages is the output.
bool run_stages(const InputSurface& input, const RemeshOptions& options, RemeshResult& out, StageRunMemo* memo) {
  const RemeshResult dual = out;  // before the stages
  std::vector<double> defects;
  for (const double defect : {options.tip_defect_deg, options.tip_defect_retry_deg}) {
    if (!(defect > 0)) break;
    defects.push_back(defect);
  }
  std::unique_ptr<TipsHeldAhead> ahead;
  if (!defects.empty() && resolve_threads(options.cvt.threads) > 1) {
    try {
      ahead = std::make_unique<TipsHeldAhead>(input, options, defects, dual, memo);
    } catch (const std::system_error&) {  // no thread to be had: the runs one after the other
      ahead.reset();
    }
  }
  bool kept = run_post_cvt_stages(input, options, out, memo);
  for (std::size_t i = 0; i < defects.size(); ++i) {
    if (kept && targets_met(out, options.cvt.sites, options.mesher.sizing).all()) break;
    TipsHeldRun held = ahead ? ahead->get(i) : run_with_tips_held(input, options, defects[i], dual, memo);
    if (replace_with_tips_held(input, options, defects[i], std::move(held), out)) kept = true;
  }
  return kept;
}

// Where the result fails its no_self_intersections check, whether the input crosses itself too:
// out.input_self_intersections gets the input's intersecting face pairs and the check's detail
// names them, so that the report says why no valid remesh was written.
void explain_self_intersections(const TriangleMesh& input, RemeshResult& out) {
  MeshCheck* check = nullptr;
  for (MeshCheck& c : out.checks.checks)
    if (c.name == "no_self_intersections" && c.ran && !c.passed) check = &c;
  if (!check) return;
  ValidationOptions o = dual_checks(out.input);
  o.require_closed = false;
  o.expected_genus = -1;
  const ValidationReport rep = validate_triangle_mesh(input.V, input.F, o);
  out.input_self_intersections = rep.self_intersecting_pairs;
  if (out.input_self_intersections > 0)
    check->detail += "; the input itself has " + std::to_string(out.input_self_intersections) +
                     " intersecting face pairs, which a remesh close to it cannot avoid";
}

// Where the result fails its boundary_loops check and loops of the input are shorter than
// RemeshOptions::min_loop_spacings site spacings, the check's detail says how many: holes below
// the resolution asked for, which more sites keep.
void explain_short_loops(const TriangleMesh& input, const RemeshOptions& options, RemeshResult& out) {
  MeshCheck* check = nullptr;
  for (MeshCheck& c : out.checks.checks)
    if (c.name == "boundary_loops" && c.ran && !c.passed) check = &c;
  if (!check) return;
  const double min_length = options.min_loop_spacings * site_spacing(input, options.cvt.sites);
  const int short_loops = boundary_loops_of(input).shorter_than(min_length);
  if (short_loops > 0)
    check->detail += "; " + std::to_string(short_loops) + " of the input's loops are shorter than " +
                     std::to_string(options.min_loop_spacings) +
                     " site spacings (holes below the resolution asked for: more sites keep them)";
}

// Crease lines of the input that the recovery did not keep: left out because their snap made
// faces cross or faces next to them fell below the smallest angle, or all of them where it was
// undone.
int crease_lines_missed(const CreaseStats& c) {
  return c.skipped_lines + c.dropped_crease_lines + (c.undone ? c.lines : 0);
}

// The adaptive sizing of the input (RemeshOptions::adaptive, on its own vertices and normals):
// the CVT's density on the vertices of its refinement `work` in `weights`, the stages' sizing
// field in `options`, the ratio of the sizes in out.size_ratio.
void adapt_sizing(const TriangleMesh& input, const TriangleMesh& work, RemeshOptions& options, CvtWeights& weights,
                  RemeshResult& out) {
  if (!options.adaptive.enabled()) return;
  const auto t = Clock::now();
  const SurfaceSizing sizing = surface_sizing(input.V, input.F, vertex_normals(input.V, input.F), options.cvt.sites,
                                              options.adaptive, options.cvt.threads);
  weights.vertex_density = sizing.density_at(work.V);
  options.mesher.sizing.relative_size = sizing.field;
  out.size_ratio = sizing.ratio;
  out.stage_seconds.emplace_back("sizing", seconds_since(t));
}

// What the stages and a fallback CVT run on (cvt_of_input()): the input, its refinement
// for the CVT, the Laplacian and the weights, the options with the adaptive sizing in them.
struct CvtInput {
  const TriangleMesh& mesh;
  TriangleMesh refined;
  bool is_refined = false;
  Laplacian laplacian;
  CvtWeights weights;
  RemeshOptions options;

  const TriangleMesh& work() const { return is_refined ? refined : mesh; }
};

// Faces of a mesh whose area is below 1e-12 of the square of their longest edge: no heat flows
// through them (their cotan weights are meaningless).
int degenerate_face_count(const TriangleMesh& m) {
  int count = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    count += (b - a).cross(c - a).norm() <= 2e-12 * longest2;
  }
  return count;
}

// The share of the mesh's area in faces with an angle below `angle_deg`.
double needle_area_share(const TriangleMesh& m, double angle_deg) {
  const double limit = angle_deg * 3.14159265358979323846 / 180;
  const Eigen::VectorXd area = face_areas(m.V, m.F);
  double needles = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    if (triangle_min_angle(m.V.row(m.F(f, 0)).transpose(), m.V.row(m.F(f, 1)).transpose(), m.V.row(m.F(f, 2)).transpose()) < limit)
      needles += area[f];
  const double total = area.sum();
  return total > 0 ? needles / total : 0;
}

// Enough resolution under every cell, the surface and its topology kept. An oriented edge
// manifold with needles (RemeshOptions::needle_area_share: a CAD mesh's fans and strips) is
// refined by refine_surface(), which reshapes them, at any vertex count; other inputs by midpoint
// subdivisions while they have too few vertices per site (the shapes of their triangles kept).
// Where the splits and flips would leave more degenerate faces than the input has (a guard: they
// should leave none), the midpoint subdivisions are used instead.
void refine_for_cvt(CvtInput& in, RemeshResult& out) {
  const RemeshOptions& options = in.options;
  const double wanted = options.min_vertices_per_site * options.cvt.sites;
  const bool oriented_manifold = out.input.topology.nonmanifold_edges == 0 && out.input.topology.inconsistent_edges == 0;
  if (options.refinement_method == RemeshOptions::Refinement::splits_and_flips && oriented_manifold &&
      options.min_vertices_per_site > 0 && options.max_refinement_levels > 0 &&
      needle_area_share(in.mesh, options.needle_angle_deg) > options.needle_area_share) {
    SurfaceRefinementOptions o = options.refinement;
    o.target_vertices = std::min(wanted, static_cast<double>(options.max_refined_vertices));
    SurfaceRefinement r = refine_surface(in.mesh, o);
    if (r.splits + r.flips == 0) return;
    if (degenerate_face_count(r.mesh) <= degenerate_face_count(in.mesh)) {
      out.refinement_splits = r.splits;
      out.refinement_flips = r.flips;
      in.refined = std::move(r.mesh), in.is_refined = true;
      return;
    }
  }
  // A midpoint subdivision makes about 4 times the vertices; none goes beyond the budget.
  while (options.min_vertices_per_site > 0 && out.refinement_levels < options.max_refinement_levels &&
         static_cast<double>(in.work().V.rows()) < wanted &&
         4.0 * static_cast<double>(in.work().V.rows()) <= options.max_refined_vertices) {
    in.refined = midpoint_subdivide(in.work());
    in.is_refined = true;
    ++out.refinement_levels;
  }
}

// The first part of remesh_cvt() on a mesh already in its unit frame: the input described and
// refined where it has too few vertices per site, its Laplacian, the adaptive sizing, and the CVT
// with its closed-ball repair (run_cvt()): `out` holds the dual, `in` what the rest runs on.
void cvt_of_input(CvtInput& in, const CvtCallback& progress, RemeshResult& out) {
  RemeshOptions& options = in.options;
  const int sites = options.cvt.sites;
  if (sites < 1) throw InvalidInputError("remesh_cvt: the number of sites must be >= 1, got " + std::to_string(sites));
  if (!(options.min_vertices_per_site >= 0) || !std::isfinite(options.min_vertices_per_site))
    throw InvalidInputError("remesh_cvt: min_vertices_per_site must be a number >= 0");
  if (!(options.covered_spacings > 0) || !(options.max_uncovered_area_share >= 0 && options.max_uncovered_area_share <= 1))
    throw InvalidInputError("remesh_cvt: covered_spacings must be > 0 and max_uncovered_area_share in [0, 1]");
  if (options.max_refined_vertices < 0)
    throw InvalidInputError("remesh_cvt: max_refined_vertices must be >= 0, got " + std::to_string(options.max_refined_vertices));
  if (options.max_refinement_levels < 0 || options.repair_rounds < 0 || options.repair_iterations < 0 ||
      !(options.max_repair_fraction >= 0))
    throw InvalidInputError(
        "remesh_cvt: max_refinement_levels, repair_rounds, repair_iterations and max_repair_fraction must be >= 0");
  auto t = Clock::now();
  out.input = describe_surface(in.mesh);

  refine_for_cvt(in, out);
  const TriangleMesh& work = in.work();
  out.cvt_vertices = static_cast<int>(work.V.rows());
  if (sites > out.cvt_vertices)
    throw InvalidInputError("remesh_cvt: " + std::to_string(sites) + " sites exceed the " +
                            std::to_string(out.cvt_vertices) + " vertices of the input" +
                            (out.refinement_levels ? " subdivided " + std::to_string(out.refinement_levels) +
                                                         " times (RemeshOptions::max_refinement_levels)"
                                                   : std::string()) +
                            "; ask for fewer sites or give a finer input");
  out.stage_seconds.emplace_back("refine", seconds_since(t));

  t = Clock::now();
  in.laplacian = options.anisotropy > 0
                     ? anisotropic_laplacian(work.V, work.F, options.anisotropy, &in.weights.face_metric_area)
                     : cotan_laplacian(work.V, work.F);
  out.degenerate_faces = static_cast<int>(in.laplacian.degenerate_faces.size());
  out.stage_seconds.emplace_back("laplacian", seconds_since(t));
  adapt_sizing(in.mesh, work, options, in.weights, out);

  run_cvt(work, in.laplacian, in.weights, options, {}, progress, out);
}

// The rest of remesh_cvt() after cvt_of_input(), with `options` (in.options, or a variant of it)
// for the stages: the post-CVT stages on the dual in `out` (and, where their result is refused,
// heat iterations and the stages again), the creases, the explanations of failed checks and the
// figures. The stages read the input through `surface`; their runs are recorded in, and where run
// before taken from, `memo`.
void stages_of_input(const CvtInput& in, const InputSurface& surface, StageRunMemo* memo, const RemeshOptions& options,
                     const CvtCallback& progress, RemeshResult& out) {
  const TriangleMesh& mesh = in.mesh;
  const int sites = options.cvt.sites;
  // The stages orient every closed piece outward: not for a non-orientable input.
  if (options.post_cvt_stages && options.cvt.build_dual && out.mesh.F.rows() > 0 && !out.input.non_orientable) {
    if (dual_meets_targets(out, options)) {
      out.post_cvt_refusal = "not run: the dual of the closed input passes every check and meets the targets";
    } else if (!run_stages(surface, options, out, memo) && options.fallback_phi_min_deg > options.cvt.target_phi_min_deg) {
      // Their result refused: the dual is the output, so heat iterations until its own φmin
      // reaches the fallback target, then the stages again on the new dual; the second result
      // replaces the first where it is better (improves_on()).
      RemeshOptions again = options;
      again.cvt.target_phi_min_deg = options.fallback_phi_min_deg;
      RemeshResult first = out;
      run_cvt(in.work(), in.laplacian, in.weights, again, first.cvt.sites, progress, out);
      if (dual_meets_targets(out, again))
        out.post_cvt_refusal = "not run again: after heat iterations the dual passes every check and meets the targets";
      else if (out.mesh.F.rows() > 0)
        run_stages(surface, again, out, memo);
      if (!improves_on(out, first, sites, options.mesher.sizing)) {
        first.stage_seconds = std::move(out.stage_seconds);
        out = std::move(first);
      }
    }
  }
  if (options.post_cvt_stages && options.cvt.build_dual && !out.post_cvt_kept && out.post_cvt_refusal.empty())
    out.post_cvt_refusal = out.input.non_orientable ? "not run: the input is not orientable (the stages orient every piece)"
                                                    : "not run: the dual has no triangle";
  if (options.cvt.build_dual && options.post_cvt_stages) keep_creases(surface, options, out);
  explain_self_intersections(mesh, out);
  explain_short_loops(mesh, options, out);
  out.quality = triangle_quality(out.mesh.V, out.mesh.F);
  out.iterations = static_cast<int>(out.cvt.iterations.size());
  out.converged = out.cvt.converged;
  out.sites = out.cvt.sites;
  if (out.refinement_splits + out.refinement_flips > 0) {
    // The refined mesh's faces lie in the input's surface: its closest points are the same points.
    Eigen::MatrixX3d at(static_cast<Eigen::Index>(out.sites.size()), 3);
    for (std::size_t i = 0; i < out.sites.size(); ++i) at.row(static_cast<Eigen::Index>(i)) = position(in.work().V, in.work().F, out.sites[i]).transpose();
    if (at.rows() > 0) out.sites = closest_surface_points(mesh.V, mesh.F, at);
  }
  for (SurfacePoint& p : out.sites)
    for (int level = 0; level < out.refinement_levels; ++level) p = subdivision_parent(p);
}

}  // namespace

RemeshResult remesh_cvt(const TriangleMesh& mesh, const RemeshOptions& options, const CvtCallback& progress) {
  validate_mesh(mesh.V, mesh.F, "mesh");
  // Computed in the unit bounding-box frame (normalize.h), so that the result does not depend on
  // the unit of length; positions are returned in the input's coordinates.
  TriangleMesh unit = mesh;
  // Faces written with mixed orientations (exported CAD and STL meshes) would give the dual
  // triangles of both orientations: they are turned to agree first.
  const int reoriented = std::max(0, orient_faces_consistently(unit.F));
  const NormalizationFrame frame = normalize_positions(unit.V);
  CvtInput in{unit, {}, false, {}, {}, options};
  RemeshResult dual;
  cvt_of_input(in, progress, dual);
  dual.reoriented_faces = reoriented;
  RemeshResult out = dual;
  const InputSurface surface(unit);
  StageRunMemo memo;  // the retry below repeats runs of the first stages
  stages_of_input(in, surface, &memo, in.options, progress, out);
  // The coverage repair's retry with dragged rings and the run with the tips of a lower defect
  // held leave the crease recovery another start: where it then misses crease lines, the stages
  // without those retries (on the same CVT) are taken if they miss fewer, pass every check and
  // meet every target (count, φmin, φm) that the first result passes and meets.
  const bool retried =
      out.coverage_ring_dragged || (out.tips_held_deg > 0 && out.tips_held_deg == options.tip_defect_retry_deg);
  if (retried && crease_lines_missed(out.creases) > 0) {
    RemeshOptions alone = in.options;  // with the adaptive sizing's field, where there is one
    alone.coverage_retry_ring_drag = 0;
    alone.tip_defect_retry_deg = 0;
    const std::size_t cvt_stages = dual.stage_seconds.size();
    RemeshResult again = std::move(dual);
    const auto t = Clock::now();
    stages_of_input(in, surface, &memo, alone, progress, again);
    const IsotropicRemeshOptions& targets = options.mesher.sizing;
    if (crease_lines_missed(again.creases) < crease_lines_missed(out.creases) && !check_lost(out.checks, again.checks) &&
        targets_met(again, options.cvt.sites, targets).covers(targets_met(out, options.cvt.sites, targets))) {
      // The report times every stage run: the first stages', then the kept ones'.
      std::vector<std::pair<std::string, double>> times = std::move(out.stage_seconds);
      times.insert(times.end(), again.stage_seconds.begin() + static_cast<std::ptrdiff_t>(cvt_stages),
                   again.stage_seconds.end());
      out = std::move(again);
      out.stage_seconds = std::move(times);
    } else {
      out.stage_seconds.emplace_back("stages without the retries, not kept", seconds_since(t));
    }
  }
  add_input_coverage_check(unit, options, out);
  for (Eigen::MatrixX3d* V : {&out.mesh.V, &out.cvt.positions, &out.cvt.diagram.V, &out.cvt.dual.V})
    if (V->rows() > 0) restore_frame(*V, frame);
  return out;
}

}  // namespace heatcvt
