#include "heatcvt/point_laplacian.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"
#include "parallel_sort.h"

namespace heatcvt {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;

/// One triangle of a point's local fan: corners (CCW around that point's PCA normal), the
/// cotangent of the angle at each corner measured in that point's tangent plane, 3D area.
struct LocalTriangle {
  std::array<int, 3> v;
  std::array<double, 3> cot;
  double area = 0;
};

struct LocalFan {
  std::vector<LocalTriangle> triangles;
  int degenerate = 0;
};


/// Heron's formula, stable form; 0 if the lengths violate the triangle inequality.
double triangle_area(double a, double b, double c) {
  double s[3] = {a, b, c};
  std::sort(s, s + 3, std::greater<double>());
  const double x = s[0], y = s[1], z = s[2];
  const double q = (x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z));
  return q > 0 ? 0.25 * std::sqrt(q) : 0.0;
}

/// Cotangent of the angle opposite the side of length a in the triangle (a, b, c).
double cot_opposite(double a, double b, double c, double area, double clamp) {
  if (!(area > 0)) return 0.0;
  return std::clamp((b * b + c * c - a * a) / (4.0 * area), -clamp, clamp);
}

/// Intrinsic Delaunay cotan Laplacian of the tufted cover of a triangle soup (Sharp & Crane
/// 2020, §4–5): every soup face gets a front and a back sheet; around an edge with m soup faces
/// the sheets are glued in the (deterministic) soup order, the up-going half-edge of face i to
/// the down-going one of face i+1 (mod m), which yields a closed oriented manifold. Edge lengths
/// are the 3D lengths, mollified by δ so every corner has slack ≥ ε·h̄; then Lawson flips until
/// every edge satisfies cot α + cot β ≥ 0. Contributions (scaled by `scale` and by ½ for the two
/// sheets) are appended to `edge_weights` (key = min·n + max) and `M`. Returns the flip count.
struct TuftedResult {
  int64_t flips = 0;
  int64_t skipped = 0;  // non-Delaunay edges that could not be flipped (combinatorial guards)
};

// The tufted cover of a triangle soup (Sharp & Crane 2020, §4): two sheets per triangle, as
// half-edges 3·s + c of sheet s ∈ {2f (front), 2f+1 (back)} with intrinsic lengths.
struct TuftedCover {
  std::vector<int> tail;
  std::vector<int64_t> next, twin;
  std::vector<double> len;
};

// Both sheets of every triangle, with their next pointers (no twins yet).
TuftedCover tufted_sheets(const std::vector<std::array<int, 3>>& soup) {
  const int64_t nf = static_cast<int64_t>(soup.size());
  const int64_t nh = 6 * nf;
  TuftedCover c;
  c.tail.resize(nh);
  c.next.resize(nh);
  c.twin.assign(nh, -1);
  c.len.resize(nh);
  std::vector<int>& tail = c.tail;
  std::vector<int64_t>& next = c.next;
  for (int64_t f = 0; f < nf; ++f) {
    const std::array<int, 3>& t = soup[f];
    const int front[3] = {t[0], t[1], t[2]}, back[3] = {t[0], t[2], t[1]};
    for (int c = 0; c < 3; ++c) {
      tail[6 * f + c] = front[c];
      tail[6 * f + 3 + c] = back[c];
      next[6 * f + c] = 6 * f + (c + 1) % 3;
      next[6 * f + 3 + c] = 6 * f + 3 + (c + 1) % 3;
    }
  }
  return c;
}

