// Sizing of the working mesh to the requested vertex count by isotropic remeshing.
#include "heatcvt/mesher/isotropic_remesh.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/orientation.h"
#include "heatcvt/mesher/sliver_collapse.h"
#include "heatcvt/mesher/tangential_relaxation.h"

namespace heatcvt {
namespace {

constexpr double kDegree = M_PI / 180.0;

struct Edge {
  double length;  // over the relative size at the midpoint (IsotropicRemeshOptions::relative_size)
  int a, b;       // a→b is a half-edge of a face
};

// The relative target size at x (1 without a sizing field).
double relative_size_at(const IsotropicRemeshOptions& o, const Eigen::Vector3d& x) {
  return o.relative_size ? o.relative_size(x) : 1.0;
}

// Length of the segment x–y over the relative size at its midpoint.
double relative_length(const IsotropicRemeshOptions& o, const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
  const double length = (x - y).norm();
  return o.relative_size ? length / o.relative_size(0.5 * (x + y)) : length;
}

// Every undirected edge once: the half-edge a→b with a < b, or the border half-edge.
std::vector<Edge> mesh_edges(const WorkingMesh& mesh, const IsotropicRemeshOptions& o) {
  std::vector<Edge> edges;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (a < b || !mesh.has_half_edge(b, a))
        edges.push_back({relative_length(o, mesh.V.row(a).transpose(), mesh.V.row(b).transpose()), a, b});
    }
  return edges;
}

// Orders edges by length (longest first when `longest_first`), ties by vertex indices.
void sort_edges(std::vector<Edge>& edges, bool longest_first) {
  std::sort(edges.begin(), edges.end(), [&](const Edge& x, const Edge& y) {
    if (x.length != y.length) return longest_first ? x.length > y.length : x.length < y.length;
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
}

int third_vertex(const MeshFace& f, int a, int b) {
  for (int v : f)
    if (v != a && v != b) return v;
  return -1;
}

// Distance from x to the surface's own border; `none` where the surface has no known border.
double distance_to_border(const SurfaceProjector& surface, const Eigen::Vector3d& x, double none = 0) {
  Eigen::Vector3d at, nrm;
  return surface.project_to_border(x, at, nrm) ? (at - x).norm() : none;
}

// Whether the halves (a, m, c) and (m, b, c) of the face (a, b, c) with m at `pos` face within
// max_normal_turn_deg of it.
bool split_keeps_facing(const WorkingMesh& mesh, int a, int b, int c, const Eigen::Vector3d& pos,
                        const IsotropicRemeshOptions& o) {
  const Eigen::Vector3d pa = mesh.V.row(a), pb = mesh.V.row(b), pc = mesh.V.row(c);
  const Eigen::Vector3d n = (pb - pa).cross(pc - pa);
  const Eigen::Vector3d n1 = (pos - pa).cross(pc - pa), n2 = (pb - pos).cross(pc - pos);
  const double min_cos = std::cos(o.max_normal_turn_deg * kDegree);
  return n.norm() > 0 && n1.norm() > 0 && n2.norm() > 0 && n.normalized().dot(n1.normalized()) >= min_cos &&
         n.normalized().dot(n2.normalized()) >= min_cos;
}

// Splits the edges longer than `limit`, longest first, at their midpoint projected to the
// surface; no face is split twice in one call, no edge at a frozen vertex, at most `budget` splits
// (< 0: no limit).
int split_edges(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o,
                const std::vector<char>& frozen, double limit, int budget) {
  std::vector<Edge> edges = mesh_edges(mesh, o);
  sort_edges(edges, true);
  // The splits are chosen on the mesh as it is, then the new vertices added at once (no copy of
  // the vertex arrays per split) and the faces edited.
  struct Split {
    int a, b, c, d, f1, f2, hint;
    Eigen::Vector3d pos, nrm;
  };
  std::vector<Split> splits;
  std::vector<char> touched(mesh.num_faces(), 0);
  for (const Edge& e : edges) {
    if (!(e.length > limit) || (budget >= 0 && static_cast<int>(splits.size()) >= budget)) break;
    const int a = e.a, b = e.b, f1 = mesh.half_edge_face(a, b), f2 = mesh.half_edge_face(b, a);
    if (f1 < 0 || touched[f1] || (f2 >= 0 && touched[f2]) || frozen[a] || frozen[b]) continue;
    Split s{a, b, third_vertex(mesh.face(f1), a, b), f2 >= 0 ? third_vertex(mesh.face(f2), a, b) : -1, f1, f2,
            mesh.anchor[a], {}, {}};
    const Eigen::Vector3d mid = 0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose();
    const double length = (mesh.V.row(a) - mesh.V.row(b)).norm();
    // A border edge of a surface with a known border gets its new vertex on that border.
    // Where the border point is beyond the face's opposite vertex (a corner of the border far
    // from the edge), the new vertex goes part of the way to it, onto the surface;
    // snap_border() brings it onto the border once the faces around it have moved.
    Eigen::Vector3d at;
    const bool on_border = f2 < 0 && surface.has_border() && surface.project_to_border(mid, at, s.nrm);
    double max_offset = o.max_split_offset;
    if (on_border) {
      max_offset = o.max_border_split_offset;
      s.pos = at;
      if ((at - mid).norm() > max_offset * length) {
        at = mid + max_offset * length * (at - mid).normalized();
        surface.project(at, s.hint, s.pos, s.nrm);
      }
      for (double t : {0.5, 0.25, 0.0}) {
        if (s.pos.allFinite() && split_keeps_facing(mesh, a, b, s.c, s.pos, o)) break;
        surface.project(mid + t * (at - mid), s.hint, s.pos, s.nrm);
      }
    } else {
      surface.project(mid, s.hint, s.pos, s.nrm);
    }
    if (!s.pos.allFinite() || !s.nrm.allFinite() || !((s.pos - mid).norm() <= max_offset * length)) continue;
    if (!split_keeps_facing(mesh, a, b, s.c, s.pos, o) || (f2 >= 0 && !split_keeps_facing(mesh, b, a, s.d, s.pos, o)))
      continue;
    touched[f1] = 1;
    if (f2 >= 0) touched[f2] = 1;
    splits.push_back(s);
  }
  const int first = mesh.num_vertices();
  {
    Eigen::MatrixX3d P(splits.size(), 3), N(splits.size(), 3);
    std::vector<int> hints(splits.size());
    for (size_t k = 0; k < splits.size(); ++k) {
      P.row(k) = splits[k].pos.transpose();
      N.row(k) = splits[k].nrm.transpose();
      hints[k] = splits[k].hint;
    }
    mesh.add_vertices(P, N, hints);
  }
  for (size_t k = 0; k < splits.size(); ++k) {
    const Split& s = splits[k];
    const int m = first + static_cast<int>(k);
    mesh.replace_face(s.f1, {s.a, m, s.c});
    mesh.add_face({m, s.b, s.c});
    if (s.f2 >= 0) {
      mesh.replace_face(s.f2, {s.b, m, s.d});
      mesh.add_face({m, s.a, s.d});
    }
  }
  return static_cast<int>(splits.size());
}

// Border vertices at a corner of the surface's own border, where that border is known: the mesh's
// border turns there by more than known_border_corner_turn_deg and both its border edges run
// along the surface's (their midpoints within border_chord_tolerance target lengths `length` of
// it). The relaxation, the polish and the collapses keep them in place.
std::vector<char> known_border_corners(const WorkingMesh& mesh, const SurfaceProjector& surface,
                                       const BorderLinks& border, const IsotropicRemeshOptions& o, double length) {
  std::vector<char> corner(mesh.num_vertices(), 0);
  if (!surface.has_border() || !(length > 0)) return corner;
  const auto along = [&](int a, int b) {
    const Eigen::Vector3d mid = 0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose();
    return distance_to_border(surface, mid, std::numeric_limits<double>::infinity()) <= o.border_chord_tolerance * length;
  };
  for (int v = 0; v < mesh.num_vertices(); ++v)
    corner[v] = border.simple(v) && border_turn(mesh, border, v) > o.known_border_corner_turn_deg * kDegree &&
                along(border.prev[v], v) && along(v, border.next[v]);
  return corner;
}

// One pass of edge collapses: the edges shorter than `limit`, shortest first, at most `budget`
// (< 0: no limit), none at a frozen vertex or within the ring of an earlier one.
class Collapser {
 public:
  Collapser(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o,
            const std::vector<char>& frozen, double long_limit)
      : mesh_(mesh), surface_(surface), o_(o), long_limit_(long_limit), vf_(mesh.vertex_faces()),
        border_(border_links(mesh)), touched_(frozen), dead_(mesh.num_faces(), 0),
        known_corners_(std::isfinite(long_limit) ? known_border_corners(mesh, surface, border_, o, long_limit / o.long_factor)
                                                 : std::vector<char>()) {
    touched_.resize(mesh.num_vertices(), 0);
  }

  int run(double limit, int budget) {
    std::vector<Edge> edges = mesh_edges(mesh_, o_);
    sort_edges(edges, false);
    int done = 0;
    for (const Edge& e : edges) {
      if (!(e.length < limit) || (budget >= 0 && done >= budget)) break;
      if (!touched_[e.a] && !touched_[e.b] && try_collapse(e.a, e.b)) ++done;
    }
    if (done > 0) mesh_.remove_faces(dead_);
    return done;
  }

  /// Collapses each spike of the border (a simple border vertex with more than one face whose
  /// surface angle is below spike_angle_deg) into its nearer border neighbour.
  int run_spikes(const std::vector<double>& surface_angle) {
    int done = 0;
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      if (touched_[v] || !border_.simple(v) || vf_[v].size() < 2 || !(surface_angle[v] < o_.spike_angle_deg * kDegree))
        continue;
      const int p = border_.prev[v], n = border_.next[v];
      const bool p_first = (mesh_.V.row(p) - mesh_.V.row(v)).norm() <= (mesh_.V.row(n) - mesh_.V.row(v)).norm();
      for (int keep : {p_first ? p : n, p_first ? n : p})
        if (!touched_[keep] && try_collapse(keep, v, keep)) {
          ++done;
          break;
        }
    }
    if (done > 0) mesh_.remove_faces(dead_);
    return done;
  }

 private:
  bool corner(int v) const {
    return border_turn(mesh_, border_, v) > o_.corner_turn_deg * kDegree ||
           (v < static_cast<int>(known_corners_.size()) && known_corners_[v]);
  }

  // Which vertex stays (`keep`) and where, or false when the edge must not collapse.
  bool choose(int a, int b, bool border_edge, int& keep, Eigen::Vector3d& pos, Eigen::Vector3d& nrm, int& hint) const {
    if (keep >= 0) {  // forced
      pos = mesh_.V.row(keep).transpose();
      nrm = mesh_.N.row(keep).transpose();
      hint = mesh_.anchor[keep];
      return true;
    }
    const bool on_a = border_.on(a), on_b = border_.on(b);
    if (!border_edge && on_a && on_b) return false;  // would pinch the surface
    if (border_edge && ((!border_.simple(a) || corner(a)) && (!border_.simple(b) || corner(b)))) return false;
    keep = a;
    if (border_edge) {
      if (!border_.simple(a) || corner(a)) keep = a;
      else if (!border_.simple(b) || corner(b)) keep = b;
      else keep = -1;  // both free: the midpoint
    } else if (on_a || on_b) {
      keep = on_a ? a : b;
    } else {
      keep = -1;
    }
    if (keep >= 0) {
      pos = mesh_.V.row(keep).transpose();
      nrm = mesh_.N.row(keep).transpose();
      hint = mesh_.anchor[keep];
      return true;
    }
    keep = a;
    hint = mesh_.anchor[a];
    const Eigen::Vector3d mid = 0.5 * (mesh_.V.row(a) + mesh_.V.row(b)).transpose();
    if (!border_edge || !surface_.project_to_border(mid, pos, nrm)) surface_.project(mid, hint, pos, nrm);
    return pos.allFinite() && nrm.allFinite();
  }

  // Where the surface's border is known, a border edge's collapse (its vertex at `pos`) must
  // not cut across a corner of it: refused where a border edge it makes has its midpoint farther
  // from that border than border_chord_tolerance target lengths and than the edges it replaces.
  bool keeps_border_chords(int a, int b, const Eigen::Vector3d& pos) const {
    if (!surface_.has_border()) return true;
    if (border_.next[b] == a) std::swap(a, b);
    if (border_.next[a] != b || border_.prev[a] < 0 || border_.next[b] < 0) return true;
    const auto gap = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
      return distance_to_border(surface_, 0.5 * (x + y));
    };
    const auto P = [&](int v) { return Eigen::Vector3d(mesh_.V.row(v).transpose()); };
    const int p = border_.prev[a], n = border_.next[b];
    const double before = std::max({gap(P(p), P(a)), gap(P(a), P(b)), gap(P(b), P(n))});
    const double after = std::max(gap(P(p), pos), gap(pos, P(n)));
    return after <= std::max(before, o_.border_chord_tolerance * long_limit_ / o_.long_factor);
  }

  // Link condition and valences: the opposite vertices of the edge are its only common
  // neighbours and keep enough edges, and the merged vertex keeps a proper fan.
  bool topology_allows(int a, int b, const std::vector<int>& shared, bool border_edge) const {
    if (static_cast<int>(shared.size()) != (border_edge ? 1 : 2)) return false;
    std::set<int> na, common;
    for (int g : vf_[a])
      for (int v : mesh_.face(g))
        if (v != a && v != b) na.insert(v);
    for (int g : vf_[b])
      for (int v : mesh_.face(g))
        if (v != a && v != b && na.count(v)) common.insert(v);
    if (common.size() != shared.size()) return false;
    for (int g : shared) {
      const int c = third_vertex(mesh_.face(g), a, b);
      if (!common.count(c) || mesh_.valence(c) <= (border_.on(c) ? 2 : 3)) return false;
    }
    const size_t merged = vf_[a].size() + vf_[b].size() - 2 * shared.size();
    return merged >= (border_edge || border_.on(a) || border_.on(b) ? 1u : 3u);
  }

  // Collapses the edge (a, b) (keeping `forced_keep` in place when given); false when refused.
  bool try_collapse(int a, int b, int forced_keep = -1) {
    const bool border_edge = !mesh_.has_half_edge(a, b) || !mesh_.has_half_edge(b, a);
    std::vector<int> shared, ring;
    for (int g : vf_[a]) {
      const MeshFace& h = mesh_.face(g);
      (h[0] == b || h[1] == b || h[2] == b ? shared : ring).push_back(g);
    }
    for (int g : vf_[b]) {
      const MeshFace& h = mesh_.face(g);
      if (!(h[0] == a || h[1] == a || h[2] == a)) ring.push_back(g);
    }
    if (!topology_allows(a, b, shared, border_edge)) return false;
    int keep = forced_keep, hint = -1;
    Eigen::Vector3d pos, nrm;
    if (!choose(a, b, border_edge, keep, pos, nrm, hint) || (border_edge && !keeps_border_chords(a, b, pos)))
      return false;
    const int gone = keep == a ? b : a;
    const double min_cos = std::cos(o_.max_normal_turn_deg * kDegree);
    for (int g : ring) {
      const MeshFace& h = mesh_.face(g);
      Eigen::Vector3d p[3];
      for (int q = 0; q < 3; ++q) p[q] = (h[q] == a || h[q] == b) ? pos : Eigen::Vector3d(mesh_.V.row(h[q]));
      const Eigen::Vector3d old_n = (mesh_.V.row(h[1]) - mesh_.V.row(h[0])).cross(mesh_.V.row(h[2]) - mesh_.V.row(h[0])).transpose();
      const Eigen::Vector3d new_n = (p[1] - p[0]).cross(p[2] - p[0]);
      if (!(new_n.norm() > 0) || !(old_n.norm() > 0) || new_n.normalized().dot(old_n.normalized()) < min_cos) return false;
      for (int q = 0; q < 3; ++q)
        if ((h[q] == a || h[q] == b) && !(relative_length(o_, p[(q + 1) % 3], pos) <= long_limit_ &&
                                          relative_length(o_, p[(q + 2) % 3], pos) <= long_limit_))
          return false;
    }
    mesh_.V.row(keep) = pos.transpose();
    mesh_.N.row(keep) = nrm.transpose();
    mesh_.anchor[keep] = hint;
    for (int g : shared) {
      dead_[g] = 1;
      touched_[third_vertex(mesh_.face(g), a, b)] = 1;
    }
    for (int g : ring) {
      MeshFace h = mesh_.face(g);
      for (int& v : h)
        if (v == gone) v = keep;
      mesh_.replace_face(g, h);
      for (int v : h) touched_[v] = 1;
    }
    touched_[a] = touched_[b] = 1;
    return true;
  }

  WorkingMesh& mesh_;
  const SurfaceProjector& surface_;
  const IsotropicRemeshOptions& o_;
  const double long_limit_;
  const std::vector<std::vector<int>> vf_;
  const BorderLinks border_;
  std::vector<char> touched_, dead_;
  const std::vector<char> known_corners_;  // known_border_corners()
};

// Valence each vertex should have: 6 inside; on a simple border 1 + the number of 60° sectors of
// the surface's angle there (4 on a straight border); pinched vertices keep theirs.
std::vector<int> target_valences(const WorkingMesh& mesh) {
  const BorderLinks border = border_links(mesh);
  const std::vector<double> angle = vertex_angle_sums(mesh);
  std::vector<int> target(mesh.num_vertices(), 6);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!border.on(v)) continue;
    target[v] = border.simple(v) ? 1 + std::max(1, static_cast<int>(std::lround(angle[v] / (M_PI / 3)))) : mesh.valence(v);
  }
  return target;
}

