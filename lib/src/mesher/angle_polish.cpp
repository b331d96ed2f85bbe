// Angle polish of the working mesh.
#include "heatcvt/mesher/angle_polish.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <iterator>
#include <cmath>
#include <limits>
#include <utility>

#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

// Quality of a one-ring: smallest angle over its triangles and the sum of the triangles'
// smallest angles (what φm averages); invalid when a triangle is inverted.
struct RingQuality {
  double min = M_PI, sum = 0;
  bool valid = true;
};

// Smallest angle of a 2D triangle, or −1 when it is inverted / degenerate (counter-clockwise = valid).
// With below_cot > 0: −2, without an atan2, when the smallest angle's cotangent exceeds below_cot
// (the angle is then below arccot(below_cot)).
double min_angle_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                    double below_cot = 0) {
  const double cr = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  if (!(cr > 0)) return -1;
  const Eigen::Vector2d p[3] = {a, b, c};
  int k = 0;  // the smallest angle is opposite the shortest edge
  double shortest = std::numeric_limits<double>::infinity();
  for (int q = 0; q < 3; ++q) {
    const double len = (p[(q + 1) % 3] - p[(q + 2) % 3]).squaredNorm();
    if (len < shortest) shortest = len, k = q;
  }
  const Eigen::Vector2d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
  const double dot = e1.dot(e2);
  if (below_cot > 0 && dot > below_cot * cr) return -2;
  return std::atan2(cr, dot);  // |e1 × e2| = cr for every corner of a CCW triangle
}

// Greedy colouring of the vertex graph in index order (vertices of one colour share no face).
std::vector<std::vector<int>> colour_classes(const WorkingMesh& mesh, const std::vector<std::vector<int>>& vf) {
  const int ns = mesh.num_vertices();
  std::vector<int> colour(ns, -1);
  std::vector<std::vector<int>> by_colour;
  for (int v = 0; v < ns; ++v) {
    std::vector<char> taken;
    for (int id : vf[v])
      for (int w : mesh.face(id))
        if (w != v && colour[w] >= 0) {
          if (static_cast<int>(taken.size()) <= colour[w]) taken.resize(colour[w] + 1, 0);
          taken[colour[w]] = 1;
        }
    int c = 0;
    while (c < static_cast<int>(taken.size()) && taken[c]) ++c;
    colour[v] = c;
    if (static_cast<int>(by_colour.size()) <= c) by_colour.resize(c + 1);
    by_colour[c].push_back(v);
  }
  return by_colour;
}

// The fan of v: every ring edge (v, b) appears as (c, v) of another face when v is interior;
// on the boundary exactly one b (`next`, the boundary edge v→next) and one c (`prev`, the
// boundary edge prev→v) have no partner.
struct Fan {
  bool interior = false;
  int next = -1, prev = -1;  ///< boundary neighbours (a single open fan only)
};

Fan fan_of(const WorkingMesh& mesh, int v, const std::vector<int>& faces) {
  std::vector<int> out_b, in_c;
  for (int id : faces) {
    const MeshFace& f = mesh.face(id);
    int k = 0;
    while (f[k] != v) ++k;
    out_b.push_back(f[(k + 1) % 3]);
    in_c.push_back(f[(k + 2) % 3]);
  }
  std::sort(out_b.begin(), out_b.end());
  std::sort(in_c.begin(), in_c.end());
  Fan fan;
  fan.interior = out_b == in_c;
  if (fan.interior) return fan;
  std::vector<int> only_out, only_in;
  std::set_difference(out_b.begin(), out_b.end(), in_c.begin(), in_c.end(), std::back_inserter(only_out));
  std::set_difference(in_c.begin(), in_c.end(), out_b.begin(), out_b.end(), std::back_inserter(only_in));
  if (only_out.size() == 1 && only_in.size() == 1) fan.next = only_out[0], fan.prev = only_in[0];
  return fan;
}

class VertexMover {
 public:
  VertexMover(WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<std::vector<int>>& vf,
              const AnglePolishOptions& o)
      : mesh_(mesh), surface_(surface), vf_(vf), o_(o), cap_(o.angle_cap_deg * M_PI / 180.0) {}

  bool better(const RingQuality& n, const RingQuality& o) const {
    if (!n.valid) return false;
    const double nm = std::min(n.min, cap_), om = std::min(o.min, cap_);
    if (nm > om + 1e-9) return true;
    if (nm < om - 1e-9) return false;
    return n.sum > o.sum + 1e-9;
  }

  // Ring quality with vertex v at x (3D), triangles checked against the normal nv.
  RingQuality ring3(int v, const Eigen::Vector3d& x, const Eigen::Vector3d& nv) const {
    RingQuality q;
    for (int id : vf_[v]) {
      const MeshFace& f = mesh_.face(id);
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = f[k] == v ? x : Eigen::Vector3d(mesh_.V.row(f[k]));
      const Eigen::Vector3d fn = (p[1] - p[0]).cross(p[2] - p[0]);
      if (!(fn.dot(nv) > 0)) q.valid = false;
      const double a = triangle_min_angle(p[0], p[1], p[2]);
      q.min = std::min(q.min, a);
      q.sum += a;
    }
    return q;
  }

