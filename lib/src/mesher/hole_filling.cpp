// Hole filling of the extracted surface.
#include "heatcvt/mesher/hole_filling.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>
#include <utility>

#include "heatcvt/closest_point.h"
#include "heatcvt/point_index.h"
#include "heatcvt/mesher/hole_sites.h"
#include "heatcvt/mesher/mesh_checks.h"

namespace heatcvt {
namespace {

// The faces of a mesh near a point: a kd-tree over the face centroids (built on first use), searched
// within the radius plus the largest distance from a centroid to its corners.
class NearbyFaces {
 public:
  explicit NearbyFaces(const WorkingMesh& mesh) : mesh_(mesh) {}
  // Every face with a point within `radius` of x (and maybe a few farther), ascending.
  std::vector<int> within(const Eigen::Vector3d& x, double radius) {
    if (!index_) {
      Eigen::MatrixX3d centroid(mesh_.num_faces(), 3);
      for (int f = 0; f < mesh_.num_faces(); ++f) {
        const MeshFace& t = mesh_.face(f);
        centroid.row(f) = (mesh_.V.row(t[0]) + mesh_.V.row(t[1]) + mesh_.V.row(t[2])) / 3.0;
        for (int v : t) reach_ = std::max(reach_, (mesh_.V.row(v) - centroid.row(f)).norm());
      }
      index_ = std::make_unique<PointIndex>(centroid);
    }
    return index_->within(x, radius + reach_);
  }

