// Heat Voronoi diagrams (paper §4): labels, tie-break of eq. 19, exact cutting along the
// bisectors of eq. 20, and the bookkeeping of the refined mesh.
//
// Inside one original face every heat function u_s is linear (vertex values interpolated with
// barycentric coordinates), so the part of a cell inside a face is the convex region where u_s
// is the largest. We obtain it by clipping the face with the half-planes u_s − u_r ≥ 0 (the
// bisector lines of eq. 20); this yields exactly the pieces of the recursive triangle/quad cut
// of Fig. 2 and terminates by construction. Points on original edges are computed only from the
// edge's own data (a 1D upper envelope walked in a canonical orientation), so both faces of an
// edge produce bit-identical points that are welded into one refined vertex: the refined mesh is
// conforming and the cell boundaries form polylines. Inside a face, polygon vertices are keyed
// combinatorially (corner, edge pair, triple point) and welded; a per-face validity check
// (exact single positive cover, boundary = canonical edge points) falls back to a centroid fan
// labelled per triangle in the rare near-degenerate faces (nearly coincident sites).
#include "heatcvt/voronoi.h"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>
#include <numeric>
#include <string>

#include "heatcvt/errors.h"
#include "heatcvt/face_clipper.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

// ---------------------------------------------------------------------------------------------
// Heat fields
// ---------------------------------------------------------------------------------------------

namespace {

struct SiteHeat {
  int site;
  double heat;
};

// Order of a heat field row: decreasing heat, ties by increasing site index.
bool hotter(const SiteHeat& x, const SiteHeat& y) {
  if (x.heat != y.heat) return x.heat > y.heat;
  return x.site < y.site;
}

// A field from per-vertex rows already in `hotter` order: row v has kept[v] entries at(v, i).
template <class At>
HeatField pack_field(int num_sites, const std::vector<int>& kept, At at) {
  const int n = static_cast<int>(kept.size());
  HeatField field;
  field.num_sites = num_sites;
  field.offsets.assign(n + 1, 0);
  for (int v = 0; v < n; ++v) field.offsets[v + 1] = field.offsets[v] + kept[v];
  field.site.resize(field.offsets[n]);
  field.heat.resize(field.offsets[n]);
  for (int v = 0; v < n; ++v)
    for (int i = 0; i < kept[v]; ++i) {
      const SiteHeat e = at(v, i);
      field.site[field.offsets[v] + i] = e.site;
      field.heat[field.offsets[v] + i] = e.heat;
    }
  return field;
}

// The `keep` hottest sites per vertex, merged column block by column block (columns must be
// added in increasing site order, so ties keep the smaller site first: the order of
// hotter). Column-major friendly: each thread owns a range of vertices.
class TopKField {
 public:
  TopKField(int num_vertices, int keep)
      : nv_(num_vertices), keep_(keep), site_(static_cast<size_t>(num_vertices) * keep, -1),
        heat_(static_cast<size_t>(num_vertices) * keep, 0.0), count_(num_vertices, 0) {}

  void add_columns(const Eigen::MatrixXd& U, int first_site, int threads) {
    const int nb = static_cast<int>(U.cols());
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int v = 0; v < nv_; ++v) {
      int* ts = &site_[static_cast<size_t>(v) * keep_];
      double* th = &heat_[static_cast<size_t>(v) * keep_];
      int& c = count_[v];
      for (int j = 0; j < nb; ++j) {
        const double h = U(v, j);
        if (h == 0.0) continue;  // absent means 0: an exact zero carries no information
        if (c == keep_ && !(h > th[keep_ - 1])) continue;
        int pos = c < keep_ ? c : keep_ - 1;
        while (pos > 0 && h > th[pos - 1]) {
          ts[pos] = ts[pos - 1];
          th[pos] = th[pos - 1];
          --pos;
        }
        ts[pos] = first_site + j;
        th[pos] = h;
        if (c < keep_) ++c;
      }
    }
  }

  HeatField finish(int num_sites) const {
    return pack_field(num_sites, count_, [&](int v, int i) {
      const size_t k = static_cast<size_t>(v) * keep_ + i;
      return SiteHeat{site_[k], heat_[k]};
    });
  }

 private:
  int nv_, keep_;
  std::vector<int> site_;
  std::vector<double> heat_;
  std::vector<int> count_;
};

}  // namespace

HeatField heat_field_from_dense(const Eigen::MatrixXd& U, int keep) {
  if (keep < 1) throw InvalidInputError("heat_field_from_dense: keep must be >= 1, got " + std::to_string(keep));
  if (!U.allFinite()) throw InvalidInputError("heat_field_from_dense: the heat matrix has NaN or infinite entries");
  TopKField top(static_cast<int>(U.rows()), keep);
  top.add_columns(U, 0, resolve_threads(0));
  return top.finish(static_cast<int>(U.cols()));
}