void glue_sheets(TuftedCover& c, const Eigen::MatrixX3d& P, int threads) {
  std::vector<int>& tail = c.tail;
  std::vector<int64_t>& next = c.next;
  std::vector<int64_t>& twin = c.twin;
  const int64_t nh = static_cast<int64_t>(tail.size());
  const int64_t n = P.rows();
  const int64_t nf = nh / 6;
  // Gluing: per undirected edge (a < b), the faces sorted by the angle of their third vertex
  // around the axis a→b (ties: soup order), then interleaved s0, s_h, s1, s_h+1, … (h = ⌈m/2⌉)
  // so that the faces on opposite sides of the edge alternate; consecutive faces are glued, the
  // up-going (a→b) half-edge of one to the down-going one of the next (cyclically). For the
  // repeated copies of two consistent neighbours T, T' this pairs every copy of T with a copy of
  // T' (a flat quad) instead of folding T onto its own copy.
  struct Side {
    int64_t key, face, up, down;
    int third;
    double angle;
  };
  std::vector<Side> sides(3 * nf);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int64_t f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      const int64_t hf = 6 * f + c;  // front half-edge tail → head
      const int a = tail[hf], b = tail[next[hf]], third = tail[next[next[hf]]];
      // Back half-edge of the same edge goes b → a.
      int64_t hb = -1;
      for (int d = 0; d < 3; ++d) {
        const int64_t g = 6 * f + 3 + d;
        if (tail[g] == b && tail[next[g]] == a) hb = g;
      }
      const int64_t key = std::min<int64_t>(a, b) * n + std::max<int64_t>(a, b);
      sides[3 * f + c] = a < b ? Side{key, f, hf, hb, third, 0.0} : Side{key, f, hb, hf, third, 0.0};
    }
  parallel_sort(sides.begin(), sides.end(), threads,
                [](const Side& x, const Side& y) { return x.key != y.key ? x.key < y.key : x.face < y.face; });
  // Groups of one edge each; they write disjoint twins, so they are glued on all threads.
  std::vector<size_t> starts;
  for (size_t r = 0; r < sides.size(); ++r)
    if (r == 0 || sides[r].key != sides[r - 1].key) starts.push_back(r);
  starts.push_back(sides.size());
  const int64_t groups = static_cast<int64_t>(starts.size()) - 1;
#pragma omp parallel num_threads(threads)
  {
    std::vector<Side> order;
#pragma omp for schedule(dynamic, 4096)
    for (int64_t g = 0; g < groups; ++g) {
      const size_t r = starts[g], e = starts[g + 1], m = e - r;
      const int a = static_cast<int>(sides[r].key / n), b = static_cast<int>(sides[r].key % n);
      const Eigen::Vector3d pa = P.row(a).transpose();
      const Eigen::Vector3d axis = (P.row(b).transpose() - pa).normalized();
      Eigen::Vector3d ref = P.row(sides[r].third).transpose() - pa;
      ref = (ref - ref.dot(axis) * axis).normalized();
      const Eigen::Vector3d ortho = axis.cross(ref);
      for (size_t i = r; i < e; ++i) {
        const Eigen::Vector3d d = P.row(sides[i].third).transpose() - pa;
        double ang = std::atan2(d.dot(ortho), d.dot(ref));
        if (!std::isfinite(ang)) ang = 0;
        sides[i].angle = ang < 0 ? ang + 2 * M_PI : ang;
      }
      std::stable_sort(sides.begin() + r, sides.begin() + e,
                       [](const Side& x, const Side& y) { return x.angle < y.angle; });
      order.clear();
      const size_t h = (m + 1) / 2;
      for (size_t i = 0; i < h; ++i) {
        order.push_back(sides[r + i]);
        if (h + i < m) order.push_back(sides[r + h + i]);
      }
      for (size_t i = 0; i < m; ++i) {
        const int64_t up = order[i].up, down = order[(i + 1) % m].down;
        twin[up] = down;
        twin[down] = up;
      }
    }
  }
}

void set_mollified_lengths(TuftedCover& c, const Eigen::MatrixX3d& P, double mollify_factor, int threads) {
  std::vector<int>& tail = c.tail;
  std::vector<int64_t>& next = c.next;
  std::vector<double>& len = c.len;
  const int64_t nh = static_cast<int64_t>(tail.size());
  // Lengths with mollification (Sharp & Crane §4.5); the mean is summed in half-edge order.
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int64_t h = 0; h < nh; ++h) len[h] = (P.row(tail[h]) - P.row(tail[next[h]])).norm();
  double mean_len = 0;
  for (int64_t h = 0; h < nh; ++h) mean_len += len[h];
  mean_len /= static_cast<double>(nh);
  const double eps = mollify_factor * mean_len;
  double delta = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(max : delta)
  for (int64_t h = 0; h < nh; ++h) {
    const double a = len[h], b = len[next[h]], c = len[next[next[h]]];
    delta = std::max(delta, eps - (b + c - a));
  }
  if (delta > 0)
    for (double& l : len) l += delta;
}