 private:
  const WorkingMesh& mesh_;
  std::unique_ptr<PointIndex> index_;
  double reach_ = 0;
};

// Mean edge length of the loop.
double mean_edge_length(const WorkingMesh& mesh, const std::vector<int>& loop) {
  double h = 0;
  for (size_t i = 0; i < loop.size(); ++i) h += (mesh.V.row(loop[i]) - mesh.V.row(loop[(i + 1) % loop.size()])).norm();
  return h / static_cast<double>(loop.size());
}

// Mean position of the loop's vertices.
Eigen::Vector3d loop_centroid(const WorkingMesh& mesh, const std::vector<int>& loop) {
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int v : loop) g += mesh.V.row(v).transpose();
  return g / static_cast<double>(loop.size());
}

// Distance from `g` to the loop's farthest vertex.
double loop_radius(const WorkingMesh& mesh, const std::vector<int>& loop, const Eigen::Vector3d& g) {
  double radius = 0;
  for (int v : loop) radius = std::max(radius, (mesh.V.row(v).transpose() - g).norm());
  return radius;
}

// The loop's centre is away from every triangle (> clearance·h) but near the sampled surface.
bool is_sampled_hole(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                     NearbyFaces& nearby, const HoleFillingOptions& o) {
  const Eigen::MatrixX3d& S = mesh.V;
  const Eigen::Vector3d g = loop_centroid(mesh, loop);
  const double h = mean_edge_length(mesh, loop);
  if (!(surface.distance_to_samples(g) < o.sample_gap * h)) return false;
  for (int fi : nearby.within(g, o.clearance * h)) {
    const MeshFace& f = mesh.face(fi);
    const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
    const Eigen::Vector3d bc = closest_point_barycentric(g, a, b, c);
    if ((bc[0] * a + bc[1] * b + bc[2] * c - g).norm() < o.clearance * h) return false;
  }
  return true;
}

// Whether every vertex of the loop is farther than sample_border_clearance·h from the edge of
// the scan (SurfaceProjector::distance_to_scan_edge()), i.e. the loop is a hole in sampled surface.
bool is_away_from_sample_border(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                                double h, const HoleFillingOptions& o) {
  for (int v : loop)
    if (!(surface.distance_to_scan_edge(mesh.V.row(v).transpose()) > o.sample_border_clearance * h)) return false;
  return true;
}

// Whether at least half of the loop's vertices lie within sample_border_clearance·h of the border
// of a cloud's samples (h its mean edge length): the loop follows the edge of what was scanned.
bool follows_sample_border(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                           const HoleFillingOptions& o) {
  if (surface.border_known()) return false;
  const double h = mean_edge_length(mesh, loop);
  int near = 0;
  for (int v : loop) near += surface.distance_to_sample_border(mesh.V.row(v).transpose()) <= o.sample_border_clearance * h;
  return 2 * near >= static_cast<int>(loop.size());
}

// Whether the loop is a hole inside the surface: where the surface's own border is known (an
// input mesh), every vertex of the loop is farther than interior_hole_clearance·h from it (always,
// on a closed surface); where the border of the samples is, farther than sample_border_clearance·h.
bool is_inside_surface(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                       const HoleFillingOptions& o) {
  const double h = mean_edge_length(mesh, loop);
  if (!surface.border_known()) return is_away_from_sample_border(mesh, surface, loop, h, o);
  if (!surface.has_border()) return true;
  for (int v : loop) {
    Eigen::Vector3d pos, nrm;
    const Eigen::Vector3d x = mesh.V.row(v);
    if (!surface.project_to_border(x, pos, nrm) || !((pos - x).norm() > o.interior_hole_clearance * h)) return false;
  }
  return true;
}

// Where the surface's own border is known (an input mesh), whether that border passes nearer the
// loop's centre than the loop's farthest vertex: the loop goes around a hole of the surface
// itself (one smaller than the site spacing included), which is one of its boundaries.
bool surrounds_surface_border(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop) {
  if (!surface.border_known() || !surface.has_border()) return false;
  const Eigen::Vector3d g = loop_centroid(mesh, loop);
  Eigen::Vector3d pos, nrm;
  return surface.project_to_border(g, pos, nrm) && (pos - g).norm() < loop_radius(mesh, loop, g);
}

// Beyond enough of the loop's edges, one edge length outward, the surface is sampled, and the
// surface there lies along the loop's own faces (surrounded_normal_agreement).
bool is_surrounded_hole(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                        const HoleFillingOptions& o) {
  const Eigen::MatrixX3d& S = mesh.V;
  int sampled = 0;
  const int L = static_cast<int>(loop.size());
  for (int i = 0; i < L; ++i) {
    const int a = loop[i], b = loop[(i + 1) % L];
    const int fi = mesh.half_edge_face(a, b);
    if (fi < 0) continue;
    const MeshFace& f = mesh.face(fi);
    const Eigen::Vector3d p0 = S.row(f[0]), p1 = S.row(f[1]), p2 = S.row(f[2]);
    const Eigen::Vector3d fn = (p1 - p0).cross(p2 - p0);
    const Eigen::Vector3d e = S.row(b) - S.row(a);
    if (!(fn.norm() > 0) || !(e.norm() > 0)) continue;
    const Eigen::Vector3d out = e.cross(fn).normalized();
    const double len = e.norm();
    const Eigen::Vector3d probe = 0.5 * (S.row(a) + S.row(b)).transpose() + len * out;
    if (!(surface.distance_to_samples(probe) < o.sample_gap * len)) continue;
    // The surface found there continues the loop's own (another object beside it does not).
    int hint = -1;
    Eigen::Vector3d pos, nrm;
    surface.project(probe, hint, pos, nrm);
    if (std::abs(nrm.dot(fn.normalized())) >= o.surrounded_normal_agreement) ++sampled;
  }
  return sampled >= o.surrounded_fraction * L;
}

// The loop is the open end of a tube whose tip is sampled: walking from the loop's centroid along
// the way its fill would face (against the loop's direction), the sampled surface comes within
// sample_gap·h before tip_reach loop radii.
bool is_sampled_tube_end(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop,
                         const HoleFillingOptions& o) {
  const int L = static_cast<int>(loop.size());
  const Eigen::Vector3d g = loop_centroid(mesh, loop);
  Eigen::Vector3d area = Eigen::Vector3d::Zero();
  double h = 0, radius = 0;
  for (int i = 0; i < L; ++i) {
    const Eigen::Vector3d a = mesh.V.row(loop[i]).transpose() - g, b = mesh.V.row(loop[(i + 1) % L]).transpose() - g;
    area += a.cross(b);
    h += (b - a).norm();
    radius += a.norm();
  }
  h /= L;
  radius /= L;
  if (!(area.norm() > 0) || !(h > 0)) return false;
  const Eigen::Vector3d axis = -area.normalized();  // the fill's triangles run against the loop
  const double step = 0.5 * o.sample_gap * h;
  for (double t = step; t <= o.tip_reach * radius; t += step)
    if (surface.distance_to_samples(g + t * axis) < o.sample_gap * h) return true;
  return false;
}

// A 3-loop that is the back of an existing face (its reversed half-edges all on one face).
bool is_back_of_face(const WorkingMesh& mesh, const std::vector<int>& loop) {
  const int f0 = mesh.half_edge_face(loop[1], loop[0]), f1 = mesh.half_edge_face(loop[2], loop[1]),
            f2 = mesh.half_edge_face(loop[0], loop[2]);
  return f0 >= 0 && f1 >= 0 && f2 >= 0 && f0 == f1 && f1 == f2;
}

// Whether the policy closes the simple loop `loop`, of the shape `shape` seen from its sites'
// normals, on a surface that is open or nearly closed.
bool selected(const WorkingMesh& mesh, const SurfaceProjector& surface, const std::vector<int>& loop, LoopShape shape,
              bool open_surface, NearbyFaces& nearby, const HoleFillingOptions& o) {
  const int L = static_cast<int>(loop.size());
  switch (o.policy) {
    case HolePolicy::fill: return true;
    case HolePolicy::keep:
      return L <= o.sampled_hole_factor * o.max_hole_edges && is_sampled_hole(mesh, surface, loop, nearby, o);
    case HolePolicy::automatic: break;
  }
  return (L <= o.max_hole_edges && o.fill_short_loops) || (L <= o.sampled_hole_factor * o.max_hole_edges && is_sampled_hole(mesh, surface, loop, nearby, o)) ||
         (L <= o.surrounded_hole_factor * o.max_hole_edges &&
          (is_surrounded_hole(mesh, surface, loop, o) ||
           (!open_surface && shape == LoopShape::unknown && is_sampled_tube_end(mesh, surface, loop, o))));
}

// Whether the triangles face the way their corners' normals do, on area-weighted average. Filling
// the border of a piece of surface (rather than a hole in it) would add its back side.
bool faces_agree_with_normals(const WorkingMesh& mesh, const std::vector<MeshFace>& tris, double min_agreement) {
  double agree = 0, area = 0;
  for (const MeshFace& t : tris) {
    const Eigen::Vector3d a = mesh.V.row(t[0]), b = mesh.V.row(t[1]), c = mesh.V.row(t[2]);
    const Eigen::Vector3d fn = (b - a).cross(c - a);
    const Eigen::Vector3d vn = mesh.N.row(t[0]) + mesh.N.row(t[1]) + mesh.N.row(t[2]);
    if (!(fn.norm() > 0) || !(vn.norm() > 0)) continue;
    agree += fn.dot(vn.normalized());
    area += fn.norm();
  }
  return !(area > 0) || agree >= min_agreement * area;
}

// The edge-connected pieces of the mesh with the number of boundary half-edges of each.
struct PieceBoundaries {
  FaceComponents components;
  std::vector<int> boundary_edges;
  explicit PieceBoundaries(const WorkingMesh& mesh) : components(face_components(mesh, false)) {
    boundary_edges.assign(components.size.size(), 0);
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int k = 0; k < 3; ++k)
        if (!mesh.has_half_edge(mesh.face(f)[(k + 1) % 3], mesh.face(f)[k])) ++boundary_edges[components.of_face[f]];
  }
};

