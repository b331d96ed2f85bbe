// Sharp creases kept as feature lines: detection on the input, recovery on the output.
#include "heatcvt/mesher/creases.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/edge_flips.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/tangential_relaxation.h"

namespace heatcvt {
namespace {

constexpr double kDegree = M_PI / 180.0;

// The feature edges of (V, F) as adjacency lists: `crease[v]` the vertices v shares a crease
// edge with (two faces whose normals differ by more than min_dihedral), `border[v]` the ones it
// shares a boundary edge with (one face).
struct FeatureGraph {
  std::vector<std::vector<int>> crease, border;
};

FeatureGraph feature_graph(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double min_dihedral) {
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  const auto normal = [&](int f) -> Eigen::Vector3d {
    const Eigen::Vector3d n =
        (V.row(F(f, 1)) - V.row(F(f, 0))).cross(V.row(F(f, 2)) - V.row(F(f, 0))).transpose();
    return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
  };
  const double min_cos = std::cos(min_dihedral);
  FeatureGraph g;
  g.crease.resize(V.rows());
  g.border.resize(V.rows());
  const auto join = [](std::vector<std::vector<int>>& adj, std::pair<int, int> e) {
    adj[e.first].push_back(e.second);
    adj[e.second].push_back(e.first);
  };
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() == 1) join(g.border, edge);
    if (faces.size() != 2) continue;
    const Eigen::Vector3d n0 = normal(faces[0]), n1 = normal(faces[1]);
    if (n0.isZero() || n1.isZero() || n0.dot(n1) >= min_cos) continue;
    join(g.crease, edge);
  }
  return g;
}

// Whether the polyline a → v → b turns by more than max_turn (radians) at v.
bool turns_at(const Eigen::MatrixX3d& V, int a, int v, int b, double max_turn) {
  const Eigen::Vector3d in = (V.row(v) - V.row(a)).transpose(), on = (V.row(b) - V.row(v)).transpose();
  return in.norm() > 0 && on.norm() > 0 && std::acos(std::clamp(in.normalized().dot(on.normalized()), -1.0, 1.0)) > max_turn;
}

// Polyline length of input vertices `line`.
double polyline_length(const Eigen::MatrixX3d& V, const std::vector<int>& line) {
  double length = 0;
  for (std::size_t i = 1; i < line.size(); ++i) length += (V.row(line[i]) - V.row(line[i - 1])).norm();
  return length;
}

// The point of `line` at arc length `at` from its first vertex (clamped to the line's ends).
Eigen::Vector3d point_at(const Eigen::MatrixX3d& V, const std::vector<int>& line, double at) {
  double done = 0;  // arc length at line[i - 1]
  for (std::size_t i = 1; i < line.size(); ++i) {
    const double piece = (V.row(line[i]) - V.row(line[i - 1])).norm();
    if (done + piece >= at && piece > 0) {
      const double t = std::clamp((at - done) / piece, 0.0, 1.0);
      return ((1 - t) * V.row(line[i - 1]) + t * V.row(line[i])).transpose();
    }
    done += piece;
  }
  return at <= 0 ? Eigen::Vector3d(V.row(line.front()).transpose()) : Eigen::Vector3d(V.row(line.back()).transpose());
}

// Points along `line` at `segments` + 1 equal arc-length steps, both ends included.
std::vector<Eigen::Vector3d> resample(const Eigen::MatrixX3d& V, const std::vector<int>& line, int segments) {
  const double total = polyline_length(V, line);
  std::vector<Eigen::Vector3d> out{V.row(line.front()).transpose()};
  for (int s = 1; s < segments; ++s) out.push_back(point_at(V, line, total * s / segments));
  out.push_back(V.row(line.back()).transpose());
  return out;
}

// The arc length along `line` of its point nearest x.
double arc_length_near(const Eigen::MatrixX3d& V, const std::vector<int>& line, const Eigen::Vector3d& x) {
  double done = 0, best = std::numeric_limits<double>::infinity(), at = 0;
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Eigen::Vector3d a = V.row(line[i - 1]).transpose(), b = V.row(line[i]).transpose();
    const double piece = (b - a).norm();
    const double t = piece > 0 ? std::clamp((x - a).dot(b - a) / (piece * piece), 0.0, 1.0) : 0.0;
    const double d = (a + t * (b - a) - x).squaredNorm();
    if (d < best) best = d, at = done + t * piece;
    done += piece;
  }
  return at;
}

double mesh_min_angle(const WorkingMesh& mesh) {
  double m = M_PI;
  for (const MeshFace& f : mesh.faces()) m = std::min(m, face_min_angle(mesh, f));
  return m;
}

// Whether the face (a, b, c) faces within 90° of `n`.
bool faces_along(const WorkingMesh& mesh, int a, int b, int c, const Eigen::Vector3d& n) {
  const Eigen::Vector3d m = (mesh.V.row(b) - mesh.V.row(a)).cross(mesh.V.row(c) - mesh.V.row(a)).transpose();
  return m.norm() > 0 && m.dot(n) > 0;
}

