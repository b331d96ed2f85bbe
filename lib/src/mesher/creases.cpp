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

// Crease edges as an adjacency list: for each vertex, the vertices it shares a crease edge with.
std::vector<std::vector<int>> crease_graph(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, double min_dihedral) {
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
  std::vector<std::vector<int>> adj(V.rows());
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() != 2) continue;
    const Eigen::Vector3d n0 = normal(faces[0]), n1 = normal(faces[1]);
    if (n0.isZero() || n1.isZero() || n0.dot(n1) >= min_cos) continue;
    adj[edge.first].push_back(edge.second);
    adj[edge.second].push_back(edge.first);
  }
  return adj;
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

double mean_edge_length(const WorkingMesh& mesh) {
  double sum = 0;
  long count = 0;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) sum += (mesh.V.row(f[k]) - mesh.V.row(f[(k + 1) % 3])).norm(), ++count;
  return count > 0 ? sum / count : 0;
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

// Joins u and w through a common neighbour x not on a line yet (the one nearest to the segment
// u–w), moved onto the line: u–x–w is then an edge path along it. Returns x, or −1.
int bridge(WorkingMesh& mesh, int u, int w, const Eigen::MatrixX3d& V, const std::vector<int>& line,
           const std::vector<std::vector<int>>& vf, std::vector<char>& taken) {
  std::vector<int> around_u;
  for (int f : vf[u])
    for (int v : mesh.face(f)) around_u.push_back(v);
  const Eigen::Vector3d a = mesh.V.row(u).transpose(), b = mesh.V.row(w).transpose();
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int f : vf[w])
    for (int x : mesh.face(f)) {
      if (x == u || x == w || taken[x] || std::find(around_u.begin(), around_u.end(), x) == around_u.end()) continue;
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

CreaseLines detect_creases(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const CreaseOptions& options) {
  CreaseLines out;
  const std::vector<std::vector<int>> adj = crease_graph(V, F, options.min_dihedral_deg * kDegree);
  const int nv = static_cast<int>(V.rows());
  out.corner.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if (adj[v].empty()) continue;
    if (adj[v].size() != 2) {
      out.corner[v] = 1;
      continue;
    }
    const Eigen::Vector3d in = (V.row(v) - V.row(adj[v][0])).transpose(), on = (V.row(adj[v][1]) - V.row(v)).transpose();
    if (in.norm() > 0 && on.norm() > 0 &&
        std::acos(std::clamp(in.normalized().dot(on.normalized()), -1.0, 1.0)) > options.corner_turn_deg * kDegree)
      out.corner[v] = 1;
  }
  std::map<std::pair<int, int>, char> used;
  const auto take = [&](int a, int b) { return used.emplace(std::make_pair(std::min(a, b), std::max(a, b)), 1).second; };
  // From every corner along each unused crease edge to the next corner; then the closed loops.
  const auto walk = [&](int start, int next) {
    std::vector<int> line{start};
    int prev = start, at = next;
    while (true) {
      line.push_back(at);
      if (out.corner[at] || at == start) break;
      const int go = adj[at][0] == prev ? adj[at][1] : adj[at][0];
      if (!take(at, go)) break;
      prev = at;
      at = go;
    }
    out.lines.push_back(std::move(line));
  };
  for (int v = 0; v < nv; ++v)
    if (out.corner[v])
      for (int u : adj[v])
        if (take(v, u)) walk(v, u);
  for (int v = 0; v < nv; ++v)
    for (int u : adj[v])
      if (take(v, u)) walk(v, u);
  return out;
}

namespace {

// The steps of recover_creases() on one mesh: which vertices are on a line (`taken`) and which
// edges run along one (`line_edges`) are shared by the steps.
class CreaseRecovery {
 public:
  CreaseRecovery(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                 const CreaseLines& lines, const CreaseOptions& o, double spacing)
      : mesh_(mesh), surface_(surface), V_(V), lines_(lines), o_(o), spacing_(spacing),
        taken_(mesh.num_vertices(), 0) {
    // The vertices a sample may take, binned in cells of the snap radius: a vertex not taken
    // keeps its place until polish() (an undo restores the places with the taken flags).
    std::vector<char> in_faces(mesh.num_vertices(), 0);
    for (const MeshFace& f : mesh.faces())
      for (int v : f) in_faces[v] = 1;
    cell_size_ = std::max(o_.max_snap_spacings * spacing_, 1e-300);
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (in_faces[v]) grid_[cell_of(mesh.V.row(v).transpose())].push_back(v);
  }