// Lawson flips of the cover's non-Delaunay edges (cotangent sum below zero).
// Every edge is queued once, in ascending order of its first half-edge; a flip queues the four
// edges around it again. Whether an edge is Delaunay depends only on its two faces, so the
// verdicts of the edges no flip has touched yet are computed beforehand on every thread.
TuftedResult flip_to_delaunay(TuftedCover& c, double cot_clamp, int threads) {
  std::vector<int>& tail = c.tail;
  std::vector<int64_t>& next = c.next;
  std::vector<int64_t>& twin = c.twin;
  std::vector<double>& len = c.len;
  const int64_t nh = static_cast<int64_t>(tail.size());
  auto halfedge_cot = [&](int64_t h) {  // cot of the angle opposite h in its face
    const double a = len[h], b = len[next[h]], c = len[next[next[h]]];
    return cot_opposite(a, b, c, triangle_area(a, b, c), cot_clamp);
  };
  auto delaunay = [&](int64_t h) { return halfedge_cot(h) + halfedge_cot(twin[h]) >= -1e-10; };
  std::vector<char> delaunay_at_start(nh, 0), touched(nh, 0);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int64_t h = 0; h < nh; ++h)
    if (h < twin[h]) delaunay_at_start[h] = delaunay(h);
  TuftedResult result;
  std::vector<int64_t> stack;
  std::vector<char> queued(nh, 0);
  for (int64_t h = nh - 1; h >= 0; --h)
    if (h < twin[h]) {
      stack.push_back(h);
      queued[h] = 1;
    }
  const int64_t max_flips = 50 * nh + 1000;  // Lawson terminates; the cap only guards rounding loops
  while (!stack.empty()) {
    int64_t h = stack.back();
    stack.pop_back();
    queued[h] = 0;
    const int64_t t = twin[h];
    if (touched[h] ? delaunay(h) : delaunay_at_start[h]) continue;
    const int64_t h1 = next[h], h2 = next[h1], t1 = next[t], t2 = next[t1];
    // Guards: distinct faces, no endpoint of degree 2 (the flip would leave a degree-1 vertex).
    if (t == h1 || t == h2 || result.flips >= max_flips) {
      ++result.skipped;
      continue;
    }
    // Lay out i = (0,0), j = (L,0), k above, l below; the new diagonal is |k − l|.
    const double L = len[h];
    const double ik = len[h2], jk = len[h1], il = len[t1], jl = len[t2];
    const double kx = (L * L + ik * ik - jk * jk) / (2 * L);
    const double ky = std::sqrt(std::max(0.0, ik * ik - kx * kx));
    const double lx = (L * L + il * il - jl * jl) / (2 * L);
    const double ly = -std::sqrt(std::max(0.0, il * il - lx * lx));
    const double kl = std::hypot(kx - lx, ky - ly);
    if (!(kl > 0) || !(triangle_area(kl, ik, il) > 0) || !(triangle_area(kl, jk, jl) > 0)) {
      ++result.skipped;
      continue;
    }
    const int k = tail[h2], l = tail[t2];
    // Face A' = (h: l→k, h2: k→i, t1: i→l), face B' = (t: k→l, t2: l→j, h1: j→k).
    tail[h] = l;
    tail[t] = k;
    len[h] = len[t] = kl;
    next[h] = h2, next[h2] = t1, next[t1] = h;
    next[t] = t2, next[t2] = h1, next[h1] = t;
    ++result.flips;
    touched[h] = 1;
    for (int64_t g : {h1, h2, t1, t2}) {
      const int64_t rep = std::min(g, twin[g]);
      touched[rep] = 1;
      if (!queued[rep]) {
        queued[rep] = 1;
        stack.push_back(rep);
      }
    }
  }
  return result;
}

