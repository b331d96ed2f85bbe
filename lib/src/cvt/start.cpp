// The start of a CVT: initial sites, graph Lloyd, surface Lloyd. See cvt/start.h.
#include "heatcvt/cvt/start.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <random>
#include <string>
#include <utility>

#include "heatcvt/cvt.h"
#include "heatcvt/errors.h"
#include "heatcvt/face_clipper.h"
#include "heatcvt/spatial_order.h"

namespace heatcvt {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

std::vector<SurfacePoint> in_spatial_order(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                           std::vector<SurfacePoint> sites) {
  Eigen::MatrixX3d P(static_cast<Eigen::Index>(sites.size()), 3);
  for (size_t s = 0; s < sites.size(); ++s) P.row(s) = position(V, F, sites[s]).transpose();
  std::vector<SurfacePoint> sorted;
  sorted.reserve(sites.size());
  for (int s : morton_order(P)) sorted.push_back(sites[s]);
  return sorted;
}

std::vector<SurfacePoint> generated_sites(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                          const CvtOptions& options, const Eigen::VectorXd& vertex_density) {
  std::vector<SurfacePoint> sites =
      initial_sites(V, F, options.sites, options.initialization, options.seed, vertex_density);
  return options.spatial_site_order ? in_spatial_order(V, F, std::move(sites)) : sites;
}

std::vector<SurfacePoint> initial_sites(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, int count,
                                        CvtInitialization method, std::uint32_t seed,
                                        const Eigen::VectorXd& vertex_density) {
  if (count < 1) throw InvalidInputError("initial_sites: the number of sites must be >= 1, got " + std::to_string(count));
  validate_mesh(V, F, "initial_sites: mesh");
  const bool dense = vertex_density.size() > 0;
  if (dense && (vertex_density.size() != V.rows() || !vertex_density.allFinite() || !(vertex_density.minCoeff() > 0)))
    throw InvalidInputError("initial_sites: vertex_density must have one positive finite value per vertex");
  // Cells of a CVT with density ρ have a diameter ∝ ρ^(-1/4): sites per area ∝ ρ^(1/2).
  const auto face_density = [&](Eigen::Index f) {
    return dense ? (vertex_density[F(f, 0)] + vertex_density[F(f, 1)] + vertex_density[F(f, 2)]) / 3.0 : 1.0;
  };
  std::mt19937 rng(seed);
  std::vector<SurfacePoint> sites;
  if (method == CvtInitialization::random) {
    const Eigen::VectorXd area = face_areas(V, F);
    std::vector<double> cdf(area.size());
    double acc = 0;
    for (Eigen::Index f = 0; f < area.size(); ++f) cdf[f] = (acc += area[f] * std::sqrt(face_density(f)));
    if (!(acc > 0)) throw InvalidInputError("initial_sites: the mesh has zero area");
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int s = 0; s < count; ++s) {
      const double x = uni(rng) * acc;
      int f = static_cast<int>(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
      f = std::min<int>(f, static_cast<int>(F.rows()) - 1);
      const double r1 = std::sqrt(uni(rng)), r2 = uni(rng);
      SurfacePoint p;
      p.face = f;
      p.bary = Eigen::Vector3d(1 - r1, r1 * (1 - r2), r1 * r2);
      sites.push_back(p);
    }
    return sites;
  }
  // farthest-point sampling on the edge graph; with a density, edges measured in units of the
  // local cell diameter (length × the mean of ρ^(1/4) at its ends)
  EdgeGraph g = edge_graph(V, F);
  if (dense)
    for (int v = 0; v < g.num_vertices(); ++v)
      for (int e = g.off[v]; e < g.off[v + 1]; ++e)
        g.len[e] *= 0.5 * (std::pow(vertex_density[v], 0.25) + std::pow(vertex_density[g.nbr[e]], 0.25));
  const int n = static_cast<int>(V.rows());
  std::vector<std::vector<int>> vf = vertex_faces(n, F);
  if (count > n) throw InvalidInputError("initial_sites: more sites than vertices");
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<int> referenced;
  for (int v = 0; v < n; ++v)
    if (!vf[v].empty()) referenced.push_back(v);
  int next = referenced[std::uniform_int_distribution<size_t>(0, referenced.size() - 1)(rng)];
  using Item = std::pair<double, int>;
  // The farthest vertex is found from per-block maxima of the distance (first vertex wins ties, as
  // a plain scan would); a Dijkstra only lowers distances, and only the blocks it touched are
  // rescanned. The block size only changes the speed, not the result.
  constexpr int kBlock = 256;
  const int nblocks = (n + kBlock - 1) / kBlock;
  std::vector<char> is_referenced(n, 0), touched(nblocks, 1);
  for (int v : referenced) is_referenced[v] = 1;
  std::vector<double> block_max(nblocks, -1);
  std::vector<int> block_arg(nblocks, -1);
  for (int s = 0; s < count; ++s) {
    SurfacePoint p;
    p.face = vf[next].front();
    int k = 0;
    while (F(p.face, k) != next) ++k;
    p.bary = Eigen::Vector3d::Unit(k);
    sites.push_back(p);
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    dist[next] = 0;
    touched[next / kBlock] = 1;
    q.push({0.0, next});
    while (!q.empty()) {
      const auto [d, v] = q.top();
      q.pop();
      if (d > dist[v]) continue;
      for (int e = g.off[v]; e < g.off[v + 1]; ++e) {
        const double nd = d + g.len[e];
        if (nd < dist[g.nbr[e]]) {
          dist[g.nbr[e]] = nd;
          touched[g.nbr[e] / kBlock] = 1;
          q.push({nd, g.nbr[e]});
        }
      }
    }
    for (int b = 0; b < nblocks; ++b) {
      if (!touched[b]) continue;
      touched[b] = 0;
      block_max[b] = -1;
      block_arg[b] = -1;
      for (int v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v)
        if (is_referenced[v] && dist[v] > block_max[b]) block_max[b] = dist[v], block_arg[b] = v;
    }
    double best = -1;  // unreached components keep +inf: sampled first
    for (int b = 0; b < nblocks; ++b)
      if (block_arg[b] >= 0 && block_max[b] > best) best = block_max[b], next = block_arg[b];
  }
  return sites;
}

std::vector<int> graph_lloyd(const EdgeGraph& g, const Eigen::MatrixX3d& V, const Eigen::VectorXd& vertex_area,
                             std::vector<int> src, int iterations, int* done) {
  const int n = static_cast<int>(V.rows());
  const int ns = static_cast<int>(src.size());
  *done = 0;
  std::vector<Eigen::Vector3d> sum(ns);
  std::vector<double> mass(ns), best(ns);
  for (int it = 0; it < iterations; ++it) {
    const std::vector<int> label = graph_voronoi(g, src);
    std::fill(sum.begin(), sum.end(), Eigen::Vector3d::Zero());
    std::fill(mass.begin(), mass.end(), 0.0);
    for (int v = 0; v < n; ++v)
      if (label[v] >= 0) {
        sum[label[v]] += vertex_area[v] * V.row(v).transpose();
        mass[label[v]] += vertex_area[v];
      }
    for (int s = 0; s < ns; ++s)
      if (mass[s] > 0) sum[s] /= mass[s];
    std::vector<int> next = src;
    std::fill(best.begin(), best.end(), std::numeric_limits<double>::infinity());
    for (int v = 0; v < n; ++v) {
      const int s = label[v];
      if (s < 0 || !(mass[s] > 0)) continue;
      const double d = (V.row(v).transpose() - sum[s]).squaredNorm();
      if (d < best[s]) best[s] = d, next[s] = v;
    }
    ++*done;
    const bool changed = next != src;
    src.swap(next);
    if (!changed) break;
  }
  return src;
}

void restricted_labels(const EdgeGraph& g, const std::vector<Eigen::Vector3d>& X, const Eigen::MatrixX3i& F,
                       const std::vector<SurfacePoint>& sites, const std::vector<Eigen::Vector3d>& P,
                       std::vector<int>& label, std::vector<double>& key) {
  const int n = static_cast<int>(X.size());
  label.assign(n, -1);
  key.assign(n, std::numeric_limits<double>::infinity());
  struct Item {
    double d;
    int s, v;
    bool operator>(const Item& o) const { return d != o.d ? d > o.d : (s != o.s ? s > o.s : v > o.v); }
  };
  std::vector<Item> heap;
  heap.reserve(2 * static_cast<size_t>(n));
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q(std::greater<Item>(), std::move(heap));
  for (size_t s = 0; s < sites.size(); ++s)
    for (int k = 0; k < 3; ++k) {
      const int v = F(sites[s].face, k);
      const double d = (X[v] - P[s]).squaredNorm();
      if (d < key[v]) {
        key[v] = d;
        q.push({d, static_cast<int>(s), v});
      }
    }
  while (!q.empty()) {
    const Item it = q.top();
    q.pop();
    if (label[it.v] >= 0) continue;
    label[it.v] = it.s;
    const Eigen::Vector3d p = P[it.s];
    for (int e = g.off[it.v]; e < g.off[it.v + 1]; ++e) {
      const int w = g.nbr[e];
      if (label[w] >= 0) continue;
      const double d = (X[w] - p).squaredNorm();
      if (d < key[w]) {
        key[w] = d;
        q.push({d, it.s, w});
      }
    }
  }
}

void update_restricted_labels(const EdgeGraph& g, const std::vector<Eigen::Vector3d>& X, const Eigen::MatrixX3i& F,
                              const std::vector<SurfacePoint>& sites, const std::vector<Eigen::Vector3d>& P,
                              std::vector<int>& label, std::vector<double>& key, int threads) {
  const int n = static_cast<int>(X.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < n; ++v)
    if (label[v] >= 0) key[v] = (X[v] - P[label[v]]).squaredNorm();
  for (size_t s = 0; s < sites.size(); ++s)
    for (int k = 0; k < 3; ++k) {
      const int v = F(sites[s].face, k);
      const double d = (X[v] - P[s]).squaredNorm();
      if (label[v] < 0 || d < key[v] || (d == key[v] && static_cast<int>(s) < label[v])) label[v] = static_cast<int>(s), key[v] = d;
    }
  std::vector<int> active(n);
  for (int v = 0; v < n; ++v) active[v] = v;
  std::vector<unsigned char> mark(n, 0);
  struct Change {
    int v, s;
    double d;
  };
  std::vector<Change> changes;
  std::vector<std::vector<Change>> found(std::max(1, threads));
  while (!active.empty()) {
    changes.clear();
    // Jacobi sweep: every decision reads the labels of the previous sweep only, so the changes
    // (concatenated in the order of `active`) do not depend on the thread count.
    const int na = static_cast<int>(active.size());
    const int nt = na < 4096 ? 1 : std::max(1, threads);
#pragma omp parallel num_threads(nt)
    {
      const int tid = omp_get_thread_num(), count = omp_get_num_threads();
      std::vector<Change>& mine = found[tid];
      mine.clear();
      const int begin = static_cast<int>(static_cast<long long>(na) * tid / count);
      const int end = static_cast<int>(static_cast<long long>(na) * (tid + 1) / count);
      for (int i = begin; i < end; ++i) {
        const int v = active[i];
        int best = label[v];
        double bk = best >= 0 ? key[v] : std::numeric_limits<double>::infinity();
        for (int e = g.off[v]; e < g.off[v + 1]; ++e) {
          const int s = label[g.nbr[e]];
          if (s < 0 || s == best) continue;
          const double d = (X[v] - P[s]).squaredNorm();
          if (d < bk || (d == bk && s < best)) best = s, bk = d;
        }
        if (best != label[v]) mine.push_back({v, best, bk});
      }
    }
    for (int t = 0; t < nt; ++t) changes.insert(changes.end(), found[t].begin(), found[t].end());
    active.clear();
    for (const Change& c : changes) {
      label[c.v] = c.s;
      key[c.v] = c.d;
      for (int e = g.off[c.v]; e < g.off[c.v + 1]; ++e)
        if (!mark[g.nbr[e]]) mark[g.nbr[e]] = 1, active.push_back(g.nbr[e]);
    }
    for (int v : active) mark[v] = 0;
    std::sort(active.begin(), active.end());
  }
}

namespace {

// The parts of the restricted cells inside one face (at most 3): cell, area, first moment.
struct FaceMoments {
  int count = 0;
  int cell[3];
  double mass[3];
  Eigen::Vector3d sum[3];
};

// Area and first moment of the restricted Voronoi cells inside one face: faces whose corners
// share a label belong to it; the others are clipped exactly (face_clipper.h) by the Euclidean
// bisector planes of their corner labels: u_i = −|x − p_i|² differs from a linear function on the
// face by a term common to all sites, so u_i − u_j is linear, as the heat differences of eq. 20 are.
// `area`: the face's mass (its area times its density, CvtSurface::face_mass); `whole_moment`:
// mass · centroid of face f (the first moment when one cell holds the face).
// `fns`, `pieces`, `scratch`: per-thread work space.
void restricted_face_moments(const std::vector<Eigen::Vector3d>& X, const Eigen::MatrixX3i& F, int f, double area,
                             const Eigen::Vector3d& whole_moment, const std::vector<int>& label,
                             const std::vector<Eigen::Vector3d>& P, FaceMoments& out, std::vector<FaceFunction>& fns,
                             std::vector<FacePiece>& pieces, FaceClipScratch& scratch) {
  out.count = 0;
  const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
  const int l[3] = {label[c[0]], label[c[1]], label[c[2]]};
  if (l[0] < 0 || l[1] < 0 || l[2] < 0) return;
  if (l[0] == l[1] && l[1] == l[2]) {
    out.cell[0] = l[0];
    out.sum[0] = whole_moment;
    out.mass[0] = area;
    out.count = 1;
    return;
  }
  fns.clear();
  for (int k = 0; k < 3; ++k) {
    bool seen = false;
    for (const FaceFunction& fn : fns) seen = seen || fn.label == l[k];
    if (seen) continue;
    FaceFunction fn;
    fn.label = l[k];
    for (int j = 0; j < 3; ++j) fn.value[j] = -(X[c[j]] - P[l[k]]).squaredNorm();
    fns.push_back(fn);
  }
  pieces.clear();
  clip_face(fns, pieces, scratch);
  for (const FacePiece& p : pieces) {
    const auto& w = p.moments.weight;
    out.cell[out.count] = p.label;
    out.sum[out.count] = area * (w[0] * X[c[0]] + w[1] * X[c[1]] + w[2] * X[c[2]]);
    out.mass[out.count] = area * p.moments.fraction;
    ++out.count;
  }
}

// Over-relaxed targets c + (ω − 1)(c − p), the extra step capped; sites with an empty cell keep
// no target (mass 0).
std::vector<Eigen::Vector3d> relaxed_targets(const std::vector<Eigen::Vector3d>& sum, const std::vector<double>& mass,
                                             const std::vector<Eigen::Vector3d>& P, double omega, double cap) {
  const size_t ns = P.size();
  std::vector<Eigen::Vector3d> target(ns);
  for (size_t s = 0; s < ns; ++s) {
    if (!(mass[s] > 0)) continue;
    const Eigen::Vector3d c = sum[s] / mass[s];
    Eigen::Vector3d step = (omega - 1.0) * (c - P[s]);
    const double len = step.norm();
    if (len > cap) step *= cap / len;
    target[s] = c + step;
  }
  return target;
}

// The vertex of each non-empty cell closest to its target (−1 for empty cells).
std::vector<int> closest_cell_vertices(const std::vector<Eigen::Vector3d>& X, const std::vector<int>& label,
                                       const std::vector<double>& mass, const std::vector<Eigen::Vector3d>& target,
                                       int threads) {
  const int n = static_cast<int>(X.size());
  const size_t ns = mass.size();
  std::vector<double> best(ns, std::numeric_limits<double>::infinity()), vertex_distance(n);
  std::vector<int> nearest(ns, -1);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int v = 0; v < n; ++v) {
    const int s = label[v];
    vertex_distance[v] = s >= 0 && mass[s] > 0 ? (X[v] - target[s]).squaredNorm() : -1.0;
  }
  for (int v = 0; v < n; ++v) {
    const int s = label[v];
    if (vertex_distance[v] < 0) continue;
    if (vertex_distance[v] < best[s]) best[s] = vertex_distance[v], nearest[s] = v;
  }
  return nearest;
}

// Sites whose restricted cell is empty go into the largest cell, at its vertex farthest from its
// site (one revived site per cell). Returns the number of such sites.
int revive_restricted(const CvtSurface& surface, const std::vector<Eigen::Vector3d>& X, const std::vector<int>& label,
                      const std::vector<double>& mass, const std::vector<Eigen::Vector3d>& P,
                      std::vector<SurfacePoint>& next) {
  const int n = static_cast<int>(X.size()), ns = static_cast<int>(mass.size());
  if (std::all_of(mass.begin(), mass.end(), [](double m) { return m > 0; })) return 0;
  // The vertex of each cell farthest from its site (the first in index order on ties).
  std::vector<int> far(ns, -1);
  std::vector<double> far_d(ns, -1);
  for (int v = 0; v < n; ++v) {
    const int c = label[v];
    if (c < 0) continue;
    const double d = (X[v] - P[c]).squaredNorm();
    if (d > far_d[c]) far_d[c] = d, far[c] = v;
  }
  std::vector<double> cell_mass = mass;
  int revived = 0;
  for (int s = 0; s < ns; ++s) {
    if (mass[s] > 0) continue;
    const int big = static_cast<int>(std::max_element(cell_mass.begin(), cell_mass.end()) - cell_mass.begin());
    if (far[big] >= 0) next[s] = vertex_point(surface.F, surface.vfaces, far[big]);
    cell_mass[big] = 0;
    ++revived;
  }
  return revived;
}

}  // namespace