// Joins u and w by an edge: it exists, or one face (u, a, b) at u has across (a, b) the face
// (b, a, w) and flipping (a, b) into (u, w) folds neither new face. Returns 0 (joined as it
// was), 1 (joined by a flip) or −1 (not joined).
// `vf` (the faces at each vertex) is kept up to date.
int join(WorkingMesh& mesh, int u, int w, std::vector<std::vector<int>>& vf) {
  if (mesh.edge_face_count(u, w) > 0) return 0;
  for (int f1 : vf[u]) {
    const MeshFace t = mesh.face(f1);
    int k = 0;
    while (t[k] != u) ++k;
    const int a = t[(k + 1) % 3], b = t[(k + 2) % 3];
    const int f2 = mesh.half_edge_face(b, a);
    if (f2 < 0 || mesh.edge_face_count(a, b) != 2) continue;
    int d = -1;
    for (int v : mesh.face(f2))
      if (v != a && v != b) d = v;
    if (d != w || mesh.valence(a) <= 3 || mesh.valence(b) <= 3) continue;
    const Eigen::Vector3d n = ((mesh.V.row(a) - mesh.V.row(u)).cross(mesh.V.row(b) - mesh.V.row(u)) +
                               (mesh.V.row(a) - mesh.V.row(b)).cross(mesh.V.row(w) - mesh.V.row(b)))
                                  .transpose();
    if (!faces_along(mesh, w, u, a, n) || !faces_along(mesh, u, w, b, n)) continue;
    mesh.flip(f1, (k + 1) % 3, f2);  // the edge a→b is corner k + 1 of f1: now (u, a, w), (w, b, u)
    const auto drop = [&](int v, int f) { vf[v].erase(std::find(vf[v].begin(), vf[v].end(), f)); };
    drop(a, f2);
    drop(b, f1);
    vf[u].push_back(f2);
    vf[w].push_back(f1);
    return 1;
  }
  return -1;
}

// The point of the polyline `line` (input vertices) nearest to x.
Eigen::Vector3d nearest_on_line(const Eigen::MatrixX3d& V, const std::vector<int>& line, const Eigen::Vector3d& x) {
  Eigen::Vector3d best = V.row(line.front()).transpose();
  for (std::size_t i = 1; i < line.size(); ++i) {
    const Eigen::Vector3d a = V.row(line[i - 1]).transpose(), ab = V.row(line[i]).transpose() - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    if ((a + t * ab - x).norm() < (best - x).norm()) best = a + t * ab;
  }
  return best;
}

// Joins u and w through a common neighbour x not on a line yet nor on the border (the one
// nearest to the segment u–w), moved onto the line: u–x–w is then an edge path along it. Returns x, or −1.
int bridge(WorkingMesh& mesh, int u, int w, const Eigen::MatrixX3d& V, const std::vector<int>& line,
           const std::vector<std::vector<int>>& vf, std::vector<char>& taken, const std::vector<char>& border) {
  std::vector<int> around_u;
  for (int f : vf[u])
    for (int v : mesh.face(f)) around_u.push_back(v);
  const Eigen::Vector3d a = mesh.V.row(u).transpose(), b = mesh.V.row(w).transpose();
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int f : vf[w])
    for (int x : mesh.face(f)) {
      if (x == u || x == w || taken[x] || border[x] || std::find(around_u.begin(), around_u.end(), x) == around_u.end()) continue;
      const Eigen::Vector3d p = mesh.V.row(x).transpose();
      const double t = std::clamp((p - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-300), 0.0, 1.0);
      const double d = (a + t * (b - a) - p).norm();
      if (d < best_d) best_d = d, best = x;
    }
  if (best < 0) return -1;
  // Onto the line between u and w: the point of the line nearest to x's foot on the middle half
  // of u–w (never onto u or w themselves).
  const Eigen::Vector3d x = mesh.V.row(best).transpose();
  const double t = std::clamp((x - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-300), 0.25, 0.75);
  mesh.V.row(best) = nearest_on_line(V, line, a + t * (b - a)).transpose();
  taken[best] = 1;
  return best;
}

}  // namespace

double CreaseLines::length(const Eigen::MatrixX3d& V, int line) const { return polyline_length(V, lines[line]); }

namespace {

// Walks the border from v through its neighbour `first` until `reach` arc length (at least one
// edge); calls visit(w, arc) on every vertex passed, with its arc length from v. Stops early at a
// vertex with other than two border neighbours or back at v. Returns the last vertex reached.
template <typename Visit>
int walk_border(const Eigen::MatrixX3d& V, const std::vector<std::vector<int>>& border, int v, int first, double reach,
                Visit visit) {
  int prev = v, at = first;
  double done = (V.row(at) - V.row(v)).norm();
  visit(at, done);
  while (done < reach && at != v && border[at].size() == 2) {
    const int go = border[at][0] == prev ? border[at][1] : border[at][0];
    done += (V.row(go) - V.row(at)).norm();
    prev = at;
    at = go;
    visit(at, done);
  }
  return at;
}

// Corners of the border seen at the output's scale: the turn of a border vertex is the angle
// between the chords to the border points `reach` behind and ahead of it (the edges themselves
// where reach is 0), so a border ragged finer than the output has no corners; of the vertices
// turning by more than max_turn, the one turning most within `reach` each way is the corner (a
// border neighbour farther than `reach` is no rival: each corner of a square of two triangles is
// one).
std::vector<int> border_corners(const Eigen::MatrixX3d& V, const std::vector<std::vector<int>>& border, double reach,
                                double max_turn) {
  const int nv = static_cast<int>(V.rows());
  std::vector<double> turn(nv, 0.0);
  const auto none = [](int, double) {};
  for (int v = 0; v < nv; ++v) {
    if (border[v].size() != 2) continue;
    const int behind = walk_border(V, border, v, border[v][0], reach, none);
    const int ahead = walk_border(V, border, v, border[v][1], reach, none);
    const Eigen::Vector3d in = (V.row(v) - V.row(behind)).transpose(), on = (V.row(ahead) - V.row(v)).transpose();
    if (behind != v && ahead != v && in.norm() > 0 && on.norm() > 0)
      turn[v] = std::acos(std::clamp(in.normalized().dot(on.normalized()), -1.0, 1.0));
  }
  std::vector<int> corners;
  for (int v = 0; v < nv; ++v) {
    if (!(turn[v] > max_turn)) continue;
    bool top = true;
    for (int first : border[v]) {
      // The walk's first step is taken whatever its length; a neighbour beyond `reach` is no rival.
      const auto beaten = [&](int w, double arc) {
        if (w == first && arc > reach) return;
        top = top && (turn[w] < turn[v] || (turn[w] == turn[v] && w >= v));
      };
      walk_border(V, border, v, first, reach, beaten);
    }
    if (top) corners.push_back(v);
  }
  return corners;
}

// Connected components of the border edges: a label per vertex, −1 off the border.
std::vector<int> border_loop_labels(const std::vector<std::vector<int>>& border) {
  std::vector<int> label(border.size(), -1);
  int loops = 0;
  for (std::size_t v = 0; v < border.size(); ++v) {
    if (border[v].empty() || label[v] >= 0) continue;
    std::vector<int> stack{static_cast<int>(v)};
    label[v] = loops;
    while (!stack.empty()) {
      const int at = stack.back();
      stack.pop_back();
      for (int w : border[at])
        if (label[w] < 0) label[w] = loops, stack.push_back(w);
    }
    ++loops;
  }
  return label;
}

}  // namespace