// Cotan weights and masses of the final triangulation: every half-edge lies in one face.
// (The areas and cotangents on every thread, then added in half-edge order.)
void add_cover_weights(const TuftedCover& c, int64_t n, double cot_clamp, double scale, int threads,
                       std::vector<std::pair<int64_t, double>>& edge_weights, Eigen::VectorXd& M) {
  const std::vector<int>& tail = c.tail;
  const std::vector<int64_t>& next = c.next;
  const std::vector<double>& len = c.len;
  const int64_t nh = static_cast<int64_t>(tail.size());
  const double w_scale = 0.5 * scale;  // ½ for the two sheets
  std::vector<double> area(nh), cot(nh);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int64_t h = 0; h < nh; ++h) {
    const double la = len[h], lb = len[next[h]], lc = len[next[next[h]]];
    area[h] = triangle_area(la, lb, lc);
    cot[h] = cot_opposite(la, lb, lc, area[h], cot_clamp);
  }
  for (int64_t h = 0; h < nh; ++h) {
    const int a = tail[h], b = tail[next[h]];
    M[a] += w_scale * area[h] / 3.0;
    if (a == b) continue;  // an intrinsic loop adds nothing to L u
    const int64_t key = std::min<int64_t>(a, b) * n + std::max<int64_t>(a, b);
    edge_weights.emplace_back(key, w_scale * 0.5 * cot[h]);
  }
}

TuftedResult tufted_intrinsic_delaunay(const std::vector<std::array<int, 3>>& soup, const Eigen::MatrixX3d& P,
                                       double mollify_factor, double cot_clamp, double scale, int threads,
                                       std::vector<std::pair<int64_t, double>>& edge_weights, Eigen::VectorXd& M) {
  TuftedCover cover = tufted_sheets(soup);
  glue_sheets(cover, P, threads);
  set_mollified_lengths(cover, P, mollify_factor, threads);
  const TuftedResult result = flip_to_delaunay(cover, cot_clamp, threads);
  add_cover_weights(cover, P.rows(), cot_clamp, scale, threads, edge_weights, M);
  return result;
}

// The k nearest neighbours of every point: the given table (checked) or a fresh kNN search.
Eigen::MatrixXi neighbour_table(const Eigen::MatrixX3d& P, const PointLaplacianOptions& options, int threads) {
  const int n = static_cast<int>(P.rows()), k = options.k;
  Eigen::MatrixXi nb;
  if (options.neighbors) {
    const Eigen::MatrixXi& given = *options.neighbors;
    if (given.rows() != n || given.cols() < k)
      throw InvalidInputError("point_laplacian: the neighbour table is " + std::to_string(given.rows()) + " by " +
                              std::to_string(given.cols()) + ", need " + std::to_string(n) + " by at least " +
                              std::to_string(k));
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if (!P.row(i).allFinite())
        throw InvalidInputError("point_laplacian: point " + std::to_string(i) + " has a NaN or infinite coordinate");
    if ((given.leftCols(k).array() < 0).any() || (given.leftCols(k).array() >= n).any())
      throw InvalidInputError("point_laplacian: the neighbour table has an index outside [0, " + std::to_string(n) + ")");
    nb = given.leftCols(k);
  } else {
    nb = k_nearest_neighbors(P, k, threads);  // validates finiteness too (throws naming the point)
  }

  return nb;
}

}  // namespace

bool across_thin_part(const Eigen::RowVector3d& a, const Eigen::RowVector3d& na, const Eigen::RowVector3d& b,
                      const Eigen::RowVector3d& nb, double min_offset, double max_dot) {
  const double dot = na.dot(nb);
  if (dot >= 0) return false;
  if (min_offset <= 0) return true;
  if (dot > max_dot) return false;
  const Eigen::RowVector3d d = b - a;
  return std::abs(d.dot(na)) >= min_offset * d.norm();
}

