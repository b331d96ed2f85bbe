// The heat Lloyd iteration (paper §7.1) with localized solves (§6). See cvt/lloyd.h.
#include "heatcvt/cvt/lloyd.h"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <queue>

#include "heatcvt/centroid.h"
#include "heatcvt/face_clipper.h"

namespace heatcvt {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The part of a cell inside one face: area fraction and ∫ φ_k / area(face) for its corners.
struct Piece {
  int face, cell;
  RegionMoments m;
};

// Exact cells of one face (paper eq. 20). Faces whose three corners have the same strictly
// hottest site belong to it entirely (the common case); the others go through clip_face().
void face_pieces(const HeatField& field, const Eigen::MatrixX3i& F, int f, std::vector<Piece>& out,
                 std::vector<FaceFunction>& fns, std::vector<FacePiece>& pieces, FaceClipScratch& scratch) {
  const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
  int top = -1;
  bool whole = true;
  for (int k = 0; k < 3 && whole; ++k) {
    const int b = field.offsets[c[k]], e = field.offsets[c[k] + 1];
    whole = e > b && (e - b == 1 || field.heat[b] > field.heat[b + 1]) && (top < 0 || field.site[b] == top);
    if (whole) top = field.site[b];
  }
  if (whole) {
    out.push_back({f, top, {1.0, {1.0 / 3, 1.0 / 3, 1.0 / 3}}});
    return;
  }
  fns.clear();
  for (int k = 0; k < 3; ++k)
    for (int e = field.offsets[c[k]]; e < field.offsets[c[k] + 1]; ++e) {
      FaceFunction fn;
      fn.label = field.site[e];
      fns.push_back(fn);
    }
  std::sort(fns.begin(), fns.end(), [](const FaceFunction& a, const FaceFunction& b) { return a.label < b.label; });
  fns.erase(std::unique(fns.begin(), fns.end(), [](const FaceFunction& a, const FaceFunction& b) { return a.label == b.label; }),
            fns.end());
  for (FaceFunction& fn : fns)
    for (int k = 0; k < 3; ++k) {
      fn.value[k] = 0.0;
      for (int e = field.offsets[c[k]]; e < field.offsets[c[k] + 1]; ++e)
        if (field.site[e] == fn.label) fn.value[k] = field.heat[e];
    }
  pieces.clear();
  clip_face(fns, pieces, scratch);
  for (const FacePiece& p : pieces) out.push_back({f, p.label, p.moments});
}

// Sorts and merges the per-cell lists built from the face pieces.
void compact_cells(IterationCells& r, int threads) {
  const int ns = static_cast<int>(r.loads.size());
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
  for (int c = 0; c < ns; ++c) {
    auto& v = r.cells.vertices[c];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    auto& a = r.cells.adjacency[c];
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    auto& l = r.loads[c];
    std::sort(l.begin(), l.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    size_t w = 0;
    for (size_t i = 0; i < l.size(); ++i) {
      if (w > 0 && l[w - 1].first == l[i].first) l[w - 1].second += l[i].second;
      else l[w++] = l[i];
    }
    l.resize(w);
  }
}

}  // namespace

double population_variance(const Eigen::VectorXd& x) {
  if (x.size() == 0) return 0.0;
  const double mean = x.mean();
  return (x.array() - mean).square().sum() / static_cast<double>(x.size());
}

CellNeighbourhoods cells_from_labels(const EdgeGraph& g, const std::vector<int>& label, int num_cells) {
  const int n = static_cast<int>(label.size());
  CellNeighbourhoods c;
  c.vertices.resize(num_cells);
  c.adjacency.resize(num_cells);
  for (int v = 0; v < n; ++v) {
    if (label[v] < 0) continue;
    c.vertices[label[v]].push_back(v);
    for (int k = g.off[v]; k < g.off[v + 1]; ++k) {
      const int w = g.nbr[k];
      if (label[w] >= 0 && label[w] != label[v]) c.adjacency[label[v]].push_back(label[w]);
    }
  }
  for (auto& a : c.adjacency) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return c;
}

IterationCells iteration_cells(const HeatField& field, const Eigen::MatrixX3i& F, const Eigen::VectorXd& face_area,
                               const Eigen::VectorXd& face_scale, int ns, int threads, int blocks_per_thread) {
  const int nf = static_cast<int>(F.rows());
  const int blocks = std::max(1, std::min(nf, std::max(1, blocks_per_thread) * threads));
  std::vector<std::vector<Piece>> pieces(blocks);
#pragma omp parallel num_threads(threads)
  {
    std::vector<FaceFunction> fns;
    std::vector<FacePiece> face;
    FaceClipScratch scratch;
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < blocks; ++b) {
      const int f0 = static_cast<int>(static_cast<long>(nf) * b / blocks);
      const int f1 = static_cast<int>(static_cast<long>(nf) * (b + 1) / blocks);
      for (int f = f0; f < f1; ++f) face_pieces(field, F, f, pieces[b], fns, face, scratch);
    }
  }
  IterationCells r;
  r.cells.vertices.assign(ns, {});
  r.cells.adjacency.assign(ns, {});
  r.loads.assign(ns, {});
  r.area = Eigen::VectorXd::Zero(ns);
  for (const auto& block : pieces)
    for (size_t i = 0; i < block.size(); ++i) {
      const Piece& p = block[i];
      const double A = face_area[p.face];
      const double scale = face_scale.size() ? face_scale[p.face] : 1.0;
      r.area[p.cell] += A * p.m.fraction;
      for (int k = 0; k < 3; ++k) {
        r.cells.vertices[p.cell].push_back(F(p.face, k));
        r.loads[p.cell].push_back({F(p.face, k), A * scale * p.m.weight[k]});
      }
      // cells sharing a face are neighbours
      for (size_t j = i + 1; j < block.size() && block[j].face == p.face; ++j) {
        r.cells.adjacency[p.cell].push_back(block[j].cell);
        r.cells.adjacency[block[j].cell].push_back(p.cell);
      }
    }
  compact_cells(r, threads);
  return r;
}