std::vector<SurfacePoint> surface_lloyd(const CvtSurface& surface, std::vector<SurfacePoint> sites,
                                        const SurfaceLloydOptions& options, int* done,
                                        std::vector<int>* final_labels, const std::function<int()>& threads_now) {
  const Eigen::MatrixX3d& V = surface.V;
  const Eigen::MatrixX3i& F = surface.F;
  const int n = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  const int ns = static_cast<int>(sites.size());
  *done = 0;
  std::vector<Eigen::Vector3d> X(n);
  for (int v = 0; v < n; ++v) X[v] = V.row(v).transpose();
  std::vector<int> label;
  std::vector<double> key;
  std::vector<Eigen::Vector3d> P(ns), sum(ns);
  std::vector<double> mass(ns);
  double previous_energy = std::numeric_limits<double>::infinity();
  double omega = options.relaxation;
  for (int s = 0; s < ns; ++s) P[s] = position(V, F, sites[s]);
  bool full_flood = true;  // first iteration and after relocated sites: labels from scratch
  std::vector<FaceMoments> moments(nf);
  std::vector<Eigen::Vector3d> whole_moment(nf);
  for (int f = 0; f < nf; ++f)
    whole_moment[f] = surface.face_mass[f] * (X[F(f, 0)] + X[F(f, 1)] + X[F(f, 2)]) / 3.0;
  for (int it = 0; it < options.iterations; ++it) {
    // Parallel loops write per-vertex / per-face / per-site results that are then combined
    // serially in index order: the same result for every thread count.
    const int threads = std::max(1, threads_now());
    if (full_flood) restricted_labels(surface.graph, X, F, sites, P, label, key);
    else update_restricted_labels(surface.graph, X, F, sites, P, label, key, threads);
    full_flood = false;
    std::fill(sum.begin(), sum.end(), Eigen::Vector3d::Zero());
    std::fill(mass.begin(), mass.end(), 0.0);
    double energy = 0;
    for (int v = 0; v < n; ++v)
      if (label[v] >= 0) energy += surface.vertex_area[v] * (surface.has_density() ? surface.vertex_density[v] : 1.0) * key[v];
#pragma omp parallel num_threads(threads)
    {
      std::vector<FaceFunction> fns;
      std::vector<FacePiece> pieces;
      FaceClipScratch scratch;
#pragma omp for schedule(dynamic, 1024)
      for (int f = 0; f < nf; ++f)
        restricted_face_moments(X, F, f, surface.face_mass[f], whole_moment[f], label, P, moments[f], fns, pieces,
                                scratch);
    }
    for (int f = 0; f < nf; ++f)
      for (int i = 0; i < moments[f].count; ++i) {
        sum[moments[f].cell[i]] += moments[f].sum[i];
        mass[moments[f].cell[i]] += moments[f].mass[i];
      }
    if (omega > 1.0 && energy > previous_energy) {
      const double decayed = 1.0 + options.relaxation_decay * (omega - 1.0);
      omega = decayed < 1.0 + options.relaxation_floor ? 1.0 : decayed;
    }
    previous_energy = energy;
    const std::vector<Eigen::Vector3d> target =
        relaxed_targets(sum, mass, P, omega, options.max_extra_step * options.spacing);
    // start of each projection: the cell's vertex closest to the target
    const std::vector<int> nearest = closest_cell_vertices(X, label, mass, target, threads);
    double max_move = 0, sum_move = 0;
    std::vector<SurfacePoint> next = sites;
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
    for (int s = 0; s < ns; ++s) {
      if (nearest[s] < 0) continue;
      next[s] = project_local(V, F, surface.vfaces, vertex_point(F, surface.vfaces, nearest[s]), target[s],
                              options.walk_max_steps, options.walk_min_gain);
    }
    if (revive_restricted(surface, X, label, mass, P, next) > 0) {
      max_move = sum_move = std::numeric_limits<double>::infinity();
      full_flood = true;
    }
    for (int s = 0; s < ns; ++s) {
      const Eigen::Vector3d q = position(V, F, next[s]);
      const double move = (q - P[s]).norm();
      max_move = std::max(max_move, move);
      sum_move += move;
      P[s] = q;
    }
    sites.swap(next);
    ++*done;
    if (max_move < options.tolerance * options.spacing) break;
    if (sum_move < options.mean_tolerance * options.spacing * ns) break;
  }
  if (final_labels) {
    if (full_flood || label.empty()) restricted_labels(surface.graph, X, F, sites, P, label, key);
    else update_restricted_labels(surface.graph, X, F, sites, P, label, key, std::max(1, threads_now()));
    *final_labels = std::move(label);
  }
  return sites;
}