HeatField heat_field_from_sparse(int num_vertices, const std::vector<std::vector<int>>& indices,
                                 const std::vector<std::vector<double>>& values, int keep, int threads) {
  if (keep < 1) throw InvalidInputError("heat_field_from_sparse: keep must be >= 1, got " + std::to_string(keep));
  if (indices.size() != values.size())
    throw InvalidInputError("heat_field_from_sparse: indices and values have different numbers of sites");
  const int n = std::max(num_vertices, 0), ns = static_cast<int>(indices.size());
  // Counting sort of the (site, heat) pairs by vertex (site order within a vertex), then each
  // row sorted by `hotter` and truncated, without per-vertex allocations.
  std::vector<int> count(n + 1, 0);
  for (int s = 0; s < ns; ++s) {
    if (indices[s].size() != values[s].size())
      throw InvalidInputError("heat_field_from_sparse: site " + std::to_string(s) +
                              " has different numbers of indices and values");
    for (size_t k = 0; k < indices[s].size(); ++k) {
      const int v = indices[s][k];
      if (v < 0 || v >= n)
        throw InvalidInputError("heat_field_from_sparse: site " + std::to_string(s) + " has vertex index " +
                                std::to_string(v) + " out of range [0, " + std::to_string(num_vertices) + ")");
      if (!std::isfinite(values[s][k]))
        throw InvalidInputError("heat_field_from_sparse: site " + std::to_string(s) + " has a non-finite value");
      if (values[s][k] != 0.0) ++count[v + 1];  // absent means 0
    }
  }
  for (int v = 0; v < n; ++v) count[v + 1] += count[v];
  std::vector<SiteHeat> pairs(count[n]);
  {
    std::vector<int> fill(count.begin(), count.end() - 1);
    for (int s = 0; s < ns; ++s)
      for (size_t i = 0; i < indices[s].size(); ++i)
        if (values[s][i] != 0.0) pairs[fill[indices[s][i]]++] = {s, values[s][i]};
  }
  std::vector<int> kept(n);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(threads))
  for (int v = 0; v < n; ++v) {
    const auto first = pairs.begin() + count[v], last = pairs.begin() + count[v + 1];
    const int m = std::min<int>(keep, static_cast<int>(last - first));
    std::partial_sort(first, first + m, last, hotter);
    kept[v] = m;
  }
  return pack_field(ns, kept, [&](int v, int k) { return pairs[count[v] + k]; });
}

// ---------------------------------------------------------------------------------------------
// Per-face tessellation
// ---------------------------------------------------------------------------------------------

namespace {

double field_value(const HeatField& field, int v, int s) {
  for (int k = field.offsets[v]; k < field.offsets[v + 1]; ++k)
    if (field.site[k] == s) return field.heat[k];
  return 0.0;
}

// A switch point of the upper envelope along the canonical edge a → b (a < b): at parameter
// t the hottest site changes between p and q (p < q). Position (1−t)·V_a + t·V_b.
struct EdgePoint {
  double t;
  int p, q;
};

// 1D upper envelope of the sites known at a or b, walked from a to b. Deterministic function
// of (a, b, field) only, so both faces of the edge obtain identical points.
std::vector<EdgePoint> edge_switch_points(const HeatField& field, int a, int b, double merge_tol) {
  std::vector<int> sites;
  for (int k = field.offsets[a]; k < field.offsets[a + 1]; ++k) sites.push_back(field.site[k]);
  for (int k = field.offsets[b]; k < field.offsets[b + 1]; ++k) sites.push_back(field.site[k]);
  std::sort(sites.begin(), sites.end());
  sites.erase(std::unique(sites.begin(), sites.end()), sites.end());
  std::vector<EdgePoint> out;
  if (sites.size() < 2) return out;
  const int m = static_cast<int>(sites.size());
  std::vector<double> ua(m), ub(m);
  for (int i = 0; i < m; ++i) {
    ua[i] = field_value(field, a, sites[i]);
    ub[i] = field_value(field, b, sites[i]);
  }
  // winner at t = 0: largest value, then largest slope (toward the edge interior), then index
  int w = 0;
  for (int i = 1; i < m; ++i) {
    const double si = ub[i] - ua[i], sw = ub[w] - ua[w];
    if (ua[i] > ua[w] || (ua[i] == ua[w] && si > sw)) w = i;
  }
  double tcur = 0.0;
  for (int guard = 0; guard < m; ++guard) {
    int best = -1;
    double best_t = std::numeric_limits<double>::infinity();
    for (int r = 0; r < m; ++r) {
      if (r == w) continue;
      const double slope_gain = (ub[r] - ua[r]) - (ub[w] - ua[w]);
      if (!(slope_gain > 0)) continue;
      const int p = std::min(r, w), q = std::max(r, w);
      const double da = ua[p] - ua[q], db = ub[p] - ub[q];
      const double t = da / (da - db);
      if (!(t > tcur) || !(t < 1.0)) continue;
      if (t < best_t || (t == best_t && (ub[r] - ua[r]) > (ub[best] - ua[best]))) {
        best_t = t;
        best = r;
      }
    }
    if (best < 0) break;
    const int p = std::min(sites[best], sites[w]), q = std::max(sites[best], sites[w]);
    if (out.empty() ? best_t > merge_tol : best_t - out.back().t > merge_tol) {
      if (1.0 - best_t > merge_tol) out.push_back({best_t, p, q});
    }
    tcur = best_t;
    w = best;
  }
  return out;
}

// A point of the refined mesh produced by one face.
struct LocalPoint {
  enum Kind { Corner, OnEdge, Interior } kind;
  int vertex = -1;                 // Corner: original vertex
  std::array<int, 4> key{};        // OnEdge: (a, b, p, q), a < b
  double t = 0;                    // OnEdge: parameter from a to b
  Eigen::Vector3d bary;            // in the parent face
};

struct FaceResult {
  bool whole = false;  // the face is one refined face of `cell` (no allocation)
  bool fast = false;   // whole because one site is strictly hottest at all three corners
  int cell = -1;
  std::vector<LocalPoint> points;
  std::vector<std::array<int, 3>> tris;
  std::vector<int> cells;
};

double bary_det(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2) {
  return (x1[1] - x0[1]) * (x2[2] - x0[2]) - (x2[1] - x0[1]) * (x1[2] - x0[2]);
}

// Fast path (most faces): one site is strictly hottest, with positive heat, at all three
// corners. It beats every other site at every corner (absent sites count as 0), hence on the
// whole face (linear interpolation), which is what the general path would conclude. Returns
// that site or −1.
int strict_face_winner(const HeatField& field, const int vtx[3]) {
  int top = -1;
  for (int c = 0; c < 3; ++c) {
    const int b = field.offsets[vtx[c]], e = field.offsets[vtx[c] + 1];
    const bool strict = e > b && field.heat[b] > 0.0 && (e - b == 1 || field.heat[b] > field.heat[b + 1]) &&
                        (top < 0 || field.site[b] == top);
    if (!strict) return -1;
    top = field.site[b];
  }
  return top;
}

// The sites known at the three corners, sorted by site, with their heat at the corners.
void face_functions(const HeatField& field, const int vtx[3], std::vector<FaceFunction>& out) {
  thread_local std::vector<int> sites;
  sites.clear();
  for (int c = 0; c < 3; ++c)
    for (int k = field.offsets[vtx[c]]; k < field.offsets[vtx[c] + 1]; ++k) sites.push_back(field.site[k]);
  std::sort(sites.begin(), sites.end());
  sites.erase(std::unique(sites.begin(), sites.end()), sites.end());
  out.resize(sites.size());
  for (size_t i = 0; i < sites.size(); ++i) {
    out[i].label = sites[i];
    for (int c = 0; c < 3; ++c) out[i].value[c] = field_value(field, vtx[c], sites[i]);
  }
}

// Guard of the exact cutting: keeps the max_cut_depth functions with the largest corner heat
// (stable, then back in site order).
void truncate_functions(std::vector<FaceFunction>& fns, int max_cut_depth) {
  const int limit = std::max(max_cut_depth, 2);
  if (static_cast<int>(fns.size()) <= limit) return;
  auto peak = [](const FaceFunction& x) { return std::max({x.value[0], x.value[1], x.value[2]}); };
  std::stable_sort(fns.begin(), fns.end(), [&](const FaceFunction& x, const FaceFunction& y) { return peak(x) > peak(y); });
  fns.resize(limit);
  std::sort(fns.begin(), fns.end(), [](const FaceFunction& x, const FaceFunction& y) { return x.label < y.label; });
}

// The refined points and triangles of one cut face. Every clipped polygon vertex lies on two
// lines (face edges, or bisectors with a local function, face_clipper.h) and gets a canonical
// key: a corner, a point on face edge k of the pair {s, r}, or the triple point {s, r, q} where
// three heat functions agree. The position of a key is computed once from the key alone, so all
// polygons of the face share bit-identical vertices even where near-parallel bisectors make the
// clipped positions ill-conditioned (nearly coincident sites).
class CutFace {
 public:
  CutFace(const HeatField& field, const int vtx[3], const std::vector<FaceFunction>& fns, const VoronoiOptions& opt,
          FaceResult& res)
      : field_(field), fns_(fns), opt_(opt), res_(res) {
    for (int c = 0; c < 3; ++c) vtx_[c] = vtx[c];
    add_canonical_points();
  }