  // Every line long enough resampled at the spacing: its corners first (shared by the lines
  // that end there) all at once, then line by line its other samples, each onto the nearest free
  // vertex, and joined. A line whose snap makes faces cross is undone alone (a crease along a
  // part thinner than the spacing); so are the corners, all of them, where they do.
  void recover_lines(long crossing_before) {
    std::vector<int> kept;
    std::map<int, int> corner_vertex;
    for (int l = 0; l < static_cast<int>(lines_.lines.size()); ++l)
      if (lines_.length(V_, l) >= o_.min_line_spacings * spacing_) kept.push_back(l);
    const Transaction corners = begin();
    for (int l : kept)
      for (int end : {lines_.lines[l].front(), lines_.lines[l].back()})
        if (lines_.corner[end] && !corner_vertex.count(end)) corner_vertex[end] = snap(V_.row(end).transpose());
    stats.corners = static_cast<int>(corner_vertex.size());
    if (self_intersecting_pairs(mesh_) > crossing_before) {
      undo(corners);
      return;
    }
    for (int l : kept) {
      const Transaction line = begin();
      recover_line(l, corner_vertex);
      if (self_intersecting_pairs(mesh_) > crossing_before) undo(line), ++stats.skipped_lines;
      else ++stats.lines;
    }
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
      const int x = bridge(mesh_, u, w, V_, line, vf, taken_);
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
  // angle is at a corner between two line edges (two crease lines meeting at that angle bound
  // every triangle between them), or where its three corners are on lines (two lines closer than
  // the spacing) and its smallest angle is at least half of `floor`.
  int unexcused_below(double floor) const {
    int count = 0;
    for (const MeshFace& f : mesh_.faces()) {
      const double smallest = face_min_angle(mesh_, f);
      if (smallest >= floor) continue;
      int k = 0;
      for (int q = 1; q < 3; ++q)
        if (corner_angle(mesh_, f, q) < corner_angle(mesh_, f, k)) k = q;
      const bool at_corner = on_line(f[k], f[(k + 1) % 3]) && on_line(f[k], f[(k + 2) % 3]);
      const bool between_lines = taken_[f[0]] && taken_[f[1]] && taken_[f[2]] && smallest >= 0.5 * floor;
      if (!at_corner && !between_lines) ++count;
    }
    return count;
  }

  CreaseStats stats;

 private:
  // The nearest vertex of the mesh not taken yet within max_snap_spacings, moved onto x.
  // Only a vertex on the same side of the surface as the line (its normal within 90° of the
  // surface's normal at x, about the bisector of the crease's two faces) qualifies: across a
  // plate thinner than the spacing the nearest vertex may be on the other side.
  int snap(const Eigen::Vector3d& x) {
    Eigen::Vector3d pos, nrm;
    int hint = -1;
    surface_.project(x, hint, pos, nrm);
    const bool sided = nrm.allFinite() && nrm.norm() > 0;
    int best = -1;
    double best_d = o_.max_snap_spacings * spacing_;
    const Cell c = cell_of(x);
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k) {
          const auto it = grid_.find({c[0] + i, c[1] + j, c[2] + k});
          if (it == grid_.end()) continue;
          for (int v : it->second) {
            if (taken_[v] || (sided && !(mesh_.N.row(v).dot(nrm.transpose()) > 0))) continue;
            const double d = (mesh_.V.row(v).transpose() - x).norm();
            if (d < best_d || (d == best_d && best >= 0 && v < best)) best_d = d, best = v;
          }
        }
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

  // Max-min-angle flips of the edges between two line vertices that do not run along a line (the
  // vertex flips above leave them alone), in faces below min_angle_deg only.
  void flip_between_lines() {
    const double sliver = o_.min_angle_deg * kDegree;
    for (int f1 = 0; f1 < mesh_.num_faces(); ++f1) {
      if (face_min_angle(mesh_, mesh_.face(f1)) >= sliver) continue;
      for (int k = 0; k < 3; ++k) {
        const MeshFace t = mesh_.face(f1);
        const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        const int f2 = mesh_.half_edge_face(b, a);
        if (f2 < 0 || !taken_[a] || !taken_[b] || on_line(a, b) || mesh_.valence(a) <= 3 || mesh_.valence(b) <= 3)
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
  std::vector<char> taken_;
  std::set<std::pair<int, int>> line_edges_;
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
};

}  // namespace

CreaseStats recover_creases(WorkingMesh& mesh, const SurfaceProjector& surface, const Eigen::MatrixX3d& V,
                            const CreaseLines& lines, const CreaseOptions& options) {
  const double spacing = mean_edge_length(mesh);
  if (!options.enabled || !(spacing > 0) || lines.lines.empty()) return {};
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const long crossing_before = self_intersecting_pairs(mesh);
  const double min_before = mesh_min_angle(mesh);
  CreaseRecovery recovery(mesh, surface, V, lines, options, spacing);
  recovery.recover_lines(crossing_before);
  recovery.polish();
  CreaseStats stats = recovery.stats;
  // Kept where nothing crosses that did not and no face falls below the lower of the smallest
  // angle before and min_angle_deg, except at a corner between two lines.
  const double floor = std::min(min_before, options.min_angle_deg * kDegree) - 1e-9;
  const long crossing = self_intersecting_pairs(mesh);
  const int below = recovery.unexcused_below(floor);
  if (crossing > crossing_before || below > 0) {
    mesh.rollback(before);
    stats.undone = true;
    stats.undone_reason = crossing > crossing_before
                              ? std::to_string(crossing - crossing_before) + " more face pairs crossed"
                              : std::to_string(below) + " faces fell below the smallest angle";
  }
  return stats;
}

}  // namespace heatcvt