// Cuts the faces that cover a corner of the surface's own border, where that border is known (none
// at a frozen vertex): a face with one border edge a→b whose midpoint is farther than
// border_chord_tolerance target lengths (`length`) from that border, and whose third vertex c,
// inside the mesh, is on it (within border_tolerance). Without the face the border runs a→c→b,
// along the surface's (as a coarse dual leaves it over a hole narrower than two spacings).
int cut_corner_faces(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o,
                     const std::vector<char>& frozen, double length) {
  if (!surface.has_border() || !(length > 0)) return 0;
  const BorderLinks border = border_links(mesh);
  const auto gap = [&](const Eigen::Vector3d& x) { return distance_to_border(surface, x) / length; };
  const auto P = [&](int v) { return Eigen::Vector3d(mesh.V.row(v).transpose()); };
  std::vector<char> drop(mesh.num_faces(), 0), touched = frozen;
  touched.resize(mesh.num_vertices(), 0);
  int cut = 0;
  for (int g = 0; g < mesh.num_faces(); ++g) {
    const MeshFace& f = mesh.face(g);
    int k = -1, border_edges = 0;
    for (int q = 0; q < 3; ++q)
      if (!mesh.has_half_edge(f[(q + 1) % 3], f[q])) k = q, ++border_edges;
    if (border_edges != 1) continue;
    const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
    if (touched[a] || touched[b] || touched[c] || border.on(c)) continue;
    const double chord = gap(0.5 * (P(a) + P(b)));
    if (!(chord > o.border_chord_tolerance) || !(gap(P(c)) <= o.border_tolerance)) continue;
    if (!(std::max(gap(0.5 * (P(a) + P(c))), gap(0.5 * (P(c) + P(b)))) < chord)) continue;
    drop[g] = 1;
    touched[a] = touched[b] = touched[c] = 1;
    ++cut;
  }
  if (cut > 0) mesh.remove_faces(drop);
  return cut;
}