  // Triangles of the region of local function s (fan from a corner, or from the region's
  // centroid when a vertex is flat).
  void add_region(int s, const std::vector<ClipVertex>& poly) {
    std::vector<int> ids;
    for (const ClipVertex& pv : poly) {
      const int id = vertex_id(s, pv.line_a, pv.line_b);
      if (ids.empty() || ids.back() != id) ids.push_back(id);
    }
    while (ids.size() > 1 && ids.back() == ids.front()) ids.pop_back();
    if (ids.size() < 3) return;
    // Fan from a corner of the polygon, unless a vertex is flat (lies on a straight side, e.g.
    // an edge point where a measure-zero cell touches): then fan from the polygon's centroid,
    // a point private to this polygon, so no zero-area triangle turns a side into a diagonal.
    const size_t np = ids.size();
    bool flat = false;
    for (size_t i = 0; i < np && !flat; ++i)
      flat = std::abs(bary_det(res_.points[ids[(i + np - 1) % np]].bary, res_.points[ids[i]].bary,
                               res_.points[ids[(i + 1) % np]].bary)) < opt_.flat_tolerance;
    if (np > 3 && flat) {
      LocalPoint c;
      c.kind = LocalPoint::Interior;
      c.bary = Eigen::Vector3d::Zero();
      for (int id : ids) c.bary += res_.points[id].bary;
      c.bary /= static_cast<double>(np);
      const int ci = static_cast<int>(res_.points.size());
      res_.points.push_back(c);
      for (size_t i = 0; i < np; ++i) {
        res_.tris.push_back({ci, ids[i], ids[(i + 1) % np]});
        res_.cells.push_back(fns_[s].label);
      }
      return;
    }
    for (size_t i = 1; i + 1 < np; ++i) {
      if (ids[0] == ids[i] || ids[i] == ids[i + 1] || ids[0] == ids[i + 1]) continue;
      res_.tris.push_back({ids[0], ids[i], ids[i + 1]});
      res_.cells.push_back(fns_[s].label);
    }
  }

  // Safety net for near-degenerate configurations (nearly coincident sites, ties under
  // truncation): the pieces must tile the face exactly once, positively oriented, and meet the
  // face boundary exactly in the canonical edge points. Otherwise the face is fanned from its
  // centroid over the canonical boundary points, each triangle labelled by its own centroid:
  // still conforming and area-exact, only the cut inside this one face is approximate.
  void finish(const std::vector<int>& alive) {
    const std::vector<int> chain = boundary_chain();
    if (tiles_face(chain)) return;
    res_.tris.clear();
    res_.cells.clear();
    LocalPoint centre;
    centre.kind = LocalPoint::Interior;
    centre.bary = Eigen::Vector3d::Constant(1.0 / 3);
    const int ci = static_cast<int>(res_.points.size());
    res_.points.push_back(centre);
    for (size_t i = 0; i < chain.size(); ++i) {
      const int a = chain[i], b = chain[(i + 1) % chain.size()];
      const Eigen::Vector3d x = (centre.bary + res_.points[a].bary + res_.points[b].bary) / 3.0;
      int best = alive[0];
      double best_u = -std::numeric_limits<double>::infinity();
      for (int r : alive) {
        const auto& U = fns_[r].value;
        const double u = U[0] * x[0] + U[1] * x[1] + U[2] * x[2];
        if (u > best_u) {
          best_u = u;
          best = r;
        }
      }
      res_.tris.push_back({ci, a, b});
      res_.cells.push_back(fns_[best].label);
    }
  }