  // Moves v if that improves its ring; returns whether it moved.
  bool move(int v) {
    const Eigen::MatrixX3d& S = mesh_.V;
    const Eigen::Vector3d x = S.row(v), nv = mesh_.N.row(v);
    const Eigen::Vector3d u = nv.unitOrthogonal(), w = nv.cross(u);
    // Ring triangles in 2D with v at the origin: (b, c) of each face (a = v), counter-clockwise.
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> ring;
    ring.reserve(vf_[v].size());
    double mean_edge = 0, area_sum = 0;
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (int id : vf_[v]) {
      const MeshFace& f = mesh_.face(id);
      int k = 0;
      while (f[k] != v) ++k;
      const Eigen::Vector3d b = S.row(f[(k + 1) % 3]).transpose() - x, c = S.row(f[(k + 2) % 3]).transpose() - x;
      const Eigen::Vector2d b2(b.dot(u), b.dot(w)), c2(c.dot(u), c.dot(w));
      ring.push_back({b2, c2});
      mean_edge += b2.norm();
      const double ar = 0.5 * (b2.x() * c2.y() - b2.y() * c2.x());
      if (!(ar > 0)) return false;  // folded in the tangent plane
      centroid += ar * (b2 + c2) / 3.0;
      area_sum += ar;
    }
    const Fan fan = fan_of(mesh_, v, vf_[v]);
    if (!(area_sum > 0) || (!fan.interior && (fan.next < 0 || !o_.boundary))) return false;
    mean_edge /= ring.size();
    centroid /= area_sum;
    // A boundary vertex on the samples' border searches in every direction within a band along
    // it (AnglePolishOptions::sample_border_band); `band` is the largest distance allowed.
    // It goes no farther out than sample_border_overshoot beyond the line through the mean of
    // the border points along its border chord (the averaged edge of the scan).
    double band = -1;
    Eigen::Vector3d edge_mean;
    Eigen::Vector2d outward = Eigen::Vector2d::Zero(), edge2 = Eigen::Vector2d::Zero();
    if (!fan.interior && fan.next >= 0 && fan.prev >= 0 && o_.sample_border_band > 0 &&
        surface_.sample_border_mean(x, mean_edge, edge_mean)) {
      const Eigen::Vector3d chord = S.row(fan.next) - S.row(fan.prev);
      outward = Eigen::Vector2d(chord.dot(w), -chord.dot(u));
      if (outward.dot(centroid) > 0) outward = -outward;  // away from the ring
      if (outward.norm() > 0) {
        outward.normalize();
        edge2 = Eigen::Vector2d((edge_mean - x).dot(u), (edge_mean - x).dot(w));
        band = std::max(surface_.distance_to_sample_border(x), o_.sample_border_band * mean_edge);
      }
    }
    const bool any_direction = fan.interior || band >= 0;
    auto in_band = [&](const Eigen::Vector2d& y) {
      return band < 0 || ((y - edge2).dot(outward) <= o_.sample_border_overshoot * mean_edge &&
                          surface_.distance_to_sample_border(x + y.x() * u + y.y() * w) <= band);
    };
    // Any other boundary vertex slides along the chord of its two boundary neighbours, only where
    // the boundary is nearly straight, so the border keeps its course.
    Eigen::Vector2d slide = Eigen::Vector2d::Zero();
    if (!any_direction) {
      const Eigen::Vector3d a = S.row(fan.prev).transpose() - x, b = S.row(fan.next).transpose() - x;
      if (!(a.norm() > 0) || !(b.norm() > 0) || (-a).normalized().dot(b.normalized()) < std::cos(o_.max_boundary_turn_deg * M_PI / 180.0))
        return false;
      const Eigen::Vector3d chord = b - a;
      slide = Eigen::Vector2d(chord.dot(u), chord.dot(w));
      if (!(slide.norm() > 0)) return false;
      slide.normalize();
      centroid = centroid.dot(slide) * slide;
    }
    // Ring quality with v at y. With `rival`, stops early (returning an invalid quality) as soon
    // as a triangle's smallest angle shows that the ring cannot be better() than `rival`.
    auto q2 = [&](const Eigen::Vector2d& y, const RingQuality* rival = nullptr) {
      const double floor = rival ? std::min(rival->min, cap_) - 1e-9 : -1.0;
      // Angles a margin below the floor are recognised by their cotangent (no atan2).
      const double margin = 1e-7;
      const double below_cot = floor > margin ? 1.0 / std::tan(floor - margin) : 0.0;
      RingQuality q;
      for (const auto& [b, c] : ring) {
        const double a = min_angle_2d(y, b, c, below_cot);
        if (a < 0 || a < floor) {
          q.valid = false;
          return q;
        }
        q.min = std::min(q.min, a);
        q.sum += a;
      }
      return q;
    };
    Eigen::Vector2d best = Eigen::Vector2d::Zero();
    RingQuality qb = q2(Eigen::Vector2d::Zero());
    if (const RingQuality qc = q2(centroid); better(qc, qb) && in_band(centroid)) best = centroid, qb = qc;
    double step = o_.initial_step * mean_edge;
    for (int iter = 0; iter < o_.max_search_steps && step > o_.final_step * mean_edge; ++iter) {
      bool improved = false;
      const int directions = any_direction ? 8 : 2;
      for (int d = 0; d < directions; ++d) {
        const double ang = d * 2 * M_PI / directions;
        const Eigen::Vector2d dir = any_direction ? Eigen::Vector2d(std::cos(ang), std::sin(ang)) : (d == 0 ? slide : -slide);
        const Eigen::Vector2d y = best + step * dir;
        const RingQuality qy = q2(y, &qb);
        if (better(qy, qb) && in_band(y)) best = y, qb = qy, improved = true;
      }
      if (!improved) step *= 0.5;
    }
    if (best.squaredNorm() == 0) return false;
    Eigen::Vector3d pos, nrm;
    int hint = mesh_.anchor[v];  // kept only with the move, so a rejected search can be skipped
    surface_.project(x + best.x() * u + best.y() * w, hint, pos, nrm);
    if (!pos.allFinite() || !nrm.allFinite()) return false;
    if (band >= 0 && !in_band(Eigen::Vector2d((pos - x).dot(u), (pos - x).dot(w)))) return false;
    if (!better(ring3(v, pos, nrm), ring3(v, x, nv))) return false;
    mesh_.V.row(v) = pos.transpose();
    mesh_.N.row(v) = nrm.transpose();
    mesh_.anchor[v] = hint;
    return true;
  }