CreaseLines detect_creases(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const CreaseOptions& options,
                           double spacing) {
  CreaseLines out;
  const FeatureGraph g = feature_graph(V, F, options.min_dihedral_deg * kDegree);
  const int nv = static_cast<int>(V.rows());
  const double max_turn = options.corner_turn_deg * kDegree;
  out.corner.assign(nv, 0);
  out.on_border.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    const std::vector<int>& c = g.crease[v];
    const std::vector<int>& b = g.border[v];
    out.on_border[v] = !b.empty();
    if (!c.empty()) out.corner[v] = c.size() != 2 || turns_at(V, c[0], v, c[1], max_turn) || !b.empty();
    if (options.border_corners && !b.empty() && b.size() != 2) out.corner[v] = 1;
  }
  if (options.border_corners)
    for (int v : border_corners(V, g.border, 0.5 * spacing, max_turn)) out.corner[v] = 1;
  out.border_loop = border_loop_labels(g.border);
  for (int v = 0; v < nv; ++v)
    for (int w : g.border[v])
      if (v < w) out.border_edges.emplace_back(v, w);
  // From every corner along each unused feature edge to the next corner; then the closed crease
  // loops (a border loop without corners is no line: the border stages keep it).
  std::map<std::pair<int, int>, char> used;
  const auto take = [&](int a, int b) { return used.emplace(std::make_pair(std::min(a, b), std::max(a, b)), 1).second; };
  const auto walk = [&](const std::vector<std::vector<int>>& adj, int start, int next, bool border) {
    std::vector<int> line{start};
    int prev = start, at = next;
    while (true) {
      line.push_back(at);
      if (out.corner[at] || at == start || adj[at].size() != 2) break;
      const int go = adj[at][0] == prev ? adj[at][1] : adj[at][0];
      if (!take(at, go)) break;
      prev = at;
      at = go;
    }
    out.lines.push_back(std::move(line));
    out.border.push_back(border);
  };
  for (int v = 0; v < nv; ++v)
    if (out.corner[v])
      for (int u : g.crease[v])
        if (take(v, u)) walk(g.crease, v, u, false);
  if (options.border_corners)
    for (int v = 0; v < nv; ++v)
      if (out.corner[v] && out.on_border[v] && g.border[v].size() == 2)
        for (int u : g.border[v])
          if (take(v, u)) walk(g.border, v, u, true);
  for (int v = 0; v < nv; ++v)
    for (int u : g.crease[v])
      if (take(v, u)) walk(g.crease, v, u, false);
  return out;
}

namespace {

// The steps of recover_creases() on one mesh: which vertices are on a line (`taken`) and which
// edges run along one (`line_edges`) are shared by the steps.
class CreaseRecovery {
 public:
  CreaseRecovery(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                 const CreaseLines& lines, const CreaseOptions& o, double spacing, const std::vector<char>& excluded)
      : mesh_(mesh), surface_(surface), V_(V), lines_(lines), o_(o), spacing_(spacing), excluded_(excluded),
        border_pass_(std::find(excluded.begin(), excluded.end(), 0) != excluded.end() &&
                     lines.border[std::find(excluded.begin(), excluded.end(), 0) - excluded.begin()]),
        taken_(mesh.num_vertices(), 0), out_border_(mesh.boundary_vertices()), next_(mesh.num_vertices(), -1),
        prev_(mesh.num_vertices(), -1) {
    // The output's border as successor and predecessor along its half-edges (−2 where a vertex
    // has two: a pinched border, no line is recovered through it).
    for (const MeshFace& f : mesh.faces())
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if (mesh.half_edge_face(b, a) >= 0) continue;
        next_[a] = next_[a] == -1 ? b : -2;
        prev_[b] = prev_[b] == -1 ? a : -2;
      }
    // The vertices a sample may take, binned in cells of the snap radius: a vertex not taken
    // keeps its place until polish() (an undo restores the places with the taken flags).
    std::vector<char> in_faces(mesh.num_vertices(), 0);
    for (const MeshFace& f : mesh.faces())
      for (int v : f) in_faces[v] = 1;
    cell_size_ = std::max(o_.max_snap_spacings * spacing_, 1e-300);
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (in_faces[v]) grid_[cell_of(mesh.V.row(v).transpose())].push_back(v);
    // The input's border edges in every cell their bounding box meets.
    for (int e = 0; e < static_cast<int>(lines.border_edges.size()); ++e) {
      const auto [a, b] = lines.border_edges[e];
      const Cell lo = cell_of(V.row(a).cwiseMin(V.row(b)).transpose()), hi = cell_of(V.row(a).cwiseMax(V.row(b)).transpose());
      for (long i = lo[0]; i <= hi[0]; ++i)
        for (long j = lo[1]; j <= hi[1]; ++j)
          for (long k = lo[2]; k <= hi[2]; ++k) border_grid_[{i, j, k}].push_back(e);
    }
  }