namespace {

// The local triangles of point i (paper §8, Sharp & Crane 2020): PCA frame of the point and its
// k neighbours, their projection to the tangent plane, its Delaunay triangulation, and the
// triangles incident to the centre with their cotangents. `dt`, `q`, `ids` are per-thread work
// space; the unit normal goes to `normal`.
LocalFan local_fan(const Eigen::MatrixX3d& P, const Eigen::MatrixXi& nb, int i, const PointLaplacianOptions& options,
                   Delaunay& dt, std::vector<Eigen::Vector2d>& q, std::vector<int>& ids, Eigen::RowVector3d& normal) {
  const int k = options.k;
  const Eigen::MatrixX3d* on = options.oriented_normals;
  LocalFan fan;
  // PCA frame of the point and its neighbours.
  ids[0] = i;
  for (int c = 0; c < k; ++c) ids[c + 1] = nb(i, c);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int id : ids) mean += P.row(id).transpose();
  mean /= (k + 1);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  double mean_sq = 0;
  for (int id : ids) {
    const Eigen::Vector3d d = P.row(id).transpose() - mean;
    C += d * d.transpose();
    mean_sq += (P.row(id) - P.row(i)).squaredNorm();
  }
  mean_sq /= k;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d nrm = es.eigenvectors().col(0);
  Eigen::Vector3d e1 = es.eigenvectors().col(2);
  if (!nrm.allFinite() || !e1.allFinite()) {
    nrm = Eigen::Vector3d::UnitZ();
    e1 = Eigen::Vector3d::UnitX();
  }
  nrm.normalize();
  e1 = (e1 - e1.dot(nrm) * nrm).normalized();
  const Eigen::Vector3d e2 = nrm.cross(e1);  // (e1, e2, n) right-handed: CCW seen from +n
  normal = nrm.transpose();

  // Projected neighbourhood and its Delaunay triangulation, the centre inserted first so
  // that it survives if a neighbour coincides with it.
  dt.clear();
  const Eigen::Vector3d pi = P.row(i).transpose();
  for (int c = 0; c <= k; ++c) {
    const Eigen::Vector3d d = P.row(ids[c]).transpose() - pi;
    q[c] = Eigen::Vector2d(d.dot(e1), d.dot(e2));
  }
  Delaunay::Vertex_handle centre = dt.insert(Kernel::Point_2(0.0, 0.0));
  centre->info() = 0;
  auto across = [&](int a, int b) {
    return across_thin_part(P.row(a), on->row(a), P.row(b), on->row(b), options.across_min_offset,
                            options.across_max_dot);
  };
  for (int c = 1; c <= k; ++c) {
    if (on && across(i, ids[c])) continue;
    const auto before = dt.number_of_vertices();
    Delaunay::Vertex_handle vh = dt.insert(Kernel::Point_2(q[c].x(), q[c].y()));
    if (dt.number_of_vertices() != before) vh->info() = c;  // else: duplicate, keep the first
  }
  if (dt.dimension() < 2) return fan;
  const double min_area = options.degenerate_area_epsilon * mean_sq;
  Delaunay::Face_circulator fc = dt.incident_faces(centre), done = fc;
  do {
    if (dt.is_infinite(fc)) continue;
    int local[3];
    for (int c = 0; c < 3; ++c) local[c] = fc->vertex(c)->info();
    // Rotate so the centre comes first (keeps CCW order, makes output deterministic).
    while (local[0] != 0) std::rotate(local, local + 1, local + 3);
    if (on && (across(ids[local[0]], ids[local[1]]) || across(ids[local[1]], ids[local[2]]) ||
               across(ids[local[0]], ids[local[2]])))
      continue;
    const Eigen::Vector2d a = q[local[0]], b = q[local[1]], d = q[local[2]];
    const double twice_area2d = (b - a).x() * (d - a).y() - (b - a).y() * (d - a).x();
    if (!(0.5 * twice_area2d > min_area) || !(twice_area2d > 0)) {
      ++fan.degenerate;
      continue;
    }
    LocalTriangle t;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector2d& x = q[local[c]];
      const Eigen::Vector2d u = q[local[(c + 1) % 3]] - x, w = q[local[(c + 2) % 3]] - x;
      t.cot[c] = std::clamp(u.dot(w) / twice_area2d, -options.cot_clamp, options.cot_clamp);
      t.v[c] = ids[local[c]];
    }
    const Eigen::Vector3d A = P.row(t.v[0]), B = P.row(t.v[1]), D = P.row(t.v[2]);
    t.area = 0.5 * (B - A).cross(D - A).norm();
    fan.triangles.push_back(t);
  } while (++fc != done);
  return fan;
}