// Cuts the ears of the border (none at a frozen vertex): faces whose corner v is on the border with no other face and an
// angle below ear_angle_deg there; the other two corners keep their faces.
int cut_ears(WorkingMesh& mesh, const IsotropicRemeshOptions& o, const std::vector<char>& frozen) {
  const std::vector<std::vector<int>> vf = mesh.vertex_faces();
  std::vector<char> drop(mesh.num_faces(), 0), touched = frozen;
  int cut = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (vf[v].size() != 1 || touched[v]) continue;
    const int g = vf[v][0];
    const MeshFace& f = mesh.face(g);
    int k = 0;
    while (f[k] != v) ++k;
    const int b = f[(k + 1) % 3], c = f[(k + 2) % 3];
    if (touched[b] || touched[c] || vf[b].size() < 2 || vf[c].size() < 2 || mesh.edge_face_count(b, c) != 2) continue;
    const Eigen::Vector3d e1 = mesh.V.row(b) - mesh.V.row(v), e2 = mesh.V.row(c) - mesh.V.row(v);
    if (!(e1.norm() > 0 && e2.norm() > 0)) continue;
    if (std::acos(std::clamp(e1.normalized().dot(e2.normalized()), -1.0, 1.0)) >= o.ear_angle_deg * kDegree) continue;
    drop[g] = 1;
    touched[v] = touched[b] = touched[c] = 1;
    ++cut;
  }
  if (cut > 0) mesh.remove_faces(drop);
  return cut;
}