  // Every line long enough resampled at the spacing: its corners first (shared by the lines
  // that end there) all at once, then line by line its other samples, each onto the nearest free
  // vertex, and joined. A line whose snap makes faces cross is undone alone (a crease along a
  // part thinner than the spacing); so is a corner (snap_corners()).
  void recover_lines(long crossing_before) {
    std::vector<int> kept;
    std::map<int, int> corner_vertex;
    for (int l = 0; l < static_cast<int>(lines_.lines.size()); ++l)
      if (!excluded_[l] && lines_.length(V_, l) >= o_.min_line_spacings * spacing_) kept.push_back(l);
    std::vector<int> ends;
    for (int l : kept)
      for (int end : {lines_.lines[l].front(), lines_.lines[l].back()})
        if (lines_.corner[end] && std::find(ends.begin(), ends.end(), end) == ends.end()) ends.push_back(end);
    crossing_ = crossing_face_pairs(mesh_);
    if (!snap_corners(ends, crossing_before, corner_vertex)) return;
    for (int l : kept)
      for (int end : {lines_.lines[l].front(), lines_.lines[l].back()})
        if (lines_.corner[end] && corner_vertex[end] >= 0) corner_lines_[corner_vertex[end]].push_back(l);
    for (int l : kept) {
      const Transaction line = begin();
      if (lines_.border[l]) recover_border_line(l, corner_vertex);
      else recover_line(l, corner_vertex);
      if (crosses_more_since(line, crossing_before)) undo(line), ++stats.skipped_lines;
      else ++stats.lines;
    }
  }

  // The corners `ends` (input vertices) snapped all at once; where that makes faces cross, one
  // by one, each undone alone where it does (a corner whose nearest vertex is across a part
  // thinner than the spacing). False where no corner could be kept.
  bool snap_corners(const std::vector<int>& ends, long crossing_before, std::map<int, int>& corner_vertex) {
    const Transaction all = begin();
    for (int end : ends) corner_vertex[end] = snap_corner(end);
    if (!crosses_more_since(all, crossing_before)) {
      stats.corners = static_cast<int>(ends.size());
      return true;
    }
    undo(all);
    corner_vertex.clear();
    int kept = 0;
    for (int end : ends) {
      const Transaction one = begin();
      const int v = snap_corner(end);
      if (v >= 0 && crosses_more_since(one, crossing_before)) undo(one), corner_vertex[end] = -1;
      else corner_vertex[end] = v, kept += v >= 0;
    }
    stats.corners = kept;
    return kept > 0;
  }

  // Corner `end` (an input vertex) onto the nearest free vertex: for a corner on the input's
  // border, a vertex of the output's border nearer to that border loop than to any other.
  int snap_corner(int end) {
    return snap(V_.row(end).transpose(), lines_.on_border[end], lines_.on_border[end] ? lines_.border_loop[end] : -1);
  }

  // Line l resampled, its samples between the corners snapped, consecutive samples joined by an
  // edge, by a flip, or through a common neighbour moved onto the line; a line whose samples are
  // all joined is an edge path, its vertices spread evenly along it (a bridge vertex sits between
  // two samples).
  void recover_line(int l, std::map<int, int>& corner_vertex) {
    const std::vector<int>& line = lines_.lines[l];
    const int segments = std::max(1, static_cast<int>(std::lround(lines_.length(V_, l) / spacing_)));
    const std::vector<Eigen::Vector3d> points = resample(V_, line, segments);
    std::vector<int> c;
    for (std::size_t s = 0; s < points.size(); ++s) {
      const int end = s == 0 ? line.front() : line.back();
      const bool at_corner = (s == 0 || s + 1 == points.size()) && lines_.corner[end];
      c.push_back(at_corner ? corner_vertex[end] : snap(points[s]));
    }
    std::vector<std::vector<int>> vf = mesh_.vertex_faces();
    std::vector<int> path{c.front()};
    std::vector<int> run;  // the current run of joined samples of a line with gaps
    std::vector<std::vector<int>> runs;
    const auto end_run = [&]() {
      if (run.size() >= 3) runs.push_back(run);
      run.clear();
    };
    bool whole = true;
    for (std::size_t s = 1; s < c.size(); ++s) {
      const int u = c[s - 1], w = c[s];
      if (u < 0 || w < 0 || u == w) {
        ++stats.missing_edges;
        whole = false;
        end_run();
        continue;
      }
      if (run.empty()) run.push_back(u);
      const int joined = join(mesh_, u, w, vf);
      if (joined >= 0) {
        stats.flips += joined;
        mark(u, w);
        path.push_back(w);
        run.push_back(w);
        continue;
      }
      const int x = bridge(mesh_, u, w, V_, line, vf, taken_, out_border_);
      if (x < 0) {
        ++stats.missing_edges;
        whole = false;
        end_run();
        continue;
      }
      ++stats.snapped;
      mark(u, x);
      mark(x, w);
      path.push_back(x);
      path.push_back(w);
      run.push_back(x);
      run.push_back(w);
    }
    end_run();
    if (whole) spread(l, path);
    else
      for (const std::vector<int>& r : runs) record_run(l, r);
  }