LloydState::LloydState(const CvtSurface& surface, const LocalizedSolver& local, const CvtOptions& options,
                       const Eigen::VectorXd& face_scale, double spacing, int threads, std::vector<SurfacePoint> sites,
                       CellNeighbourhoods cells, int rings)
    : surface_(surface), local_(local), options_(options), face_scale_(face_scale),
      normals_(vertex_normals(surface.V, surface.F)), spacing_(spacing), threads_(threads), sites_(std::move(sites)),
      cells_(std::move(cells)), rings_(rings), omega_(options.relaxation) {
  const int n = surface_.num_vertices();
  scratch_.resize(threads_);
  for (auto& t : scratch_) {
    t.ws.resize(n);
    t.mark.assign(n, 0);
    t.heat = Eigen::VectorXd::Zero(n);
    t.dist.assign(n, std::numeric_limits<double>::infinity());
  }
  resize_scratch();
}

void LloydState::resize_scratch() {
  const int ns = num_sites();
  for (auto& t : scratch_) t.cmark.assign(ns, 0);
  indices_.resize(ns);
  values_.resize(ns);
  cells_.vertices.resize(ns);
  cells_.adjacency.resize(ns);
  settled_.assign(ns, 0);
}

Eigen::MatrixX3d LloydState::positions() const {
  Eigen::MatrixX3d P(num_sites(), 3);
  for (int s = 0; s < num_sites(); ++s) P.row(s) = position(surface_.V, surface_.F, sites_[s]).transpose();
  return P;
}

// Cells within `rings` steps of `cell` in the adjacency graph (cell included), sorted.
void LloydState::ring_cells(int cell, int rings, ThreadScratch& t) const {
  t.cells.clear();
  t.frontier.assign(1, cell);
  t.cmark[cell] = 1;
  t.cells.push_back(cell);
  for (int r = 0; r < rings; ++r) {
    t.next.clear();
    for (int c : t.frontier)
      for (int a : cells_.adjacency[c])
        if (!t.cmark[a]) {
          t.cmark[a] = 1;
          t.cells.push_back(a);
          t.next.push_back(a);
        }
    t.frontier.swap(t.next);
  }
  for (int c : t.cells) t.cmark[c] = 0;
  std::sort(t.cells.begin(), t.cells.end());
}