// Whether the triangles close the loop's piece (it is the piece's only boundary) into a surface
// that encloses a volume of at least min_ratio · area^(3/2), with a fill of at most max_cap_share
// of the piece's area or more than all of it: a closed object missing a cap, not the two sides of
// a flat piece pressed together, nor one view of a round object whose unseen back the fill would
// stand for.
bool closes_a_volume(const WorkingMesh& mesh, const PieceBoundaries& pieces, const std::vector<int>& loop,
                     const std::vector<MeshFace>& tris, double min_ratio, double max_cap_share) {
  const int f0 = mesh.half_edge_face(loop[0], loop[1]);
  if (f0 < 0) return false;
  const int piece = pieces.components.of_face[f0];
  if (pieces.boundary_edges[piece] != static_cast<int>(loop.size())) return false;
  double volume = 0, area = 0;
  auto add = [&](const MeshFace& t) {
    const Eigen::Vector3d a = mesh.V.row(t[0]), b = mesh.V.row(t[1]), c = mesh.V.row(t[2]);
    volume += a.dot(b.cross(c)) / 6.0;
    area += 0.5 * (b - a).cross(c - a).norm();
  };
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (pieces.components.of_face[f] == piece) add(mesh.face(f));
  const double piece_area = area;
  for (const MeshFace& t : tris) add(t);
  // A fill larger than the piece itself is not limited: the piece is then a ring round a gap of
  // the extraction (coarse site counts), not what was seen of an object (a rim's fill is at most
  // as large as the part of a ball or a can seen from one side).
  const double share = (area - piece_area) / piece_area;
  return std::abs(volume) >= min_ratio * std::pow(area, 1.5) && (share <= max_cap_share || share > 1.0);
}