  // Border line l: the output's border path between the vertices of its two corners (the
  // direction along the border whose vertices lie nearer to their places on the line), its
  // vertices spread evenly along the input's border between the corners.
  void recover_border_line(int l, std::map<int, int>& corner_vertex) {
    const std::vector<int>& line = lines_.lines[l];
    const int from = corner_vertex[line.front()], to = corner_vertex[line.back()];
    std::vector<int> best;
    double best_score = o_.border_snap_spacings * spacing_;
    if (from >= 0 && to >= 0)
      for (const std::vector<int>* step : {&next_, &prev_}) {
        const std::vector<int> path = border_path(from, to, *step);
        if (path.empty()) continue;
        const double score = mean_distance_to_spread(line, path);
        if (score < best_score) best_score = score, best = path;
      }
    if (best.empty()) {
      ++stats.missing_edges;
      return;
    }
    for (std::size_t i = 1; i < best.size(); ++i) mark(best[i - 1], best[i]);
    for (int v : best) taken_[v] = 1;
    spread(l, best);
  }

  // The output's border from vertex `from` along `step` (next_ or prev_) to the first corner
  // vertex; empty unless that is `to`, or where it passes a vertex a line took already.
  std::vector<int> border_path(int from, int to, const std::vector<int>& step) const {
    std::vector<int> path{from};
    for (int v = step[from]; v >= 0 && path.size() <= static_cast<std::size_t>(mesh_.num_vertices()); v = step[v]) {
      path.push_back(v);
      if (corner_lines_.count(v)) return v == to ? path : std::vector<int>{};
      if (taken_[v]) return {};
    }
    return {};
  }

  // Mean distance from the vertices of `path` to where spread() would put them on `line`.
  double mean_distance_to_spread(const std::vector<int>& line, const std::vector<int>& path) const {
    const int segments = static_cast<int>(path.size()) - 1;
    if (segments < 2) return 0;
    const std::vector<Eigen::Vector3d> at = resample(V_, line, segments);
    double sum = 0;
    for (int i = 1; i < segments; ++i) sum += (mesh_.V.row(path[i]).transpose() - at[i]).norm();
    return sum / (segments - 1);
  }

  // The vertices off the lines relaxed, flipped and polished around them; slivers whose corners
  // are all on lines flipped across their edges that do not run along one.
  // Only vertices within polish_rings rings of a line vertex move: the rest of the mesh keeps
  // its shape (a relaxation there would round off its tips).
  void polish() {
    std::vector<char> near = taken_;
    for (int ring = 0; ring < o_.polish_rings; ++ring) {
      std::vector<char> next = near;
      for (const MeshFace& f : mesh_.faces())
        if (near[f[0]] || near[f[1]] || near[f[2]]) next[f[0]] = next[f[1]] = next[f[2]] = 1;
      near.swap(next);
    }
    std::vector<char> movable(mesh_.num_vertices(), 0), fixed(mesh_.num_vertices(), 1);
    for (int v = 0; v < mesh_.num_vertices(); ++v) movable[v] = near[v] && !taken_[v], fixed[v] = !movable[v];
    FlipOptions flips;
    flips.valence_mode = false;
    for (int round = 0; round < o_.polish_rounds; ++round) {
      flip_between_lines();
      slide_on_lines();
      RelaxationBorder border;
      border.slide = true;
      tangential_relaxation(mesh_, surface_, o_.threads, border, &fixed);
      flip_edges(mesh_, flips, &movable);
      angle_polish(mesh_, surface_, 2, fixed, {}, o_.threads);
      flip_edges(mesh_, flips, &movable);
    }
    flip_between_lines();
  }

  // The faces below `floor` that the lines do not excuse. A face is excused where its smallest
  // angle is at least half of `floor` and at a corner between two line edges (two lines meeting
  // at that angle bound every triangle between them), or, between crease lines, where its three
  // corners are on lines (two lines closer than the spacing). Below half of it no corner excuses
  // a face: two lines meeting that sharply are most likely a ragged crease of a coarse input
  // (a decimated scan), not a feature worth a sliver. `blamed`
  // gets the lines with a recovered vertex within polish_rings + 1 rings of the faces counted.
  int unexcused_below(double floor, std::vector<int>& blamed) const {
    int count = 0;
    std::map<int, std::vector<int>> lines_at = corner_lines_;
    for (const LinePath& p : paths_)
      for (int v : p.path) lines_at[v].push_back(p.line);
    const std::vector<std::vector<int>> vf = mesh_.vertex_faces();
    for (const MeshFace& f : mesh_.faces()) {
      const double smallest = face_min_angle(mesh_, f);
      if (smallest >= floor) continue;
      int k = 0;
      for (int q = 1; q < 3; ++q)
        if (corner_angle(mesh_, f, q) < corner_angle(mesh_, f, k)) k = q;
      const bool at_corner = on_line(f[k], f[(k + 1) % 3]) && on_line(f[k], f[(k + 2) % 3]);
      const bool between_lines = !border_pass_ && taken_[f[0]] && taken_[f[1]] && taken_[f[2]];
      if ((at_corner || between_lines) && smallest >= 0.5 * floor) continue;
      ++count;
      for (int w : ring_vertices(f, vf))
        if (lines_at.count(w)) blamed.insert(blamed.end(), lines_at[w].begin(), lines_at[w].end());
    }
    std::sort(blamed.begin(), blamed.end());
    blamed.erase(std::unique(blamed.begin(), blamed.end()), blamed.end());
    return count;
  }