// Union of the vertices of t.cells, in a deterministic order (cells sorted, vertices sorted per cell).
void LloydState::union_vertices(ThreadScratch& t, std::vector<int>& out) const {
  out.clear();
  for (int c : t.cells)
    for (int v : cells_.vertices[c])
      if (!t.mark[v]) {
        t.mark[v] = 1;
        out.push_back(v);
      }
  for (int v : out) t.mark[v] = 0;
}

// Dijkstra ball of the given radius around the vertices of a face (index set of an empty cell).
void LloydState::dijkstra_ball(int face, double radius, ThreadScratch& t, std::vector<int>& out) const {
  const EdgeGraph& g = surface_.graph;
  out.clear();
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
  for (int k = 0; k < 3; ++k) {
    const int v = surface_.F(face, k);
    if (t.dist[v] > 0) {
      if (std::isinf(t.dist[v])) t.touched.push_back(v);
      t.dist[v] = 0;
      q.push({0.0, v});
    }
  }
  while (!q.empty()) {
    const auto [d, v] = q.top();
    q.pop();
    if (d > t.dist[v]) continue;
    out.push_back(v);
    for (int k = g.off[v]; k < g.off[v + 1]; ++k) {
      const int w = g.nbr[k];
      const double nd = d + g.len[k];
      if (nd <= radius && nd < t.dist[w]) {
        if (std::isinf(t.dist[w])) t.touched.push_back(w);
        t.dist[w] = nd;
        q.push({nd, w});
      }
    }
  }
  for (int v : t.touched) t.dist[v] = std::numeric_limits<double>::infinity();
  t.touched.clear();
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

HeatField LloydState::heat_field(double* mean_index_set) {
  const int ns = num_sites();
  const Eigen::MatrixX3i& F = surface_.F;
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads_)
  for (int s = 0; s < ns; ++s) {
    ThreadScratch& t = scratch_[omp_get_thread_num()];
    ring_cells(s, settled_[s] ? std::min(rings_, options_.voronoi_rings_settled) : rings_, t);
    union_vertices(t, indices_[s]);
    if (cells_.vertices[s].empty())
      dijkstra_ball(sites_[s].face, options_.tuning.empty_cell_radius * spacing_, t, indices_[s]);
    t.rhs.clear();
    for (int k = 0; k < 3; ++k)
      if (sites_[s].bary[k] != 0.0) t.rhs.push_back({F(sites_[s].face, k), sites_[s].bary[k]});
    local_.solve(t.rhs, indices_[s], values_[s], t.ws);
  }
  double index_total = 0;
  for (int s = 0; s < ns; ++s) index_total += static_cast<double>(indices_[s].size());
  if (mean_index_set) *mean_index_set = index_total / ns;
  return heat_field_from_sparse(surface_.num_vertices(), indices_, values_, options_.keep_sites_per_vertex, threads_);
}

// Heat centroids: area source of each cell, localized to the cell and `centroid_rings` rings;
// the hottest vertex of the cell, refined quadratically (§7.1 "Centroids on faces").
void LloydState::heat_centroids(const IterationCells& ic, std::vector<SurfacePoint>& moved) {
  const int ns = num_sites();
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads_)
  for (int c = 0; c < ns; ++c) {
    if (ic.loads[c].empty()) continue;  // the cell vanished: the site stays
    ThreadScratch& t = scratch_[omp_get_thread_num()];
    ring_cells(c, options_.centroid_rings, t);
    std::vector<int> I;
    union_vertices(t, I);
    local_.solve(ic.loads[c], I, t.values, t.ws);
    for (size_t i = 0; i < I.size(); ++i) t.heat[I[i]] = t.values[i];
    int hottest = -1;
    double best = -std::numeric_limits<double>::infinity();
    for (int v : cells_.vertices[c])  // sorted: ties go to the smallest index
      if (t.heat[v] > best) best = t.heat[v], hottest = v;
    if (hottest >= 0) {
      if (options_.quadratic_refinement)
        moved[c] = refine_hottest_vertex(surface_.V, surface_.F, surface_.vfaces, normals_, t.heat, hottest);
      else
        moved[c] = vertex_point(surface_.F, surface_.vfaces, hottest);
    }
    for (int v : I) t.heat[v] = 0.0;
  }
}