// Vertices in no face, and a lookup of those near a point.
class UnusedSites {
 public:
  explicit UnusedSites(const WorkingMesh& mesh) : mesh_(mesh), free_(mesh.num_vertices(), 1) {
    for (const MeshFace& f : mesh.faces())
      for (int v : f) free_[v] = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (free_[v]) list_.push_back(v);
  }
  bool any() const { return !list_.empty(); }
  // Free vertices within `radius` of `centre`, ascending.
  std::vector<int> near(const Eigen::Vector3d& centre, double radius) const {
    std::vector<int> out;
    for (int v : list_)
      if (free_[v] && (mesh_.V.row(v).transpose() - centre).norm() <= radius) out.push_back(v);
    return out;
  }
  void take(const std::vector<int>& vs) {
    for (int v : vs) free_[v] = 0;
  }

 private:
  const WorkingMesh& mesh_;
  std::vector<char> free_;
  std::vector<int> list_;
};

// Triangulates a selected loop: with the unused sites inside it when there are any (hole_sites.h),
// else by the max-min-angle triangulation of the loop alone.
bool triangulate_selected(const WorkingMesh& mesh, const std::vector<int>& loop, const HoleTriangulation& with_sites,
                          bool sites_ok, std::vector<MeshFace>& tris) {
  if (sites_ok && !with_sites.interior_sites.empty()) {
    tris = with_sites.faces;
    return true;
  }
  return triangulate_loop(mesh, loop, tris);
}

// Adds the fills' triangles; with o.reject_intersecting_fills, the rejectable fills that
// self-intersect the result are taken out again (one global test for the whole pass). Returns the fills kept and
// appends their loop lengths to `sizes`.
int add_fills_without_intersections(WorkingMesh& mesh, const std::vector<MeshFace>& added, const std::vector<int>& fill_of,
                                    const std::vector<int>& fill_sizes, const std::vector<char>& rejectable,
                                    const HoleFillingOptions& o, std::vector<int>* sizes) {
  const int first = mesh.num_faces();
  for (const MeshFace& t : added) mesh.add_face(t);
  std::vector<char> failed(fill_sizes.size(), 0);
  if (o.reject_intersecting_fills && !added.empty())
    for (int f : self_intersecting_faces(mesh))
      if (f >= first && rejectable[fill_of[f - first]]) failed[fill_of[f - first]] = 1;
  std::vector<char> drop(mesh.num_faces(), 0);
  for (size_t t = 0; t < added.size(); ++t) drop[first + t] = failed[fill_of[t]];
  mesh.remove_faces(drop);
  int kept = 0;
  for (size_t i = 0; i < fill_sizes.size(); ++i)
    if (!failed[i]) {
      if (sizes) sizes->push_back(fill_sizes[i]);
      ++kept;
    }
  return kept;
}