// Sums the per-edge contributions (sorted: deterministic order), clamps negative weights and
// assembles L, the lumped masses M (floored at min_mass_fraction of the mean) and h̄.
void assemble_laplacian(const Eigen::MatrixX3d& P, std::vector<std::pair<int64_t, double>>& edge_weights,
                        Eigen::VectorXd M, const PointLaplacianOptions& options, int threads, PointLaplacian& out) {
  const int n = static_cast<int>(P.rows());
  parallel_sort(edge_weights.begin(), edge_weights.end(), threads);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(edge_weights.size());
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(n);
  double length_sum = 0;
  int64_t edge_count = 0;
  for (size_t r = 0; r < edge_weights.size();) {
    const int64_t key = edge_weights[r].first;
    double w = 0;
    for (; r < edge_weights.size() && edge_weights[r].first == key; ++r) w += edge_weights[r].second;
    const int a = static_cast<int>(key / n), b = static_cast<int>(key % n);
    if (w < 0) {
      ++out.clamped_edges;
      out.most_negative_weight = std::min(out.most_negative_weight, w);
      continue;
    }
    if (w == 0) continue;
    triplets.emplace_back(a, b, w);
    triplets.emplace_back(b, a, w);
    diag[a] -= w;
    diag[b] -= w;
  }
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, diag[i]);
  {  // h̄: mean 3D length of the distinct edges of the local triangles
    std::vector<int64_t> keys;
    keys.reserve(3 * static_cast<size_t>(out.triangles.rows()));
    for (Eigen::Index t = 0; t < out.triangles.rows(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int a = out.triangles(t, c), b = out.triangles(t, (c + 1) % 3);
        keys.push_back(static_cast<int64_t>(std::min(a, b)) * n + std::max(a, b));
      }
    parallel_sort(keys.begin(), keys.end(), threads);
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (int64_t key : keys) length_sum += (P.row(static_cast<int>(key / n)) - P.row(static_cast<int>(key % n))).norm();
    edge_count = static_cast<int64_t>(keys.size());
  }

  Laplacian& lap = out.laplacian;
  lap.L.resize(n, n);
  lap.L.setFromTriplets(triplets.begin(), triplets.end());
  lap.L.makeCompressed();
  lap.mean_edge_length = edge_count > 0 ? length_sum / static_cast<double>(edge_count) : 0.0;
  const Eigen::Index positive = (M.array() > 0).count();
  const double floor_mass = options.min_mass_fraction * M.sum() / static_cast<double>(std::max<Eigen::Index>(1, positive));
  for (int i = 0; i < n; ++i)
    if (!(M[i] > 0)) {
      ++out.isolated_points;
      M[i] = floor_mass;
    } else if (M[i] < floor_mass) {
      M[i] = floor_mass;
    }
  lap.M = std::move(M);
}

}  // namespace