// Closes the notches of the border (none at a frozen vertex): a simple border vertex v whose two border edges v→prev and
// v→next make an angle below notch_angle_deg, with the surface on the far side (surface angle
// above π), gets the face (v, prev, next) when it faces like v's normal. Returns the faces added.
int fill_notches(WorkingMesh& mesh, const IsotropicRemeshOptions& o, const std::vector<char>& frozen) {
  const BorderLinks border = border_links(mesh);
  const std::vector<double> angle = vertex_angle_sums(mesh);
  std::vector<char> touched = frozen;
  int added = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!border.simple(v) || !(angle[v] > M_PI)) continue;
    const int p = border.prev[v], n = border.next[v];
    if (p == n || touched[v] || touched[p] || touched[n]) continue;
    const Eigen::Vector3d x = mesh.V.row(v), a = mesh.V.row(p), b = mesh.V.row(n);
    if (!((a - x).norm() > 0 && (b - x).norm() > 0)) continue;
    if (std::acos(std::clamp((a - x).normalized().dot((b - x).normalized()), -1.0, 1.0)) >= o.notch_angle_deg * kDegree)
      continue;
    // (v, p, n) holds v→p, p→n, n→v: the first and last pair with the border half-edges p→v, v→n.
    if (mesh.has_half_edge(p, n) || mesh.edge_face_count(p, n) > 1) continue;
    const Eigen::Vector3d fn = (a - x).cross(b - x);
    if (!(fn.norm() > 0) || !(fn.normalized().dot(mesh.N.row(v).transpose()) > 0.5)) continue;
    mesh.add_face({v, p, n});
    touched[v] = touched[p] = touched[n] = 1;
    ++added;
  }
  return added;
}

// Edge length of equilateral triangles that give the target count on the mesh's area
// (V ≈ 2A / (√3 L²)); with a sizing field, the uniform length L whose local lengths L·g give it
// (each face's area counted over g² at its centroid).
double target_length(const WorkingMesh& mesh, const IsotropicRemeshOptions& o) {
  double area = 0;
  for (const MeshFace& f : mesh.faces()) {
    const double a = 0.5 * (mesh.V.row(f[1]) - mesh.V.row(f[0])).cross(mesh.V.row(f[2]) - mesh.V.row(f[0])).norm();
    const double g = relative_size_at(o, (mesh.V.row(f[0]) + mesh.V.row(f[1]) + mesh.V.row(f[2])).transpose() / 3.0);
    area += a / (g * g);
  }
  return o.target_vertices > 0 ? std::sqrt(2.0 * area / (std::sqrt(3.0) * o.target_vertices)) : 0.0;
}

// Largest distances, in target edge lengths, from a border vertex to the surface's own border
// (`vertex_gap`), among the border vertices within max_border_gap target lengths of it (the others
// are on holes of the mesh, not of the surface), and from the midpoint of a border edge between
// two of those to it (`chord_gap`); 0 where the surface has no known border.
void border_gaps(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o,
                 double& vertex_gap, double& chord_gap) {
  vertex_gap = chord_gap = 0;
  if (!surface.has_border() || mesh.empty()) return;
  const double length = target_length(mesh, o);
  const BorderLinks border = border_links(mesh);
  const auto gap = [&](const Eigen::Vector3d& x) {
    return distance_to_border(surface, x, std::numeric_limits<double>::infinity()) / length;
  };
  std::vector<char> near(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!border.on(v)) continue;
    const double d = gap(mesh.V.row(v).transpose());
    near[v] = d <= o.max_border_gap;
    if (near[v]) vertex_gap = std::max(vertex_gap, d);
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const int w = border.on(v) ? border.next[v] : -1;
    if (w >= 0 && near[v] && near[w]) chord_gap = std::max(chord_gap, gap(0.5 * (mesh.V.row(v) + mesh.V.row(w)).transpose()));
  }
}

// The sizing's steps on one mesh, each tried and, where it makes faces cross, redone from the same
// start with the vertices around the crossing faces frozen (the way the mesher's other stages
// treat the intersections they make).
class Sizer {
 public:
  Sizer(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o, MesherStats& stats)
      : mesh_(mesh), surface_(surface), o_(o), stats_(stats), frozen_(mesh.num_vertices(), 0),
        tips_(tip_vertices(mesh, o.tips)) {
    crossing_pairs_ = crossing_face_pairs(mesh);
    crossings_ = faces_in_pairs(mesh, crossing_pairs_);  // faces crossing already are left alone
    freeze_around(crossings_);
  }

  // With `reshape`, the border cleaning and the remeshing rounds; then the count adjusted and
  // the polish (all that a mesh of the right shape but the wrong count gets).
  void run(bool reshape) {
    double& length = length_;
    length = target_length(mesh_, o_);
    if (reshape) {
      attempt([&] { return snap_border(); });
      clean_border();
      for (int round = 0; round < o_.rounds && length > 0; ++round) {
        attempt([&] {
          const int splits = split_edges(mesh_, surface_, o_, frozen(), o_.long_factor * length, -1);
          const int collapses =
              Collapser(mesh_, surface_, o_, frozen_or_tips(), o_.long_factor * length).run(o_.short_factor * length, -1);
          flip_and_relax();
          return splits + collapses;
        });
        // Borders and pieces make the equilateral estimate off: correct it by the count reached.
        length *= std::sqrt(static_cast<double>(vertices_in_faces(mesh_)) / o_.target_vertices);
      }
      clean_border();
    }
    // A mesh of the right shape keeps it away from the vertices the count adjustment adds: only
    // their two rings are flipped, relaxed and polished.
    local_ = !reshape;
    adjust_count(o_.long_factor * length);
    attempt([&] { return final_polish(); });
    local_ = false;
    sliver_passes(length);
  }