 private:
  // Corners, then the switch points of each edge (edge k = corners k, k+1).
  void add_canonical_points() {
    for (int c = 0; c < 3; ++c) {
      LocalPoint p;
      p.kind = LocalPoint::Corner;
      p.vertex = vtx_[c];
      p.bary = Eigen::Vector3d::Unit(c);
      res_.points.push_back(p);
    }
    for (int k = 0; k < 3; ++k) {
      const int ca = k, cb = (k + 1) % 3;
      const int a = std::min(vtx_[ca], vtx_[cb]), b = std::max(vtx_[ca], vtx_[cb]);
      const int corner_a = vtx_[ca] == a ? ca : cb, corner_b = corner_a == ca ? cb : ca;
      for (const EdgePoint& e : edge_switch_points(field_, a, b, opt_.edge_merge_tolerance)) {
        LocalPoint p;
        p.kind = LocalPoint::OnEdge;
        p.key = {a, b, e.p, e.q};
        p.t = e.t;
        p.bary = Eigen::Vector3d::Zero();
        p.bary[corner_a] = 1.0 - e.t;
        p.bary[corner_b] = e.t;
        edge_point_ids_[k].push_back(static_cast<int>(res_.points.size()));
        res_.points.push_back(p);
      }
    }
  }

  static int common_corner(int k1, int k2) {
    for (int c : {k1, (k1 + 1) % 3})
      if (c == k2 || c == (k2 + 1) % 3) return c;
    return k1;
  }

  // Nearest canonical point (corner or walk point) of face edge k at parameter t from its
  // smaller to its larger vertex.
  int snap_to_edge(int k, double t) const {
    const int ca = k, cb = (k + 1) % 3;
    const int a = std::min(vtx_[ca], vtx_[cb]);
    const int corner_a = vtx_[ca] == a ? ca : cb, corner_b = corner_a == ca ? cb : ca;
    int best = corner_a;
    double best_d = std::abs(t);
    if (std::abs(1.0 - t) < best_d) {
      best = corner_b;
      best_d = std::abs(1.0 - t);
    }
    for (int id : edge_point_ids_[k]) {
      const double dd = std::abs(res_.points[id].t - t);
      if (dd < best_d) {
        best = id;
        best_d = dd;
      }
    }
    return best;
  }

  // The walk of edge k is the canonical truth: look the pair up, else snap to the nearest point.
  int point_on_edge(int k, int p, int q) const {
    const int ca = k, cb = (k + 1) % 3;
    const int a = std::min(vtx_[ca], vtx_[cb]), b = std::max(vtx_[ca], vtx_[cb]);
    const int gp = fns_[std::min(p, q)].label, gq = fns_[std::max(p, q)].label;
    for (int id : edge_point_ids_[k]) {
      const LocalPoint& lp = res_.points[id];
      if (lp.key[2] == gp && lp.key[3] == gq) return id;
    }
    const double da = field_value(field_, a, gp) - field_value(field_, a, gq);
    const double db = field_value(field_, b, gp) - field_value(field_, b, gq);
    double t = da / (da - db);
    if (!std::isfinite(t)) t = 0.5;
    return snap_to_edge(k, t);
  }

  int vertex_id(int s, int l1, int l2) {
    if (l1 < 0 && l2 < 0) return common_corner(-1 - l1, -1 - l2);
    if (l1 < 0 || l2 < 0) {
      const int k = l1 < 0 ? -1 - l1 : -1 - l2, r = l1 < 0 ? l2 : l1;
      return point_on_edge(k, s, r);
    }
    std::array<int, 3> tri = {s, l1, l2};
    std::sort(tri.begin(), tri.end());
    const std::array<int, 4> key = {tri[0], tri[1], tri[2], 0};
    auto it = key_ids_.find(key);
    if (it != key_ids_.end()) return it->second;
    const int id = triple_point(tri);
    key_ids_.emplace(key, id);
    return id;
  }

  // The point where u_a = u_b = u_c (Σβ = 1): a canonical edge point when it lies on the face
  // boundary, an existing point when several triples meet there (≥ 4 cells), else a new point.
  int triple_point(const std::array<int, 3>& tri) {
    Eigen::Matrix3d A;
    for (int c = 0; c < 3; ++c) {
      A(0, c) = fns_[tri[0]].value[c] - fns_[tri[1]].value[c];
      A(1, c) = fns_[tri[0]].value[c] - fns_[tri[2]].value[c];
      A(2, c) = 1.0;
    }
    Eigen::Vector3d x = A.fullPivLu().solve(Eigen::Vector3d(0, 0, 1));
    if (!x.allFinite()) x = Eigen::Vector3d::Constant(1.0 / 3);
    x = x.cwiseMax(0.0);
    x /= x.sum();
    int cmin = 0;
    if (x.minCoeff(&cmin) <= opt_.weld_tolerance) {
      const int k = (cmin + 1) % 3, ca = k, cb = (k + 1) % 3;
      const int corner_a = vtx_[ca] < vtx_[cb] ? ca : cb, corner_b = corner_a == ca ? cb : ca;
      return snap_to_edge(k, x[corner_b] / (x[corner_a] + x[corner_b]));
    }
    for (int i = 0; i < static_cast<int>(res_.points.size()); ++i)
      if ((res_.points[i].bary - x).cwiseAbs().maxCoeff() < opt_.weld_tolerance) return i;
    LocalPoint p;
    p.kind = LocalPoint::Interior;
    p.bary = x;
    res_.points.push_back(p);
    return static_cast<int>(res_.points.size()) - 1;
  }