  // The vertices within polish_rings + 1 rings of face f (the ones the polish around a line
  // vertex there may have moved).
  std::vector<int> ring_vertices(const MeshFace& f, const std::vector<std::vector<int>>& vf) const {
    std::vector<int> near(f.begin(), f.end());
    for (int ring = 0; ring <= o_.polish_rings; ++ring)
      for (std::size_t i = 0, n = near.size(); i < n; ++i)
        for (int g : vf[near[i]])
          for (int w : mesh_.face(g))
            if (std::find(near.begin(), near.end(), w) == near.end()) near.push_back(w);
    return near;
  }

  CreaseStats stats;

 private:
  // The nearest vertex of the mesh not taken yet within max_snap_spacings, moved onto x.
  // Only a vertex on the same side of the surface as the line (its normal within 90° of the
  // surface's normal at x, about the bisector of the crease's two faces) qualifies: across a
  // plate thinner than the spacing the nearest vertex may be on the other side.
  // A border corner (`border`) takes the nearest border vertex within border_snap_spacings; any
  // other sample a vertex off the border.
  int snap(const Eigen::Vector3d& x, bool border = false, int loop = -1) {
    Eigen::Vector3d pos, nrm;
    int hint = -1;
    surface_.project(x, hint, pos, nrm);
    const bool sided = nrm.allFinite() && nrm.norm() > 0;
    int best = -1;
    double best_d = (border ? o_.border_snap_spacings : o_.max_snap_spacings) * spacing_;
    for_items_near(grid_, x, best_d, [&](int v) {
      if (taken_[v] || out_border_[v] != border || (sided && !(mesh_.N.row(v).dot(nrm.transpose()) > 0)) ||
          (loop >= 0 && nearest_input_loop(v) != loop))
        return;
      const double d = (mesh_.V.row(v).transpose() - x).norm();
      if (d < best_d || (d == best_d && best >= 0 && v < best)) best_d = d, best = v;
    });
    if (best < 0) return -1;
    mesh_.anchor[best] = hint;
    mesh_.V.row(best) = x.transpose();
    if (nrm.allFinite()) mesh_.N.row(best) = nrm.transpose();
    taken_[best] = 1;
    ++stats.snapped;
    return best;
  }

  // The vertices of `path`, an edge path along `line` from its start to its end, moved to equal
  // arc-length steps of the line; its two ends keep their place.
  // Recorded in paths_ for slide_on_lines().
  void spread(int l, const std::vector<int>& path) {
    const std::vector<int>& line = lines_.lines[l];
    const int segments = static_cast<int>(path.size()) - 1;
    const std::vector<Eigen::Vector3d> at = resample(V_, line, segments);
    for (std::size_t i = 1; i + 1 < path.size(); ++i) place(path[i], at[i]);
    LinePath recorded{l, path, {}};
    const double total = polyline_length(V_, line);
    for (int i = 0; i <= segments; ++i) recorded.at.push_back(total * i / segments);
    paths_.push_back(std::move(recorded));
  }

  // A run of joined samples of line l (a line with gaps) recorded in paths_ for
  // slide_on_lines(), with the arc length of each vertex's nearest point of the line; left out
  // where those are not increasing along the run (a closed line's run across its start).
  void record_run(int l, const std::vector<int>& run) {
    LinePath recorded{l, run, {}};
    for (int v : run) {
      const double at = arc_length_near(V_, lines_.lines[l], mesh_.V.row(v).transpose());
      if (!recorded.at.empty() && !(at > recorded.at.back())) return;
      recorded.at.push_back(at);
    }
    paths_.push_back(std::move(recorded));
  }

  // Vertex v moved onto x, a point of the input surface, with the surface's normal there.
  void place(int v, const Eigen::Vector3d& x) {
    Eigen::Vector3d pos, nrm;
    surface_.project(x, mesh_.anchor[v], pos, nrm);
    mesh_.V.row(v) = x.transpose();
    if (nrm.allFinite()) mesh_.N.row(v) = nrm.transpose();
  }

  // The smallest angle of the faces `faces` at vertex v if v were at x; −1 if a face would turn
  // by 90° or more from `normals` (its normal with v where it is).
  double min_angle_with(int v, const Eigen::Vector3d& x, const std::vector<int>& faces,
                        const std::vector<Eigen::Vector3d>& normals) {
    const Eigen::RowVector3d kept = mesh_.V.row(v);
    mesh_.V.row(v) = x.transpose();
    double smallest = M_PI;
    for (std::size_t i = 0; i < faces.size() && smallest >= 0; ++i) {
      const MeshFace& f = mesh_.face(faces[i]);
      smallest = faces_along(mesh_, f[0], f[1], f[2], normals[i]) ? std::min(smallest, face_min_angle(mesh_, f)) : -1;
    }
    mesh_.V.row(v) = kept;
    return smallest;
  }