 private:
  // Slivers the polish could not open: flipped over creases and folds, the notches of the border
  // closed (where surface may be added), those flat along the border, the sliver ears, spikes
  // and the slivers across ribbons one triangle wide trimmed, the others' shortest edges
  // collapsed (border edges and interior vertices into border ones too); the pieces they cut off
  // removed, the count restored and polished once more; repeated while
  // slivers are left, as each polish can expose new ones. Each pass starts with only the regions
  // around faces crossing now frozen. A later pass may end with a smaller φmin than an earlier
  // one: the state with the largest φmin (among those with the count within count_aim) is kept.
  // The slivers it still has get the best of their local edits, with no polish after it to undo
  // them (repair_slivers() only makes edits that raise the smallest angle around a sliver).
  void sliver_passes(double length) {
    struct State {
      WorkingMesh::Checkpoint mesh;
      MesherStats stats;
      std::vector<int> crossings;
      std::vector<FacePair> crossing_pairs;
      double min_angle;
    };
    State best{mesh_.checkpoint(), stats_, crossings_, crossing_pairs_, smallest_angle()};
    for (int pass = 0; pass < o_.sliver_passes && figures_below_target(); ++pass) {
      thaw();
      // Each kind of edit is its own attempt: a collapse that makes faces cross costs neither
      // the flips nor the trims elsewhere.
      int changed = attempt([&] {
        const int flipped = flip_sliver_edges(mesh_, surface_, o_.sliver_flips, frozen());
        stats_.flipped_edges += flipped;
        return flipped;
      });
      if (o_.fill_notches) changed += attempt([&] { return fill_notches(mesh_, o_, frozen()); });
      changed += attempt([&] {
        const int trimmed = trim_boundary_slivers(mesh_, o_.border_slivers);
        stats_.trimmed_faces += trimmed;
        return trimmed;
      });
      changed += attempt([&] {
        const int collapsed = collapse_slivers(mesh_, surface_, o_.slivers, stats_, &frozen());
        stats_.collapsed_edges += collapsed;
        return collapsed;
      });
      stats_.removed_triangles +=
          remove_small_pieces(mesh_, o_.min_piece_faces, o_.min_piece_vertex_fraction, &stats_.pieces_removed);
      if (changed == 0) break;
      adjust_count(o_.long_factor * length);
      attempt([&] { return final_polish(); });
      const double now = smallest_angle();
      if (now > best.min_angle && count_within_aim()) best = {mesh_.checkpoint(), stats_, crossings_, crossing_pairs_, now};
    }
    if (smallest_angle() < best.min_angle) {
      mesh_.rollback(best.mesh);
      stats_ = best.stats;
      crossings_ = best.crossings;
      crossing_pairs_ = best.crossing_pairs;
    }
    // The repairs, then the cut of what they leave; the count the cut restores can leave new
    // slivers, which get the repairs and the cut again (at most cut_rounds times).
    const int floor = count_floor(o_);
    for (int round = 0; round <= o_.cut_rounds && figures_below_target(); ++round) {
      thaw();
      attempt([&] { return repair_slivers(mesh_, surface_, o_.repair, frozen(), floor); });
      // Where an edit of that repair made faces cross, the whole repair was undone and its region
      // frozen: the slivers left there get the best edit that makes none cross, one at a time.
      if (o_.repair_without_crossings && figures_below_target()) {
        thaw();
        attempt([&] {
          return repair_slivers_without_crossings(mesh_, surface_, o_.repair, frozen(), floor, crossing_pairs_);
        });
      }
      // An input mesh (its border known) is whole where the mesh is cut: only a sampling's
      // surface may lose its slivers.
      if (round == o_.cut_rounds || !o_.cut_unrepairable || o_.keep_topology.enabled() || surface_.border_known() ||
          !figures_below_target() || !cut_slivers_left(floor))
        break;
    }
  }

  // The slivers that no edit could raise are cut out (cut_unrepairable_slivers()) with the pieces
  // that leaves too small; where the count falls below `floor`, it is restored by splits whose
  // two rings alone are polished. Undone where the count stays below `floor`, fewer faces are
  // not left below the target angle, or the smallest angle falls. Returns whether it was kept.
  bool cut_slivers_left(int floor) {
    const WorkingMesh::Checkpoint before = mesh_.checkpoint();
    const MesherStats stats_before = stats_;
    const double angle_before = smallest_angle();
    const int slivers_before = faces_below_target();
    const int cut = cut_unrepairable_slivers(mesh_, o_);
    if (cut == 0) return false;
    stats_.trimmed_faces += cut;
    stats_.removed_triangles +=
        remove_small_pieces(mesh_, o_.min_piece_faces, o_.min_piece_vertex_fraction, &stats_.pieces_removed);
    crossings_ = faces_in_pairs(mesh_, crossing_pairs_ = crossing_face_pairs(mesh_));
    if (vertices_in_faces(mesh_) < floor) {
      thaw();
      local_ = true;
      adjust_count(o_.long_factor * length_);
      attempt([&] { return final_polish(); });
      local_ = false;
    }
    if (vertices_in_faces(mesh_) >= floor && faces_below_target() < slivers_before && smallest_angle() >= angle_before)
      return true;
    mesh_.rollback(before);
    stats_ = stats_before;
    crossings_ = faces_in_pairs(mesh_, crossing_pairs_ = crossing_face_pairs(mesh_));
    return false;
  }

  double smallest_angle() const {
    double m = M_PI;
    for (const MeshFace& f : mesh_.faces()) m = std::min(m, face_min_angle(mesh_, f));
    return m;
  }

  bool count_within_aim() const {
    const int slack = std::max(0, static_cast<int>(std::floor(o_.count_aim * o_.count_tolerance * o_.target_vertices)));
    return std::abs(vertices_in_faces(mesh_) - o_.target_vertices) <= slack;
  }

  bool figures_below_target() const { return faces_below_target() > 0; }

  int faces_below_target() const {
    int n = 0;
    for (const MeshFace& f : mesh_.faces()) n += face_min_angle(mesh_, f) < o_.min_angle_deg * kDegree;
    return n;
  }

  // Notches closed, spikes collapsed, ears cut: the border's noise at the site spacing.
  void clean_border() {
    for (int pass = 0; pass < 3; ++pass) {
      int changed = 0;
      if (o_.fill_notches) changed += attempt([&] { return fill_notches(mesh_, o_, frozen()); });
      changed += attempt([&] {
        return Collapser(mesh_, surface_, o_, frozen_or_tips(), std::numeric_limits<double>::infinity())
            .run_spikes(vertex_angle_sums(mesh_));
      });
      changed += attempt([&] { return cut_ears(mesh_, o_, frozen()); });
      changed += attempt([&] { return cut_corner_faces(mesh_, surface_, o_, frozen(), length_); });
      if (changed == 0) break;
    }
  }