  // Boundary points counter-clockwise: corner k, the points of edge k, ...
  std::vector<int> boundary_chain() const {
    std::vector<int> chain;
    for (int k = 0; k < 3; ++k) {
      chain.push_back(k);
      if (vtx_[k] < vtx_[(k + 1) % 3])
        chain.insert(chain.end(), edge_point_ids_[k].begin(), edge_point_ids_[k].end());
      else
        chain.insert(chain.end(), edge_point_ids_[k].rbegin(), edge_point_ids_[k].rend());
    }
    return chain;
  }

  // Every directed edge once; an edge without its reverse must be a boundary step of `chain`,
  // every boundary step must be covered, all triangles positive and their areas sum to the face.
  bool tiles_face(const std::vector<int>& chain) const {
    if (res_.tris.empty()) return false;
    std::vector<std::pair<int, int>> directed, boundary;
    double total = 0;
    for (const auto& t : res_.tris) {
      const double det = bary_det(res_.points[t[0]].bary, res_.points[t[1]].bary, res_.points[t[2]].bary);
      total += det;
      if (!(det > -opt_.orientation_tolerance)) return false;
      for (int c = 0; c < 3; ++c) directed.push_back({t[c], t[(c + 1) % 3]});
    }
    if (std::abs(total - 1.0) > opt_.tiling_tolerance) return false;
    std::sort(directed.begin(), directed.end());
    if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
    for (size_t i = 0; i < chain.size(); ++i) boundary.push_back({chain[i], chain[(i + 1) % chain.size()]});
    std::sort(boundary.begin(), boundary.end());
    for (const auto& e : directed) {
      if (std::binary_search(directed.begin(), directed.end(), std::make_pair(e.second, e.first))) continue;
      if (!std::binary_search(boundary.begin(), boundary.end(), e)) return false;  // a crack or a T-junction
    }
    for (const auto& e : boundary)
      if (!std::binary_search(directed.begin(), directed.end(), e)) return false;
    return true;
  }