SurfaceLloydOptions surface_lloyd_options(const CvtOptions& options, int iterations, double spacing) {
  SurfaceLloydOptions o;
  o.iterations = iterations;
  o.tolerance = options.surface_lloyd_tolerance;
  o.mean_tolerance = options.surface_lloyd_mean_tolerance;
  o.relaxation = options.surface_lloyd_relaxation;
  o.spacing = spacing;
  o.max_extra_step = options.tuning.max_extra_step;
  o.relaxation_decay = options.tuning.relaxation_decay;
  o.relaxation_floor = options.tuning.relaxation_floor;
  o.walk_max_steps = options.tuning.walk_max_steps;
  o.walk_min_gain = options.tuning.walk_min_gain;
  return o;
}

CvtStartReport cvt_start(const CvtSurface& surface, const CvtOptions& options, bool surface_on,
                         std::vector<SurfacePoint>& sites, const std::function<int()>& threads_now) {
  CvtStartReport report;
  const Eigen::MatrixX3i& F = surface.F;
  if (sites.empty()) sites = generated_sites(surface.V, F, options, surface.vertex_density);
  const int ns = static_cast<int>(sites.size());
  const auto tg = Clock::now();
  if (options.graph_lloyd_iterations > 0) {
    std::vector<int> sources(ns);
    for (int s = 0; s < ns; ++s) sources[s] = nearest_corner(F, sites[s]);
    sources = graph_lloyd(surface.graph, surface.V, surface.vertex_area, sources, options.graph_lloyd_iterations,
                          &report.graph_lloyd_iterations);
    for (int s = 0; s < ns; ++s) sites[s] = vertex_point(F, surface.vfaces, sources[s]);
  }
  report.graph_lloyd_seconds = since(tg);
  if (surface_on) {
    const auto ts = Clock::now();
    const double spacing = std::sqrt(surface.face_area.sum() / ns);
    sites = surface_lloyd(surface, sites, surface_lloyd_options(options, options.surface_lloyd_iterations, spacing),
                          &report.surface_lloyd_iterations, &report.labels, threads_now);
    report.surface_lloyd_seconds = since(ts);
  }
  return report;
}

}  // namespace heatcvt