// Sites whose cell vanished (e.g. two sites that reached the same hottest vertex) are moved into
// the largest cell, to its vertex farthest from that cell's site (one per cell).
int LloydState::revive_empty_cells(IterationCells& ic, std::vector<SurfacePoint>& moved) const {
  int revived = 0;
  for (int c = 0; c < num_sites(); ++c) {
    if (!ic.loads[c].empty()) continue;
    int big = 0;
    ic.area.maxCoeff(&big);
    const Eigen::Vector3d centre = position(surface_.V, surface_.F, moved[big]);
    int far = -1;
    double best = -1;
    for (int v : cells_.vertices[big]) {
      const double dist = (surface_.V.row(v).transpose() - centre).norm();
      if (dist > best) best = dist, far = v;
    }
    if (far < 0) continue;
    moved[c] = vertex_point(surface_.F, surface_.vfaces, far);
    ic.area[big] = 0;  // do not put two revived sites into the same cell
    ++revived;
  }
  return revived;
}

// Accelerated step from the plain Lloyd map G(x) = heat centroids: Anderson mixing over the last
// `anderson_depth` iterations (safeguarded by the residual), or over-relaxation; each step goes
// at most max_extra_step spacings beyond the centroid and is projected onto the surface.
void LloydState::accelerated_step(const IterationCells& ic, std::vector<SurfacePoint>& moved, CvtIterationStats& st) {
  const int ns = num_sites();
  const Eigen::MatrixX3d& V = surface_.V;
  const Eigen::MatrixX3i& F = surface_.F;
  std::vector<Eigen::Vector3d> X(ns), C(ns);
  double r2 = 0;
  for (int s = 0; s < ns; ++s) {
    X[s] = position(V, F, sites_[s]);
    C[s] = position(V, F, moved[s]);
    r2 += ic.area[s] * (C[s] - X[s]).squaredNorm();
  }
  const double residual = std::sqrt(r2);
  std::vector<Eigen::Vector3d> target;
  const bool plain_only = st.revived_sites > 0;
  if (options_.anderson_depth > 0) {
    Eigen::VectorXd f(3 * ns), g(3 * ns);
    for (int s = 0; s < ns; ++s) {
      const double w = std::sqrt(std::max(ic.area[s], 0.0));
      f.segment<3>(3 * s) = w * (C[s] - X[s]);
      g.segment<3>(3 * s) = C[s];
    }
    const bool comparable = aa_.f_prev.size() == f.size() && !plain_only;
    if (!comparable || residual > aa_.residual_prev) {
      aa_.dF.clear();
      aa_.dG.clear();
    } else {
      aa_.dF.push_back(f - aa_.f_prev);
      aa_.dG.push_back(g - aa_.g_prev);
      if (static_cast<int>(aa_.dF.size()) > options_.anderson_depth) {
        aa_.dF.erase(aa_.dF.begin());
        aa_.dG.erase(aa_.dG.begin());
      }
    }
    aa_.f_prev = f;
    aa_.g_prev = g;
    aa_.residual_prev = comparable ? residual : std::numeric_limits<double>::infinity();
    if (!plain_only && !aa_.dF.empty()) {
      const int m = static_cast<int>(aa_.dF.size());
      Eigen::MatrixXd DF(3 * ns, m), DG(3 * ns, m);
      for (int k = 0; k < m; ++k) DF.col(k) = aa_.dF[k], DG.col(k) = aa_.dG[k];
      const Eigen::VectorXd gamma = DF.colPivHouseholderQr().solve(f);
      if (gamma.allFinite()) {
        const Eigen::VectorXd x = g - DG * gamma;
        target.resize(ns);
        for (int s = 0; s < ns; ++s) target[s] = x.segment<3>(3 * s);
      }
      st.anderson_columns = m;
    }
  } else if (omega_ > 1.0 && !plain_only) {
    target.resize(ns);
    for (int s = 0; s < ns; ++s) target[s] = C[s] + (omega_ - 1.0) * (C[s] - X[s]);
  }
  st.residual = residual;
  if (target.empty()) return;
  const double cap = options_.tuning.max_extra_step * spacing_;
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads_)
  for (int s = 0; s < ns; ++s) {
    if (ic.loads[s].empty()) continue;
    Eigen::Vector3d step = target[s] - C[s];
    const double len = step.norm();
    if (!(len > 0)) continue;
    if (len > cap) step *= cap / len;
    moved[s] = project_local(V, F, surface_.vfaces, moved[s], C[s] + step, options_.tuning.walk_max_steps,
                             options_.tuning.walk_min_gain);
  }
}