  const HeatField& field_;
  const std::vector<FaceFunction>& fns_;
  const VoronoiOptions& opt_;
  FaceResult& res_;
  int vtx_[3];
  std::array<std::vector<int>, 3> edge_point_ids_;  // ordered from the canonical a to b
  std::map<std::array<int, 4>, int> key_ids_;
};

FaceResult tessellate_face(const Eigen::MatrixX3i& F, const HeatField& field, int f, const VoronoiOptions& opt) {
  FaceResult res;
  const int vtx[3] = {F(f, 0), F(f, 1), F(f, 2)};
  const int fast = strict_face_winner(field, vtx);
  if (fast >= 0) {
    res.whole = res.fast = true;
    res.cell = fast;
    return res;
  }
  thread_local std::vector<FaceFunction> fns;
  face_functions(field, vtx, fns);
  res.whole = true;
  if (fns.empty()) return res;  // no site known here: cell −1
  if (!opt.exact) {
    // label of the face centroid (mean of the corner values), ties by smaller site index
    int best = 0;
    for (size_t i = 1; i < fns.size(); ++i)
      if (fns[i].value[0] + fns[i].value[1] + fns[i].value[2] > fns[best].value[0] + fns[best].value[1] + fns[best].value[2])
        best = static_cast<int>(i);
    res.cell = fns[best].label;
    return res;
  }
  const int l0 = corner_winner(fns, 0), l1 = corner_winner(fns, 1), l2 = corner_winner(fns, 2);
  if (l0 == l1 && l1 == l2) {
    // u_l is the largest at all three corners, hence (linear functions) on the whole face
    res.cell = fns[l0].label;
    return res;
  }
  res.whole = false;
  truncate_functions(fns, opt.max_cut_depth);
  thread_local FaceClipScratch clip;
  face_candidates(fns, clip.alive);
  CutFace cut(field, vtx, fns, opt, res);
  for (int s : clip.alive)
    if (clip_face_region(fns, clip.alive, s, clip.region, clip.next)) cut.add_region(s, clip.region);
  cut.finish(clip.alive);
  return res;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Assembly and bookkeeping
// ---------------------------------------------------------------------------------------------

namespace {

// Voronoi vertices: refined vertices (other than `skipped` ones) where ≥ 3 cells meet.
std::vector<char> find_voronoi_vertices(VoronoiDiagram& d, const std::vector<char>& interior) {
  const int nrv = static_cast<int>(d.V.rows()), nv = static_cast<int>(interior.size());
  std::vector<int> inc_off, inc;
  refined_vertex_faces(d, inc_off, inc);
  d.voronoi_vertices.clear();
  std::vector<char> is_vvertex(nrv, 0);
  std::vector<int> cells;
  for (int v = 0; v < nrv; ++v) {
    if (v < nv && interior[v]) continue;
    cells.clear();
    for (int i = inc_off[v]; i < inc_off[v + 1]; ++i)
      if (d.face_cell[inc[i]] >= 0) cells.push_back(d.face_cell[inc[i]]);
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    if (cells.size() < 3) continue;
    is_vvertex[v] = 1;
    VoronoiVertex vv;
    vv.position = d.V.row(v).transpose();
    const int r = inc[inc_off[v]];
    int k = 0;
    while (d.F(r, k) != v) ++k;
    vv.location.face = d.face_parent[r];
    vv.location.bary = d.face_bary.row(3 * r + k).transpose();
    vv.cells = cells;
    d.voronoi_vertices.push_back(std::move(vv));
  }
  return is_vvertex;
}

// Cell adjacency and the refined edges separating two cells: (cell a, cell b, v0, v1), cell a <
// cell b, v0 < v1, sorted. Edges between two skipped vertices are not looked at. The refined edges
// (min, max, face) are bucketed by the smaller vertex (counting sort), then each bucket sorted.
std::vector<std::array<int, 4>> separating_edges(VoronoiDiagram& d, int num_sites, const std::vector<char>& interior) {
  const int nrv = static_cast<int>(d.V.rows()), nrf = static_cast<int>(d.F.rows());
  const int nv = static_cast<int>(interior.size());
  auto skipped = [&](int v) { return v < nv && interior[v]; };
  std::vector<int> bucket(nrv + 1, 0);
  for (int r = 0; r < nrf; ++r)
    for (int k = 0; k < 3; ++k) {
      const int a = d.F(r, k), b = d.F(r, (k + 1) % 3);
      if (!(skipped(a) && skipped(b))) ++bucket[std::min(a, b) + 1];
    }
  for (int v = 0; v < nrv; ++v) bucket[v + 1] += bucket[v];
  std::vector<std::array<int, 3>> half(bucket[nrv]);
  {
    std::vector<int> fill(bucket.begin(), bucket.end() - 1);
    for (int r = 0; r < nrf; ++r)
      for (int k = 0; k < 3; ++k) {
        const int a = d.F(r, k), b = d.F(r, (k + 1) % 3);
        if (!(skipped(a) && skipped(b))) half[fill[std::min(a, b)]++] = {std::min(a, b), std::max(a, b), r};
      }
  }
  for (int v = 0; v < nrv; ++v)
    if (bucket[v + 1] - bucket[v] > 1) std::sort(half.begin() + bucket[v], half.begin() + bucket[v + 1]);
  d.cell_adjacency.assign(num_sites, {});
  std::vector<std::array<int, 4>> separating;
  std::vector<int> cells;
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    cells.clear();
    for (size_t k = i; k < j; ++k)
      if (d.face_cell[half[k][2]] >= 0) cells.push_back(d.face_cell[half[k][2]]);
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    for (size_t x = 0; x < cells.size(); ++x)
      for (size_t y = x + 1; y < cells.size(); ++y) {
        d.cell_adjacency[cells[x]].push_back(cells[y]);
        d.cell_adjacency[cells[y]].push_back(cells[x]);
        separating.push_back({cells[x], cells[y], half[i][0], half[i][1]});
      }
    i = j;
  }
  for (auto& adj : d.cell_adjacency) {
    std::sort(adj.begin(), adj.end());
    adj.erase(std::unique(adj.begin(), adj.end()), adj.end());
  }
  std::sort(separating.begin(), separating.end());
  return separating;
}

// Chains the separating edges of each pair of cells into polylines (pairs in increasing order;
// within a pair: start at chain ends in increasing vertex order, neighbours in increasing order,
// then the closed loops). A polyline ends at Voronoi vertices and at branch points.
void chain_edges(VoronoiDiagram& d, const std::vector<std::array<int, 4>>& separating,
                 const std::vector<char>& is_vvertex) {
  d.edges.clear();
  std::vector<std::array<int, 3>> adj;  // (vertex, neighbour, edge slot) sorted
  std::vector<char> used;
  for (size_t i = 0; i < separating.size();) {
    size_t j = i;
    while (j < separating.size() && separating[j][0] == separating[i][0] && separating[j][1] == separating[i][1]) ++j;
    const int m = static_cast<int>(j - i);
    adj.clear();
    for (int e = 0; e < m; ++e) {
      adj.push_back({separating[i + e][2], separating[i + e][3], e});
      adj.push_back({separating[i + e][3], separating[i + e][2], e});
    }
    std::sort(adj.begin(), adj.end());
    used.assign(m, 0);
    auto range = [&](int v) {
      auto lo = std::lower_bound(adj.begin(), adj.end(), std::array<int, 3>{v, INT_MIN, INT_MIN});
      auto hi = lo;
      while (hi != adj.end() && (*hi)[0] == v) ++hi;
      return std::make_pair(lo, hi);
    };
    auto is_end = [&](int v) {
      auto [lo, hi] = range(v);
      return hi - lo != 2 || is_vvertex[v];
    };
    auto walk = [&](int start, int first_next, int slot) {
      VoronoiEdge e;
      e.cell_a = separating[i][0];
      e.cell_b = separating[i][1];
      e.polyline.push_back(start);
      int cur = first_next;
      used[slot] = 1;
      while (true) {
        e.polyline.push_back(cur);
        if (cur == start || is_end(cur)) break;
        auto [lo, hi] = range(cur);
        auto nxt = hi;
        for (auto it = lo; it != hi; ++it)
          if (!used[(*it)[2]]) {
            nxt = it;
            break;
          }
        if (nxt == hi) break;
        used[(*nxt)[2]] = 1;
        cur = (*nxt)[1];
      }
      d.edges.push_back(std::move(e));
    };
    for (size_t k = 0; k < adj.size(); ++k)
      if (!used[adj[k][2]] && is_end(adj[k][0])) walk(adj[k][0], adj[k][1], adj[k][2]);
    for (size_t k = 0; k < adj.size(); ++k)  // closed loops
      if (!used[adj[k][2]]) walk(adj[k][0], adj[k][1], adj[k][2]);
    i = j;
  }
}


// Adjacency, Voronoi vertices, edges and areas of a refined mesh whose faces carry cells.
// `interior[v]` (original vertices): every face around v took the fast path (one site strictly
// hottest at its three corners), so all faces around v are whole faces of one cell (that site is
// v's strict top). Such a vertex is no Voronoi vertex, and an edge joining two such vertices has
// two whole faces of the same cell on its sides. Both are skipped: on a typical diagram that is
// most of the mesh.
void finish_diagram(VoronoiDiagram& d, int num_sites, const std::vector<char>& interior) {
  d.cell_area = Eigen::VectorXd::Zero(num_sites);
  for (int r = 0; r < d.F.rows(); ++r)
    if (d.face_cell[r] >= 0) d.cell_area[d.face_cell[r]] += d.face_area[r];
  const std::vector<char> is_vvertex = find_voronoi_vertices(d, interior);
  chain_edges(d, separating_edges(d, num_sites, interior), is_vvertex);
}

}  // namespace

VoronoiDiagram tessellate(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatField& field,
                          const VoronoiOptions& options) {
  validate_mesh(V, F, "tessellate: mesh");
  const int nv = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  if (field.num_vertices() != nv)
    throw InvalidInputError("tessellate: the heat field has " + std::to_string(field.num_vertices()) +
                            " vertices but the mesh has " + std::to_string(nv));
  if (field.num_sites < 0 || static_cast<int>(field.site.size()) != field.offsets.back() ||
      field.heat.size() != field.site.size())
    throw InvalidInputError("tessellate: inconsistent heat field arrays");
  for (size_t k = 0; k < field.site.size(); ++k) {
    if (field.site[k] < 0 || field.site[k] >= field.num_sites)
      throw InvalidInputError("tessellate: heat field site index " + std::to_string(field.site[k]) +
                              " out of range [0, " + std::to_string(field.num_sites) + ")");
    if (!std::isfinite(field.heat[k])) throw InvalidInputError("tessellate: heat field has a non-finite value");
  }
  if (!(options.edge_merge_tolerance >= 0) || !(options.weld_tolerance >= 0) || !(options.flat_tolerance >= 0) ||
      !(options.orientation_tolerance >= 0) || !(options.tiling_tolerance >= 0))
    throw InvalidInputError("tessellate: the tolerances of VoronoiOptions must be >= 0");
  const int threads = resolve_threads(options.threads);

  std::vector<FaceResult> results(nf);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 256)
  for (int f = 0; f < nf; ++f) results[f] = tessellate_face(F, field, f, options);