  // Only the faces crossing now and their neighbours stay frozen: the regions frozen where an
  // earlier step made faces cross are opened again (a later step on the changed mesh may succeed
  // there), as are those around crossings the steps have removed.
  void thaw() {
    frozen_.assign(mesh_.num_vertices(), 0);
    freeze_around(crossings_);
  }

  const std::vector<char>& frozen() {
    frozen_.resize(mesh_.num_vertices(), 0);
    return frozen_;
  }

  // The vertices the flips, the relaxation and the polish leave alone: the frozen ones and, in
  // the local count adjustment, those outside the two rings of the vertices it added.
  std::vector<char> held() {
    std::vector<char> h = frozen();
    if (local_) {
      active_.resize(mesh_.num_vertices(), 0);
      for (int v = 0; v < mesh_.num_vertices(); ++v) h[v] = h[v] || !active_[v];
    }
    return h;
  }

  // `marks` with the tips the sizing started with marked too.
  std::vector<char> with_tips(std::vector<char> marks) const {
    for (std::size_t v = 0; v < tips_.size() && v < marks.size(); ++v) marks[v] = marks[v] || tips_[v];
    return marks;
  }

  // The frozen vertices and the tips: no edge at them collapses.
  std::vector<char> frozen_or_tips() { return with_tips(frozen()); }

  // The held vertices, the tips and the corners of the surface's known border
  // (known_border_corners()): the vertices the relaxation and the angle polish leave in place.
  std::vector<char> held_and_corners() {
    std::vector<char> h = with_tips(held());
    const std::vector<char> corners = known_border_corners(mesh_, surface_, border_links(mesh_), o_, length_);
    for (int v = 0; v < mesh_.num_vertices(); ++v) h[v] = h[v] || corners[v];
    return h;
  }

  // Marks the two rings of the vertices from index `first` on as active.
  void activate_from(int first) {
    std::vector<char> ring(mesh_.num_vertices(), 0);
    for (int v = first; v < mesh_.num_vertices(); ++v) ring[v] = 1;
    for (int r = 0; r < 2; ++r) {
      std::vector<char> next = ring;
      for (const MeshFace& f : mesh_.faces())
        if (ring[f[0]] || ring[f[1]] || ring[f[2]]) next[f[0]] = next[f[1]] = next[f[2]] = 1;
      ring.swap(next);
    }
    active_.resize(mesh_.num_vertices(), 0);
    for (int v = 0; v < mesh_.num_vertices(); ++v) active_[v] = active_[v] || ring[v];
  }

  // Vertices with no held vertex in their one-ring: a flip of an edge at one of them changes
  // only faces of vertices that may change.
  std::vector<char> flippable() {
    std::vector<char> ok(mesh_.num_vertices(), 1);
    const std::vector<char> fz = held();
    for (const MeshFace& f : mesh_.faces())
      if (fz[f[0]] || fz[f[1]] || fz[f[2]]) ok[f[0]] = ok[f[1]] = ok[f[2]] = 0;
    return ok;
  }

  // The mesh's topology where one is to be kept (o_.keep_topology), else the unset one.
  TopologyTarget topology_of_if_kept() const { return o_.keep_topology.enabled() ? topology_of(mesh_) : TopologyTarget(); }

  // The faces with a corner among `vertices`.
  std::vector<int> faces_at(const std::vector<int>& vertices) const {
    std::vector<char> in(mesh_.num_vertices(), 0);
    for (int v : vertices) in[v] = 1;
    std::vector<int> faces;
    for (int f = 0; f < mesh_.num_faces(); ++f) {
      const MeshFace& t = mesh_.face(f);
      if (in[t[0]] || in[t[1]] || in[t[2]]) faces.push_back(f);
    }
    return faces;
  }

  // Freezes the vertices of `faces` and of every face touching them.
  void freeze_around(const std::vector<int>& faces) {
    std::vector<char> in(mesh_.num_vertices(), 0);
    for (int f : faces)
      for (int v : mesh_.face(f)) in[v] = 1;
    frozen_.resize(mesh_.num_vertices(), 0);
    for (const MeshFace& f : mesh_.faces())
      if (in[f[0]] || in[f[1]] || in[f[2]])
        for (int v : f) frozen_[v] = 1;
  }

  // Runs `step` (which returns how much it changed); where it makes more faces cross than
  // crossed before, or breaks the topology to keep (o_.keep_topology), undoes it
  // (counters too), freezes the region and runs it again, at most three times, then leaves the
  // step out. Returns what the kept run changed (0 if none).
  template <class Step>
  int attempt(Step step) {
    throw_if_cancelled(o_.cancelled);
    for (int tries = 0; tries < 3; ++tries) {
      const WorkingMesh::Checkpoint before = mesh_.checkpoint();
      const MesherStats stats_before = stats_;
      const TopologyTarget topology_before = topology_of_if_kept();
      const int changed = step();
      // A step that left the mesh as it was cannot have made faces cross.
      if (mesh_.V == before.V && mesh_.faces() == before.faces) return changed;
      // Only the faces the step made or moved are checked again (crossing_face_pairs_after()).
      std::vector<FacePair> bad_pairs = crossing_face_pairs_after(mesh_, before, crossing_pairs_);
      std::vector<int> bad = faces_in_pairs(mesh_, bad_pairs);
      const bool broken = breaks_topology(o_.keep_topology, topology_before, topology_of_if_kept());
      if (bad.size() <= crossings_.size() && !broken) {
        crossings_ = std::move(bad);  // what the next step is measured against
        crossing_pairs_ = std::move(bad_pairs);
        return changed;
      }
      freeze_around(bad);
      frozen_.resize(before.V.rows());  // vertices added by the step are gone again
      WorkingMesh changed_mesh;
      if (broken) changed_mesh = mesh_;  // the loops it lost are found against the state rolled back to
      mesh_.rollback(before);
      stats_ = stats_before;
      if (broken) {
        std::vector<int> loops_before;
        boundary_loop_labels(mesh_, loops_before);
        freeze_around(faces_at(lost_loop_vertices(changed_mesh, loops_before)));
      }
    }
    return 0;
  }

  // Valence flips towards target_valences(), then a relaxation step with the border sliding (or
  // following the samples' border where it is near).
  void flip_and_relax() {
    FlipOptions f = o_.flips;
    f.valence_mode = true;
    f.max_passes = 3;
    const std::vector<int> target = target_valences(mesh_);
    const std::vector<char> movable = flippable();
    stats_.flipped_edges += flip_edges(mesh_, f, &movable, &target);
    RelaxationBorder border;
    border.slide = true;
    border.follow_sample_border = o_.follow_sample_border;
    border.corner_turn_deg = o_.corner_turn_deg;
    const std::vector<char> fixed = held_and_corners();
    tangential_relaxation(mesh_, surface_, o_.threads, border, &fixed);
    snap_border();
  }