// One pass: every simple boundary loop that qualifies is triangulated. Returns the loops filled.
int fill_pass(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& o, std::vector<int>* sizes) {
  const int max_loop = std::max(o.max_fill_edges, o.surrounded_hole_factor * o.max_hole_edges);
  UnusedSites unused(mesh);
  NearbyFaces nearby(mesh);  // the faces as they are before this pass adds any
  const PieceBoundaries pieces(mesh);
  std::unordered_map<int, std::vector<int>> next;  // boundary half-edge a->b (face side) by start vertex
  std::vector<std::pair<int, int>> bedges;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (!mesh.has_half_edge(b, a)) {
        next[a].push_back(b);
        bedges.push_back({a, b});
      }
    }
  if (bedges.empty()) return 0;
  // Pieces of an open scan, rather than a nearly closed surface with gaps.
  const bool open_surface = static_cast<double>(bedges.size()) > o.open_surface_fraction * 1.5 * mesh.num_faces();
  std::sort(bedges.begin(), bedges.end());
  std::unordered_map<long long, char> used;
  std::vector<MeshFace> added;
  std::vector<int> fill_of;     // added triangle -> its fill
  std::vector<int> fill_sizes;  // loop length of each fill
  std::vector<char> rejectable;  // whether the fill is taken out if it self-intersects
  for (const auto& [a0, b0] : bedges) {
    if (used.count(WorkingMesh::edge_key(a0, b0))) continue;
    std::vector<int> loop = {a0};
    int cur = b0;
    bool simple = true;
    used[WorkingMesh::edge_key(a0, b0)] = 1;
    while (cur != a0 && static_cast<int>(loop.size()) <= max_loop + 1) {
      auto it = next.find(cur);
      if (it == next.end() || it->second.size() != 1) {
        simple = false;
        break;
      }
      loop.push_back(cur);
      used[WorkingMesh::edge_key(cur, it->second[0])] = 1;
      cur = it->second[0];
    }
    const int L = static_cast<int>(loop.size());
    if (!simple || cur != a0 || L > max_loop || L < 3) continue;
    std::vector<int> sorted = loop;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
    if (L == 3 && is_back_of_face(mesh, loop)) continue;  // would duplicate that face
    if (o.policy == HolePolicy::keep && surrounds_surface_border(mesh, surface, loop)) continue;
    HoleTriangulation with_sites;
    bool sites_ok = false;
    if (o.sites.enabled) {
      const Eigen::Vector3d g = loop_centroid(mesh, loop);
      sites_ok = triangulate_hole_with_sites(mesh, loop, unused.near(g, loop_radius(mesh, loop, g)), o.sites, with_sites);
    }
    const bool sampled_by_sites = sites_ok && !with_sites.interior_sites.empty() && L <= o.max_fill_edges &&
                                  with_sites.interior_sites.size() >= o.sites.sampled_fraction * with_sites.expected_sites;
    // A hole inside the surface; from a cloud (the border known only from the samples), not the
    // outer border of a piece seen from its sites' side (a fragment far from the scan's edge).
    const bool inside = L <= o.max_fill_edges && (surface.border_known() || with_sites.shape != LoopShape::outer_border) &&
                        is_inside_surface(mesh, surface, loop, o);
    if (L > (o.policy == HolePolicy::fill ? o.max_fill_edges : o.surrounded_hole_factor * o.max_hole_edges) &&
        !sampled_by_sites && !inside)
      continue;
    if (!sampled_by_sites && !inside && !selected(mesh, surface, loop, with_sites.shape, open_surface, nearby, o)) continue;
    std::vector<MeshFace> tris;
    if (!triangulate_selected(mesh, loop, with_sites, sites_ok, tris)) continue;
    // Beyond the extraction's own small gaps, a loop is filled only when the fill does not face
    // against its corners' normals (closing the border of a piece would turn its back side up).
    if (L > o.max_hole_edges && !faces_agree_with_normals(mesh, tris, o.min_fill_normal_agreement) &&
        !closes_a_volume(mesh, pieces, loop, tris, o.min_closed_volume,
                         o.policy != HolePolicy::fill && follows_sample_border(mesh, surface, loop, o)
                             ? o.max_cap_area_fraction
                             : std::numeric_limits<double>::infinity()))
      continue;
    if (sites_ok) unused.take(with_sites.interior_sites);
    added.insert(added.end(), tris.begin(), tris.end());
    fill_of.insert(fill_of.end(), tris.size(), static_cast<int>(fill_sizes.size()));
    fill_sizes.push_back(L);
    // Only the fill of what looks like the border of a piece, from its sites' side, is taken out
    // when it cuts through the mesh: a gap of the extraction, a hole inside the surface, or a
    // loop around the tip of a thin part, is filled and untangled after.
    // Under HolePolicy::fill every fill stays (a watertight mesh is asked for).
    rejectable.push_back(o.policy != HolePolicy::fill && !inside && open_surface && L > o.max_hole_edges &&
                         (with_sites.shape == LoopShape::outer_border || with_sites.shape == LoopShape::not_simple));
  }
  return add_fills_without_intersections(mesh, added, fill_of, fill_sizes, rejectable, o, sizes);
}

}  // namespace