  // assemble in face order (deterministic)
  VoronoiDiagram d;
  size_t num_tris = 0, num_new = 0;
  for (const FaceResult& r : results) {
    num_tris += r.whole ? 1 : r.tris.size();
    for (const LocalPoint& p : r.points) num_new += p.kind != LocalPoint::Corner;
  }
  std::vector<Eigen::Vector3d> new_points;
  new_points.reserve(num_new);
  struct KeyHash {
    size_t operator()(const std::array<int, 4>& k) const {
      uint64_t h = 1469598103934665603ull;
      for (int x : k) h = (h ^ static_cast<uint32_t>(x)) * 1099511628211ull;
      return static_cast<size_t>(h ^ (h >> 29));
    }
  };
  std::unordered_map<std::array<int, 4>, int, KeyHash> edge_ids;  // lookups only: order never used
  d.F.resize(num_tris, 3);
  d.face_cell.resize(num_tris);
  d.face_parent.resize(num_tris);
  d.face_bary.resize(3 * num_tris, 3);
  d.face_area.resize(num_tris);
  const Eigen::VectorXd parent_area = face_areas(V, F);
  int row = 0;
  std::vector<int> gid;
  for (int f = 0; f < nf; ++f) {
    const FaceResult& r = results[f];
    if (r.whole) {
      d.F.row(row) = F.row(f);
      d.face_bary.middleRows<3>(3 * row).setIdentity();
      d.face_cell[row] = r.cell;
      d.face_parent[row] = f;
      d.face_area[row] = parent_area[f];
      ++row;
      continue;
    }
    gid.resize(r.points.size());
    for (size_t i = 0; i < r.points.size(); ++i) {
      const LocalPoint& p = r.points[i];
      if (p.kind == LocalPoint::Corner) {
        gid[i] = p.vertex;
      } else if (p.kind == LocalPoint::OnEdge) {
        auto it = edge_ids.find(p.key);
        if (it != edge_ids.end()) {
          gid[i] = it->second;
        } else {
          gid[i] = nv + static_cast<int>(new_points.size());
          edge_ids.emplace(p.key, gid[i]);
          new_points.push_back((1.0 - p.t) * V.row(p.key[0]).transpose() + p.t * V.row(p.key[1]).transpose());
        }
      } else {
        gid[i] = nv + static_cast<int>(new_points.size());
        new_points.push_back(p.bary[0] * V.row(F(f, 0)).transpose() + p.bary[1] * V.row(F(f, 1)).transpose() +
                             p.bary[2] * V.row(F(f, 2)).transpose());
      }
    }
    for (size_t k = 0; k < r.tris.size(); ++k, ++row) {
      for (int c = 0; c < 3; ++c) {
        d.F(row, c) = gid[r.tris[k][c]];
        d.face_bary.row(3 * row + c) = r.points[r.tris[k][c]].bary.transpose();
      }
      d.face_cell[row] = r.cells[k];
      d.face_parent[row] = f;
      d.face_area[row] = parent_area[f] * bary_det(r.points[r.tris[k][0]].bary, r.points[r.tris[k][1]].bary,
                                                   r.points[r.tris[k][2]].bary);
    }
  }
  d.V.resize(nv + new_points.size(), 3);
  d.V.topRows(nv) = V;
  for (size_t i = 0; i < new_points.size(); ++i) d.V.row(nv + i) = new_points[i].transpose();

  // components without any site
  Eigen::VectorXi comp;
  const int ncomp = connected_components(nv, F, comp);
  std::vector<char> has_face(ncomp, 0), reached(ncomp, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) has_face[comp[F(f, k)]] = 1;
  for (int v = 0; v < nv; ++v)
    if (field.offsets[v + 1] > field.offsets[v]) reached[comp[v]] = 1;
  for (int c = 0; c < ncomp; ++c)
    if (has_face[c] && !reached[c]) d.unreached_components.push_back(c);

  std::vector<char> interior(nv, 1);
  for (int f = 0; f < nf; ++f)
    if (!results[f].fast)
      for (int k = 0; k < 3; ++k) interior[F(f, k)] = 0;
  finish_diagram(d, field.num_sites, interior);
  return d;
}