PointLaplacian point_laplacian(const Eigen::MatrixX3d& P, const PointLaplacianOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int k = options.k;
  if (k < 3) throw InvalidInputError("point_laplacian: k = " + std::to_string(k) + " is too small (need k >= 3)");
  if (options.threads < 0)
    throw InvalidInputError("point_laplacian: threads = " + std::to_string(options.threads) + " is negative");
  if (P.rows() < static_cast<Eigen::Index>(k) + 1)
    throw InvalidInputError("point_laplacian: the cloud has " + std::to_string(P.rows()) +
                            " points, need at least k + 1 = " + std::to_string(k + 1));
  if (!(options.cot_clamp > 0) || !(options.degenerate_area_epsilon >= 0) || !(options.min_mass_fraction > 0) ||
      !(options.mollify_factor >= 0) || !(options.across_min_offset >= 0 && options.across_min_offset <= 1) ||
      !(options.across_max_dot >= -1 && options.across_max_dot <= 0))
    throw InvalidInputError("point_laplacian: cot_clamp and min_mass_fraction must be > 0, "
                            "degenerate_area_epsilon and mollify_factor >= 0, across_min_offset in [0, 1], across_max_dot in [-1, 0]");
  const int n = static_cast<int>(P.rows());
  const int threads = resolve_threads(options.threads);
  const Eigen::MatrixXi nb = neighbour_table(P, options, threads);

  const Eigen::MatrixX3d* on = options.oriented_normals;
  if (on && on->rows() != n)
    throw InvalidInputError("point_laplacian: " + std::to_string(on->rows()) + " oriented normals for " +
                            std::to_string(n) + " points");
  PointLaplacian out;
  out.normals.resize(n, 3);
  std::vector<LocalFan> fans(n);

#pragma omp parallel num_threads(threads)
  {
    Delaunay dt;
    std::vector<Eigen::Vector2d> q(k + 1);
    std::vector<int> ids(k + 1);
    Eigen::RowVector3d normal;
#pragma omp for schedule(dynamic, 64)
    for (int i = 0; i < n; ++i) {
      fans[i] = local_fan(P, nb, i, options, dt, q, ids, normal);
      out.normals.row(i) = normal;
    }
  }

  // Sequential, ordered merge: results do not depend on the thread count.
  std::vector<std::pair<int64_t, double>> edge_weights;
  std::vector<std::pair<std::array<int, 3>, int64_t>> keyed;  // (sorted corners, occurrence)
  std::vector<std::array<int, 3>> all_tris;  // the soup, with repetitions, in point order
  Eigen::VectorXd M = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    out.degenerate_triangles += fans[i].degenerate;
    for (const LocalTriangle& t : fans[i].triangles) {
      if (!options.intrinsic_delaunay)
        for (int c = 0; c < 3; ++c) {
          M[t.v[c]] += t.area / 9.0;  // (1/3 weight) · (area / 3 per corner), eq. 6
          const int a = t.v[(c + 1) % 3], b = t.v[(c + 2) % 3];
          const int64_t key = static_cast<int64_t>(std::min(a, b)) * n + std::max(a, b);
          edge_weights.emplace_back(key, t.cot[c] / 6.0);  // (1/3 weight) · ½ cot, eq. 5
        }
      std::array<int, 3> s = t.v;
      std::sort(s.begin(), s.end());
      keyed.emplace_back(s, static_cast<int64_t>(all_tris.size()));
      all_tris.push_back(t.v);
    }
  }
  if (keyed.empty())
    throw InvalidInputError("point_laplacian: no local triangle could be built (the " + std::to_string(n) +
                            " points are collinear or coincident)");
  if (options.intrinsic_delaunay) {
    const TuftedResult r = tufted_intrinsic_delaunay(all_tris, P, options.mollify_factor, options.cot_clamp,
                                                     1.0 / 3.0, threads, edge_weights, M);
    out.intrinsic_flips = r.flips;
    out.unflippable_edges = r.skipped;
  }

  // Distinct triangles, first occurrence kept, in order of occurrence.
  parallel_sort(keyed.begin(), keyed.end(), threads);
  std::vector<int64_t> firsts;
  for (size_t r = 0; r < keyed.size(); ++r)
    if (r == 0 || keyed[r].first != keyed[r - 1].first) firsts.push_back(keyed[r].second);
  std::sort(firsts.begin(), firsts.end());
  out.triangles.resize(static_cast<Eigen::Index>(firsts.size()), 3);
  for (size_t r = 0; r < firsts.size(); ++r)
    for (int c = 0; c < 3; ++c) out.triangles(static_cast<Eigen::Index>(r), c) = all_tris[firsts[r]][c];

  assemble_laplacian(P, edge_weights, std::move(M), options, threads, out);
  out.neighbors = nb;
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace heatcvt