  // Border vertices within max_border_gap target lengths of the surface's own border (an input
  // mesh's boundary) are moved onto it: the output's border loops run on the input's.
  int snap_border() {
    if (!surface_.has_border()) return 0;
    const BorderLinks border = border_links(mesh_);
    const std::vector<char> fixed = held();
    int moved = 0;
    for (int v = 0; v < mesh_.num_vertices(); ++v) {
      if (!border.on(v) || fixed[v]) continue;
      Eigen::Vector3d pos, nrm;
      const Eigen::Vector3d x = mesh_.V.row(v);
      if (!surface_.project_to_border(x, pos, nrm) || !((pos - x).norm() <= o_.max_border_gap * length_)) continue;
      mesh_.V.row(v) = pos.transpose();
      mesh_.N.row(v) = nrm.transpose();
      ++moved;
    }
    return moved;
  }

  // Splits the longest or collapses the shortest edges until the count is within count_aim ×
  // count_tolerance of the target (or nothing more can be done).
  void adjust_count(double long_limit) {
    const double base_limit = long_limit;
    const int target = o_.target_vertices;
    const int slack = std::max(0, static_cast<int>(std::floor(o_.count_aim * o_.count_tolerance * target)));
    for (int round = 0; round < 12; ++round) {
      const int diff = target - vertices_in_faces(mesh_);
      if (std::abs(diff) <= slack) break;
      const int changed = attempt([&] {
        const int first = mesh_.num_vertices();
        const int n = diff > 0 ? split_edges(mesh_, surface_, o_, frozen(), 0.0, diff)
                               : Collapser(mesh_, surface_, o_, frozen_or_tips(), long_limit)
                                     .run(std::numeric_limits<double>::infinity(), -diff);
        if (diff > 0) activate_from(first);
        else local_ = false;  // a collapse leaves no new vertex to mark: polish everywhere
        flip_and_relax();
        return n;
      });
      // Collapses stall where every ring would get an edge above the limit (a mesh far above
      // the target on a small area): the limit grows, up to max_collapse_growth times.
      if (diff < 0 && changed < -diff / 2 && long_limit < o_.max_collapse_growth * base_limit)
        long_limit *= 1.25;
      else if (changed == 0)
        break;
    }
  }

  // Max-min-angle flips and angle polish, as the mesher's polish does; returns the moves and flips.
  int final_polish() {
    FlipOptions f = o_.flips;
    f.valence_mode = false;
    f.max_passes = 5;
    const std::vector<char> movable = flippable();
    bool converged = false;
    int flips = flip_edges(mesh_, f, &movable, nullptr, nullptr, &converged), moves = 0;
    const std::vector<char> fixed = held_and_corners();
    std::vector<char>& settled = settled_since_last_polish();
    for (int cycle = 0; cycle < o_.polish_cycles; ++cycle) {
      const WorkingMesh::Checkpoint unpolished = mesh_.checkpoint();
      moves += angle_polish(mesh_, surface_, 2, fixed, o_.angle, o_.threads, &settled);
      const std::vector<MeshFace> unflipped = mesh_.faces();
      // After a converged call, only the edges near the vertices the polish moved can flip.
      const std::vector<char> dirty = converged ? moved_vertex_rings(mesh_, unpolished) : std::vector<char>();
      flips += flip_edges(mesh_, f, &movable, nullptr, converged ? &dirty : nullptr, &converged);
      unsettle_changed_faces(unflipped, mesh_, settled);
    }
    polished_ = mesh_.checkpoint();  // the marks hold for this state; the snap below is a change
    moves += snap_border();
    stats_.flipped_edges += flips;
    return flips + moves;
  }

  // The angle polish's `settled` marks (angle_polish()) as the last final_polish() left them,
  // cleared where the mesh has changed since (unsettle_changes_since()): the polish that follows
  // is the same as one that searches every vertex, at the cost of the changes only (the sliver
  // passes polish the whole mesh after a few local edits). A step rolled back counts as a change
  // from the state it left, so the marks stay right.
  std::vector<char>& settled_since_last_polish() {
    if (polished_.V.rows() == 0) settled_.assign(mesh_.num_vertices(), 0);
    else unsettle_changes_since(polished_, mesh_, settled_);
    return settled_;
  }

  WorkingMesh& mesh_;
  const SurfaceProjector& surface_;
  const IsotropicRemeshOptions& o_;
  MesherStats& stats_;
  std::vector<char> frozen_;
  const std::vector<char> tips_;  // tip_vertices() of the mesh the sizing started from
  std::vector<int> crossings_;
  std::vector<FacePair> crossing_pairs_;  // the pairs of crossings_, by their corners
  double length_ = 0;          // the target edge length, corrected by the count each round
  bool local_ = false;         // count adjustment on a mesh of the right shape: see held()
  std::vector<char> active_;   // vertices near those the local count adjustment added
  WorkingMesh::Checkpoint polished_;  // the mesh as the last final_polish() left it
  std::vector<char> settled_;         // its angle polish marks (settled_since_last_polish())
};

// The border's vertices are on the surface's border within border_tolerance and its edges'
// midpoints within border_chord_tolerance.
bool border_fits(const SizingFigures& q, const IsotropicRemeshOptions& o) {
  return q.border_gap <= o.border_tolerance && q.border_chord_gap <= o.border_chord_tolerance;
}

// A mesh misses a shape target, or its count is off by more than reshape_count_error.
bool reshapes(const SizingFigures& q, const IsotropicRemeshOptions& o) {
  const bool shape_met = q.min_angle >= o.min_angle_deg * kDegree && q.mean_angle >= o.mean_angle_deg * kDegree &&
                         border_fits(q, o);
  const bool count_near = std::abs(q.vertices - o.target_vertices) <= o.reshape_count_error * o.target_vertices;
  return !(shape_met && count_near);
}

}  // namespace