VoronoiDiagram heat_voronoi(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const HeatSolver& solver,
                            const std::vector<SurfacePoint>& sites, const VoronoiOptions& options) {
  validate_mesh(V, F, "heat_voronoi: mesh");
  if (sites.empty()) throw InvalidInputError("heat_voronoi: no sites given");
  if (solver.num_vertices() != V.rows())
    throw InvalidInputError("heat_voronoi: the solver has " + std::to_string(solver.num_vertices()) +
                            " vertices but the mesh has " + std::to_string(V.rows()));
  if (options.keep_sites_per_vertex < 1)
    throw InvalidInputError("heat_voronoi: keep_sites_per_vertex must be >= 1");
  for (size_t s = 0; s < sites.size(); ++s) {
    const SurfacePoint& p = sites[s];
    if (p.face < 0 || p.face >= F.rows())
      throw InvalidInputError("heat_voronoi: site " + std::to_string(s) + " has face index " + std::to_string(p.face) +
                              " out of range [0, " + std::to_string(F.rows()) + ")");
    if (!p.bary.allFinite())
      throw InvalidInputError("heat_voronoi: site " + std::to_string(s) + " has non-finite barycentric coordinates");
  }
  // Batched solves in blocks of columns; the `keep` hottest sites per vertex are merged block by
  // block, so memory is #V·(keep + block) instead of #V·#sites. Same result as
  // heat_field_from_dense on the full matrix (order: heat descending, then site ascending).
  const int nv = static_cast<int>(V.rows()), ns = static_cast<int>(sites.size());
  const int block = std::max(1, options.solve_block);
  const int threads = resolve_threads(options.threads);
  TopKField top(nv, options.keep_sites_per_vertex);
  for (int s0 = 0; s0 < ns; s0 += block) {
    const int nb = std::min(block, ns - s0);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(V.rows(), nb);
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < 3; ++k) rhs(F(sites[s0 + j].face, k), j) += sites[s0 + j].bary[k];  // eq. 8
    const Eigen::MatrixXd U = solver.solve(rhs);
    if (!U.allFinite()) throw SolverError("heat_voronoi: the heat solve produced non-finite values");
    top.add_columns(U, s0, threads);
  }
  const HeatField field = top.finish(ns);
  return tessellate(V, F, field, options);
}

std::vector<std::vector<std::pair<int, double>>> cell_load_vectors(const VoronoiDiagram& diagram,
                                                                    const Eigen::MatrixX3i& F) {
  const int nc = diagram.num_cells();
  std::vector<std::map<int, double>> acc(nc);
  for (int r = 0; r < diagram.F.rows(); ++r) {
    const int c = diagram.face_cell[r];
    if (c < 0 || c >= nc) continue;
    const int parent = diagram.face_parent[r];
    if (parent < 0 || parent >= F.rows())
      throw InvalidInputError("cell_load_vectors: F does not match the diagram (parent face out of range)");
    const double A = diagram.face_area[r];
    for (int k = 0; k < 3; ++k) {
      const double w = diagram.face_bary(3 * r, k) + diagram.face_bary(3 * r + 1, k) + diagram.face_bary(3 * r + 2, k);
      acc[c][F(parent, k)] += A * w / 3.0;
    }
  }
  std::vector<std::vector<std::pair<int, double>>> out(nc);
  for (int c = 0; c < nc; ++c) out[c].assign(acc[c].begin(), acc[c].end());
  return out;
}

std::vector<std::pair<int, double>> cell_load_vector(const VoronoiDiagram& diagram, const Eigen::MatrixX3i& F,
                                                      int cell) {
  if (cell < 0 || cell >= diagram.num_cells())
    throw InvalidInputError("cell_load_vector: cell " + std::to_string(cell) + " out of range [0, " +
                            std::to_string(diagram.num_cells()) + ")");
  std::map<int, double> acc;
  for (int r = 0; r < diagram.F.rows(); ++r) {
    if (diagram.face_cell[r] != cell) continue;
    const int parent = diagram.face_parent[r];
    if (parent < 0 || parent >= F.rows())
      throw InvalidInputError("cell_load_vector: F does not match the diagram (parent face out of range)");
    const double A = diagram.face_area[r];
    for (int k = 0; k < 3; ++k) {
      const double w = diagram.face_bary(3 * r, k) + diagram.face_bary(3 * r + 1, k) + diagram.face_bary(3 * r + 2, k);
      acc[F(parent, k)] += A * w / 3.0;
    }
  }
  return {acc.begin(), acc.end()};
}

void refined_vertex_faces(const VoronoiDiagram& d, std::vector<int>& offsets, std::vector<int>& faces) {
  const int nrv = static_cast<int>(d.V.rows()), nrf = static_cast<int>(d.F.rows());
  offsets.assign(nrv + 1, 0);
  for (int r = 0; r < nrf; ++r)
    for (int k = 0; k < 3; ++k) ++offsets[d.F(r, k) + 1];
  for (int v = 0; v < nrv; ++v) offsets[v + 1] += offsets[v];
  faces.resize(offsets[nrv]);
  std::vector<int> fill(offsets.begin(), offsets.end() - 1);
  for (int r = 0; r < nrf; ++r)
    for (int k = 0; k < 3; ++k) faces[fill[d.F(r, k)]++] = r;
}

std::vector<std::vector<int>> cell_faces(const VoronoiDiagram& diagram) {
  std::vector<std::vector<int>> out(diagram.num_cells());
  for (int r = 0; r < diagram.F.rows(); ++r) {
    const int c = diagram.face_cell[r];
    if (c >= 0 && c < diagram.num_cells()) out[c].push_back(r);
  }
  return out;
}

}  // namespace heatcvt