// Moves the sites; a site is settled when it and all its neighbours moved less than
// settled_move spacings (each bisector then moved less than that, so the cell stays within
// voronoi_rings_settled rings); once all sites moved that little, the rings drop for good.
void LloydState::finish_step(std::vector<SurfacePoint>& moved, CvtIterationStats& st) {
  const int ns = num_sites();
  double max_move = 0, sum_move = 0;
  std::vector<double> move_length(ns);
  for (int s = 0; s < ns; ++s) {
    const double d = (position(surface_.V, surface_.F, moved[s]) - position(surface_.V, surface_.F, sites_[s])).norm();
    move_length[s] = d;
    max_move = std::max(max_move, d);
    sum_move += d;
  }
  sites_.swap(moved);
  st.max_move = max_move;
  st.mean_move = sum_move / ns;
  const double settled_move = options_.tuning.settled_move * spacing_;
  if (max_move < settled_move) rings_ = std::min(rings_, options_.voronoi_rings_settled);
  std::vector<char> small(ns, 0);
  for (int s = 0; s < ns; ++s) small[s] = move_length[s] < settled_move;
  for (int s = 0; s < ns; ++s) {
    bool all = small[s];
    for (int c : cells_.adjacency[s]) all = all && small[c];
    settled_[s] = all;
  }
}

void LloydState::step(const HeatField& field, CvtIterationStats& st) {
  const int ns = num_sites();
  const auto tt = Clock::now();
  IterationCells ic = iteration_cells(field, surface_.F, surface_.face_area, face_scale_, ns, threads_,
                                      options_.tuning.face_blocks_per_thread);
  st.tessellate_seconds = since(tt);
  st.area_variance = population_variance(ic.area);
  cells_ = std::move(ic.cells);
  // Safeguard of the over-relaxation: the energy proxy grew → back towards plain Lloyd.
  if (omega_ > 1.0 && options_.anderson_depth == 0 && st.area_variance > previous_variance_) {
    const double decayed = 1.0 + options_.tuning.relaxation_decay * (omega_ - 1.0);
    omega_ = decayed < 1.0 + options_.tuning.relaxation_floor ? 1.0 : decayed;
  }
  previous_variance_ = st.area_variance;
  st.relaxation = omega_;
  const auto t1 = Clock::now();
  std::vector<SurfacePoint> moved = sites_;
  heat_centroids(ic, moved);
  st.revived_sites = revive_empty_cells(ic, moved);
  accelerated_step(ic, moved, st);
  finish_step(moved, st);
  st.centroid_seconds = since(t1);
}

void LloydState::add_sites(const std::vector<SurfacePoint>& added, bool full_rings) {
  sites_.insert(sites_.end(), added.begin(), added.end());
  resize_scratch();
  if (full_rings) rings_ = options_.voronoi_rings;
  previous_variance_ = std::numeric_limits<double>::infinity();
}

void LloydState::reset_sites(std::vector<SurfacePoint> sites, CellNeighbourhoods cells, int rings) {
  sites_ = std::move(sites);
  cells_ = std::move(cells);
  rings_ = rings;
  resize_scratch();
}

bool LloydState::full_rings_field_ready() {
  const bool any_settled = std::find(settled_.begin(), settled_.end(), 1) != settled_.end();
  const bool ready = rings_ == options_.voronoi_rings && !any_settled;
  rings_ = options_.voronoi_rings;
  settled_.assign(num_sites(), 0);
  return ready;
}

}  // namespace heatcvt