 private:
  WorkingMesh& mesh_;
  const SurfaceProjector& surface_;
  const std::vector<std::vector<int>>& vf_;
  const AnglePolishOptions& o_;
  const double cap_;
};

}  // namespace

int angle_polish(WorkingMesh& mesh, const SurfaceProjector& surface, int rounds, const std::vector<char>& frozen,
                 const AnglePolishOptions& options, int threads, std::vector<char>* settled) {
  const int nv = mesh.num_vertices();
  const std::vector<std::vector<int>> vf = mesh.vertex_faces();
  const std::vector<std::vector<int>> by_colour = colour_classes(mesh, vf);
  std::vector<char> local;
  std::vector<char>& done = settled ? *settled : local;  // 1: last search kept no move, ring unchanged since
  if (static_cast<int>(done.size()) != nv) done.assign(nv, 0);
  VertexMover mover(mesh, surface, vf, options);
  std::vector<char> moved(nv, 0);
  int moves = 0;
  for (int round = 0; round < rounds; ++round) {
    int round_moves = 0;
    for (const std::vector<int>& group : by_colour) {
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 16) reduction(+ : round_moves)
      for (size_t gi = 0; gi < group.size(); ++gi) {
        const int v = group[gi];
        if (vf[v].size() < 3 || frozen[v] || done[v]) continue;
        moved[v] = mover.move(v);
        done[v] = !moved[v];
        if (moved[v]) ++round_moves;
      }
      // A move changes the rings of the vertices that share a face with it (serial, in index
      // order within the colour: the same marks for any thread count).
      for (int v : group) {
        if (!moved[v]) continue;
        moved[v] = 0;
        for (int id : vf[v])
          for (int w : mesh.face(id)) done[w] = 0;
      }
    }
    moves += round_moves;
    if (round_moves == 0) break;
  }
  return moves;
}

void unsettle_changed_faces(const std::vector<MeshFace>& before, const WorkingMesh& mesh, std::vector<char>& settled) {
  if (before.size() != mesh.faces().size() || static_cast<int>(settled.size()) != mesh.num_vertices()) {
    std::fill(settled.begin(), settled.end(), 0);
    return;
  }
  for (size_t f = 0; f < before.size(); ++f) {
    const MeshFace& now = mesh.face(static_cast<int>(f));
    if (now == before[f]) continue;
    for (int k = 0; k < 3; ++k) settled[before[f][k]] = settled[now[k]] = 0;
  }
}

void unsettle_changes_since(const WorkingMesh::Checkpoint& before, const WorkingMesh& mesh, std::vector<char>& settled) {
  const MeshChanges changes = changes_since(before, mesh);
  const int nv = mesh.num_vertices();
  settled.resize(nv, 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const MeshFace& t = mesh.face(f);
    bool changed = changes.new_face[f];
    for (int v : t) changed = changed || changes.moved[v] || changes.rehinted[v];
    if (changed) settled[t[0]] = settled[t[1]] = settled[t[2]] = 0;
  }
  for (const MeshFace& f : changes.removed)
    for (int v : f)
      if (v < nv) settled[v] = 0;
  for (int v = 0; v < nv; ++v)
    if (changes.moved[v] || changes.rehinted[v]) settled[v] = 0;
}

}  // namespace heatcvt