bool triangulate_loop(const WorkingMesh& mesh, const std::vector<int>& loop, std::vector<MeshFace>& out) {
  const int L = static_cast<int>(loop.size());
  if (L < 3) return false;
  auto is_edge = [&](int i, int j) { return mesh.edge_face_count(loop[i], loop[j]) > 0; };
  const double NEG = -1.0;
  std::vector<double> best(L * L, NEG);
  std::vector<int> split(L * L, -1);
  for (int i = 0; i + 1 < L; ++i) best[i * L + i + 1] = M_PI;  // a polygon edge: neutral
  for (int len = 2; len < L; ++len)
    for (int i = 0; i + len < L; ++i) {
      const int j = i + len;
      // The chord (i, j) must not already be an edge of the mesh (except the closing edge 0..L-1).
      if (!(i == 0 && j == L - 1) && is_edge(i, j)) continue;
      for (int k = i + 1; k < j; ++k) {
        const double a = best[i * L + k], b = best[k * L + j];
        if (a < 0 || b < 0) continue;
        const double q = std::min({a, b, face_min_angle(mesh, {loop[i], loop[k], loop[j]})});
        if (q > best[i * L + j]) {
          best[i * L + j] = q;
          split[i * L + j] = k;
        }
      }
    }
  if (best[0 * L + L - 1] < 0) return false;
  std::vector<std::pair<int, int>> stack = {{0, L - 1}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[i * L + j];
    out.push_back({loop[i], loop[j], loop[k]});  // reversed w.r.t. loop order i<k<j
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

int fill_holes(WorkingMesh& mesh, const SurfaceProjector& surface, const HoleFillingOptions& options,
               const ManifoldOptions& manifold, int& removed, std::vector<int>* filled_edges) {
  int filled = 0;
  for (int pass = 0; pass < options.passes; ++pass) {
    const int before = mesh.num_faces();
    const int pass_filled = fill_pass(mesh, surface, options, filled_edges);
    if (mesh.num_faces() == before) break;
    filled += pass_filled;
    removed += make_vertices_manifold(mesh, manifold);
  }
  return filled;
}

}  // namespace heatcvt