  // Every vertex inside a recovered path or run slid along its line, between its two neighbours,
  // to the place among slide_steps + 1 evenly spaced ones in the middle slide_range of that
  // interval where the smallest angle of its faces is largest (the ends and corners keep their
  // place). Where two lines run closer than the spacing (a plate thinner than a cell), evenly
  // spread samples on both face each other and the faces between the lines are right-angled or
  // worse; sliding staggers them.
  void slide_on_lines() {
    if (o_.slide_steps < 1 || !(o_.slide_range > 0)) return;
    const std::vector<std::vector<int>> vf = mesh_.vertex_faces();
    std::vector<Eigen::Vector3d> normals;
    for (LinePath& p : paths_) {
      const std::vector<int>& line = lines_.lines[p.line];
      for (std::size_t i = 1; i + 1 < p.path.size(); ++i) {
        const int v = p.path[i];
        normals.clear();
        for (int f : vf[v]) {
          const MeshFace& t = mesh_.face(f);
          normals.push_back((mesh_.V.row(t[1]) - mesh_.V.row(t[0])).cross(mesh_.V.row(t[2]) - mesh_.V.row(t[0])).transpose());
        }
        const double lo = p.at[i - 1], hi = p.at[i + 1];
        double best = min_angle_with(v, mesh_.V.row(v).transpose(), vf[v], normals), best_at = p.at[i];
        for (int step = 0; step <= o_.slide_steps; ++step) {
          const double at = lo + (hi - lo) * (0.5 + o_.slide_range * (static_cast<double>(step) / o_.slide_steps - 0.5));
          const double angle = min_angle_with(v, point_at(V_, line, at), vf[v], normals);
          if (angle > best + 1e-9) best = angle, best_at = at;
        }
        if (best_at != p.at[i]) {
          place(v, point_at(V_, line, best_at));
          p.at[i] = best_at;
        }
      }
    }
  }

  // Everything a line's recovery changes, to undo it.
  struct Transaction {
    WorkingMesh::Checkpoint mesh;
    std::vector<char> taken;
    std::set<std::pair<int, int>> line_edges;
    std::size_t paths;
    CreaseStats stats;
  };
  Transaction begin() const { return {mesh_.checkpoint(), taken_, line_edges_, paths_.size(), stats}; }

  // Whether the mesh has more than `limit` crossing face pairs after the edits since `t`, whose
  // state's pairs are crossing_: only the faces the edits made or moved are checked
  // (crossing_face_pairs_after()). Where it has not, crossing_ becomes the pairs of the mesh now;
  // where it has, the caller undoes `t` and crossing_ holds for the state restored.
  bool crosses_more_since(const Transaction& t, long limit) {
    std::vector<FacePair> now = crossing_face_pairs_after(mesh_, t.mesh, crossing_);
    if (static_cast<long>(now.size()) > limit) return true;
    crossing_ = std::move(now);
    return false;
  }
  void undo(const Transaction& t) {
    mesh_.rollback(t.mesh, true);
    taken_ = t.taken;
    line_edges_ = t.line_edges;
    paths_.resize(t.paths);
    const int skipped = stats.skipped_lines;
    stats = t.stats;
    stats.skipped_lines = skipped;
  }

  void mark(int a, int b) {
    line_edges_.emplace(std::min(a, b), std::max(a, b));
    ++stats.line_edges;
  }
  bool on_line(int a, int b) const { return line_edges_.count({std::min(a, b), std::max(a, b)}) > 0; }

  // Max-min-angle flips of the edges at a line vertex that do not run along a line (the flips of
  // the polish leave every edge at a line vertex alone), in faces below min_angle_deg only: a
  // corner of a square sheet split into three 30° faces becomes two 45° ones.
  void flip_between_lines() {
    const double sliver = o_.min_angle_deg * kDegree;
    for (int f1 = 0; f1 < mesh_.num_faces(); ++f1) {
      if (face_min_angle(mesh_, mesh_.face(f1)) >= sliver) continue;
      for (int k = 0; k < 3; ++k) {
        const MeshFace t = mesh_.face(f1);
        const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        const int f2 = mesh_.half_edge_face(b, a);
        if (f2 < 0 || (!taken_[a] && !taken_[b]) || on_line(a, b) || mesh_.valence(a) <= 3 || mesh_.valence(b) <= 3)
          continue;
        int d = -1;
        for (int v : mesh_.face(f2))
          if (v != a && v != b) d = v;
        if (d < 0 || d == c || mesh_.edge_face_count(c, d) > 0) continue;
        const double old_min = std::min(face_min_angle(mesh_, t), face_min_angle(mesh_, mesh_.face(f2)));
        const double new_min = std::min(face_min_angle(mesh_, {c, a, d}), face_min_angle(mesh_, {d, b, c}));
        const Eigen::Vector3d n = ((mesh_.V.row(b) - mesh_.V.row(a)).cross(mesh_.V.row(c) - mesh_.V.row(a)) +
                                   (mesh_.V.row(a) - mesh_.V.row(b)).cross(mesh_.V.row(d) - mesh_.V.row(b)))
                                      .transpose();
        if (!(new_min > old_min) || !faces_along(mesh_, c, a, d, n) || !faces_along(mesh_, d, b, c, n)) continue;
        mesh_.flip(f1, k, f2);
        break;
      }
    }
  }