int remove_flying_faces(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o) {
  // Only pieces with a border: a closed piece encloses a volume and spans no depth jump (its
  // steep faces are caps of thin parts, which stay).
  const FaceComponents pieces = face_components(mesh, true);
  const std::vector<char> open = open_pieces(mesh, pieces);
  std::vector<char> flying(mesh.num_faces(), 0);
  for (int id = 0; id < mesh.num_faces(); ++id) {
    const MeshFace& f = mesh.face(id);
    if (!open[pieces.of_face[id]]) continue;
    const Eigen::Vector3d a = mesh.V.row(f[0]), b = mesh.V.row(f[1]), c = mesh.V.row(f[2]);
    const double longest = std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()});
    Eigen::Vector3d pos, nrm;
    int hint = mesh.anchor[f[0]];
    const Eigen::Vector3d g = (a + b + c) / 3.0;
    surface.project(g, hint, pos, nrm);
    if (pos.allFinite() && (pos - g).norm() <= o.max_face_offset * longest) continue;
    // ... and stands across the surface: tilted from its corners' normals by more than
    // min_flying_tilt_deg (a coarse face over a curved part is off the surface but not across it).
    const Eigen::Vector3d fn = (b - a).cross(c - a);
    double facing = 0;
    for (int v : f) facing += std::abs(fn.normalized().dot(mesh.N.row(v).transpose())) / 3.0;
    flying[id] = !(fn.norm() > 0) || facing < std::cos(o.min_flying_tilt_deg * kDegree);
  }
  // Vertices left with several fans keep their largest (make_vertices_manifold()).
  const int removed = mesh.remove_faces(flying);
  return removed > 0 ? removed + make_vertices_manifold(mesh) : 0;
}

int cut_unrepairable_slivers(WorkingMesh& mesh, const IsotropicRemeshOptions& o) {
  // Open pieces, and closed ones with less than max_cut_closed_fraction of the vertices.
  const FaceComponents pieces = face_components(mesh, true);
  std::vector<char> cuttable = open_pieces(mesh, pieces);
  std::vector<int> piece_vertices(pieces.size.size(), 0);
  std::vector<char> seen(mesh.num_vertices(), 0);
  for (int id = 0; id < mesh.num_faces(); ++id)
    for (int v : mesh.face(id))
      if (!seen[v]) seen[v] = 1, ++piece_vertices[pieces.of_face[id]];
  const double small = o.max_cut_closed_fraction * vertices_in_faces(mesh);
  for (std::size_t p = 0; p < cuttable.size(); ++p) cuttable[p] = cuttable[p] || piece_vertices[p] < small;
  std::vector<char> cut(mesh.num_faces(), 0);
  for (int id = 0; id < mesh.num_faces(); ++id)
    cut[id] = cuttable[pieces.of_face[id]] && face_min_angle(mesh, mesh.face(id)) < o.min_angle_deg * kDegree;
  const int removed = mesh.remove_faces(cut);
  return removed > 0 ? removed + make_vertices_manifold(mesh) : 0;
}

SizingFigures sizing_figures(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& o) {
  SizingFigures q;
  border_gaps(mesh, surface, o, q.border_gap, q.border_chord_gap);
  q.vertices = vertices_in_faces(mesh);
  for (const MeshFace& f : mesh.faces()) {
    const double a = face_min_angle(mesh, f);
    q.min_angle = std::min(q.min_angle, a);
    q.mean_angle += a;
    q.below += a < o.min_angle_deg * kDegree;
  }
  if (!mesh.empty()) q.mean_angle /= mesh.num_faces(), q.below /= mesh.num_faces();
  return q;
}

bool sizing_no_worse(const SizingFigures& after, const SizingFigures& before, const IsotropicRemeshOptions& o) {
  const double count_slack = o.count_tolerance * o.target_vertices;
  const int err_after = std::abs(after.vertices - o.target_vertices), err_before = std::abs(before.vertices - o.target_vertices);
  const bool count = err_after <= count_slack || err_after <= err_before;
  // A border brought onto the surface's own border may cost up to border_fit_angle_slack_deg of
  // the angle figures: the inset border's triangles were shaped for a border that was not there.
  const bool border_fitted = !border_fits(before, o) && border_fits(after, o);
  const double slack = border_fitted ? o.border_fit_angle_slack_deg * kDegree : 0.0;
  const double target = o.min_angle_deg * kDegree;
  // A mesh off the count by more than count_first_error is mostly missing: its count comes
  // first, φmin may drop (φm may not).
  const bool count_first = err_before > o.count_first_error * o.target_vertices && err_after < err_before;
  const bool min_angle = count_first || (before.min_angle >= target ? after.min_angle >= target - slack
                                                                    : after.below <= before.below);
  // A mostly missing mesh made nearly whole may also lose a little φm, where its φmin holds up.
  const double mean_slack =
      count_first && after.min_angle >= o.traded_min_angle_deg * kDegree ? o.count_first_mean_slack_deg * kDegree : 0.0;
  const bool mean_angle =
      after.mean_angle >= std::min(before.mean_angle, o.mean_angle_deg * kDegree) - std::max(slack, mean_slack) - 1e-12;
  const bool border = after.border_gap <= std::max(before.border_gap, o.border_tolerance) &&
                      after.border_chord_gap <= std::max(before.border_chord_gap, o.border_chord_tolerance);
  if (count && min_angle && mean_angle && border) return true;
  // A result that meets more of the three targets (count, φmin, φm) than before is kept as long
  // as its φmin stays above traded_min_angle_deg and the border is no farther off.
  auto targets_met = [&](const SizingFigures& q, int err) {
    return (err <= count_slack) + (q.min_angle >= target) + (q.mean_angle >= o.mean_angle_deg * kDegree);
  };
  return border && targets_met(after, err_after) > targets_met(before, err_before) &&
         after.min_angle >= o.traded_min_angle_deg * kDegree;
}

bool sizing_reshapes(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options) {
  return reshapes(sizing_figures(mesh, surface, options), options);
}

int count_floor(const IsotropicRemeshOptions& options) {
  return static_cast<int>(std::ceil((1 - options.count_tolerance) * options.target_vertices));
}

bool needs_sizing(const WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options) {
  if (options.target_vertices <= 0 || mesh.empty()) return false;
  const SizingFigures q = sizing_figures(mesh, surface, options);
  return std::abs(q.vertices - options.target_vertices) >
             options.count_aim * options.count_tolerance * options.target_vertices ||
         q.min_angle < options.min_angle_deg * kDegree || q.mean_angle < options.mean_angle_deg * kDegree ||
         !border_fits(q, options);
}

bool size_to_target(WorkingMesh& mesh, const SurfaceProjector& surface, const IsotropicRemeshOptions& options,
                    MesherStats& stats) {
  if (!needs_sizing(mesh, surface, options)) return false;
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const SizingFigures figures_before = sizing_figures(mesh, surface, options);
  const MesherStats stats_before = stats;
  // A mesh of the right shape whose count is off by little only gets the count adjusted; where
  // that is worse on a target, it is remeshed as a whole instead.
  const bool reshape = reshapes(figures_before, options);
  for (const bool whole : {reshape, true}) {
    Sizer(mesh, surface, options, stats).run(whole);
    if (sizing_no_worse(sizing_figures(mesh, surface, options), figures_before, options)) return true;
    mesh.rollback(before);
    stats = stats_before;
    if (whole) break;
  }
  return false;
}

}  // namespace heatcvt