  WorkingMesh& mesh_;
  const SurfaceProjector& surface_;
  const Eigen::MatrixX3d& V_;
  const CreaseLines& lines_;
  const CreaseOptions& o_;
  const double spacing_;
  const std::vector<char>& excluded_;  // lines left out
  const bool border_pass_;             // the lines recovered are border lines
  std::vector<char> taken_;
  std::vector<char> out_border_;    // output vertices on its border
  std::vector<int> next_, prev_;    // along the output's border (−1 off it, −2 pinched)
  std::map<int, std::vector<int>> corner_lines_;  // output vertices that a corner took: the lines ending there
  std::set<std::pair<int, int>> line_edges_;
  std::vector<FacePair> crossing_;  // the crossing face pairs of the mesh as recover_lines() last checked it
  // A recovered line (or a run of joined samples of a line with gaps): its edge path of output
  // vertices and their arc lengths along the line.
  struct LinePath {
    int line;
    std::vector<int> path;
    std::vector<double> at;
  };
  std::vector<LinePath> paths_;
  using Cell = std::array<long, 3>;
  Cell cell_of(const Eigen::Vector3d& x) const {
    return {static_cast<long>(std::floor(x[0] / cell_size_)), static_cast<long>(std::floor(x[1] / cell_size_)),
            static_cast<long>(std::floor(x[2] / cell_size_))};
  }
  double cell_size_ = 1;
  std::map<Cell, std::vector<int>> grid_;  // vertices in faces by cell of side max_snap_spacings · spacing
  std::map<Cell, std::vector<int>> border_grid_;  // the input's border edges by cell

  // The border loop of the input's border edge nearest to output vertex v, among the edges
  // within border_snap_spacings of it; −1 if there is none.
  int nearest_input_loop(int v) const {
    const Eigen::Vector3d x = mesh_.V.row(v).transpose();
    double best = o_.border_snap_spacings * spacing_;
    int loop = -1;
    for_items_near(border_grid_, x, best, [&](int e) {
      const auto [a, b] = lines_.border_edges[e];
      const double d = (nearest_on_line(V_, {a, b}, x) - x).norm();
      if (d < best) best = d, loop = lines_.border_loop[a];
    });
    return loop;
  }

  // Calls visit(item) for the items of `grid` in every cell within `radius` of x (cells of
  // cell_size_; at least the 3 × 3 × 3 around x's own).
  template <typename Visit>
  void for_items_near(const std::map<Cell, std::vector<int>>& grid, const Eigen::Vector3d& x, double radius,
                      Visit visit) const {
    const Cell c = cell_of(x);
    const long reach = std::max(1L, static_cast<long>(std::ceil(radius / cell_size_)));
    for (long i = -reach; i <= reach; ++i)
      for (long j = -reach; j <= reach; ++j)
        for (long k = -reach; k <= reach; ++k) {
          const auto it = grid.find({c[0] + i, c[1] + j, c[2] + k});
          if (it == grid.end()) continue;
          for (int item : it->second) visit(item);
        }
  }
};

}  // namespace

namespace {

// One pass of recover_creases(): the crease lines (`border` false) or the border lines. Kept where
// nothing crosses that did not and no face falls below the lower of the smallest angle before
// and min_angle_deg (border_min_angle_deg for the border lines), except at a corner between two
// lines (unexcused_below()). Where faces fall below it, the lines next to them are left out and
// the others recovered again (options.retries times).
CreaseStats recover_pass(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                         const CreaseLines& lines, const CreaseOptions& options, double spacing, bool border) {
  std::vector<char> excluded(lines.lines.size(), 0);
  for (std::size_t l = 0; l < lines.lines.size(); ++l) excluded[l] = lines.border[l] != border;
  if (std::find(excluded.begin(), excluded.end(), 0) == excluded.end()) return {};
  const int other_kind = static_cast<int>(std::count(excluded.begin(), excluded.end(), 1));
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const long crossing_before = self_intersecting_pairs(mesh);
  const double min_angle = border ? options.border_min_angle_deg : options.min_angle_deg;
  const double floor = std::min(mesh_min_angle(mesh), min_angle * kDegree) - 1e-9;
  for (int attempt = 0;; ++attempt) {
    CreaseRecovery recovery(mesh, surface, V, lines, options, spacing, excluded);
    recovery.recover_lines(crossing_before);
    recovery.polish();
    CreaseStats stats = recovery.stats;
    stats.dropped_lines = static_cast<int>(std::count(excluded.begin(), excluded.end(), 1)) - other_kind;
    const long crossing = self_intersecting_pairs(mesh);
    std::vector<int> blamed;
    const int below = recovery.unexcused_below(floor, blamed);
    if (crossing <= crossing_before && below == 0) return stats;
    mesh.rollback(before);
    if (attempt < options.retries && crossing <= crossing_before && !blamed.empty()) {
      for (int l : blamed) excluded[l] = 1;
      continue;
    }
    stats.undone = true;
    stats.undone_reason = crossing > crossing_before
                              ? std::to_string(crossing - crossing_before) + " more face pairs crossed"
                              : std::to_string(below) + " faces fell below the smallest angle";
    return stats;
  }
}

}  // namespace

CreaseStats recover_creases(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                            const CreaseLines& lines, const CreaseOptions& options) {
  const double spacing = mean_edge_length(mesh);
  if (!options.enabled || !(spacing > 0) || lines.lines.empty()) return {};
  CreaseStats stats = recover_pass(mesh, surface, V, lines, options, spacing, false);
  stats.dropped_crease_lines = stats.dropped_lines;
  stats.dropped_lines = 0;
  if (options.border_corners) {
    const CreaseStats b = recover_pass(mesh, surface, V, lines, options, spacing, true);
    stats.border_lines = b.lines;
    stats.border_corners = b.corners;
    stats.dropped_lines = b.dropped_lines;
    if (b.undone) stats.border_undone_reason = b.undone_reason;
  }
  return stats;
}

}  // namespace heatcvt
