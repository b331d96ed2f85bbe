// Natural-neighbour coordinates by area stealing on heat Voronoi diagrams (paper §7.2).
// See natural_neighbour.h.
#include "heatcvt/natural_neighbour.h"

#include <omp.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <string>

#include "heatcvt/closest_point.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh.h"
#include "heatcvt/parallel.h"

namespace heatcvt {

namespace {

// Heat of site s at vertex v in the field (0 when absent).
double field_value(const HeatField& field, int v, int s) {
  for (int k = field.offsets[v]; k < field.offsets[v + 1]; ++k)
    if (field.site[k] == s) return field.heat[k];
  return 0.0;
}

// Keeps the `keep` hottest sites per vertex across blocks of dense columns (same order as
// heat_field_from_dense: heat descending, then site ascending; exact zeros are not stored).
class TopK {
 public:
  TopK(int n, int keep) : keep_(keep), rows_(n) {}
  void add(const Eigen::MatrixXd& U, int first, int threads) {
    const int n = static_cast<int>(rows_.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int v = 0; v < n; ++v) {
      auto& row = rows_[v];
      for (int j = 0; j < U.cols(); ++j)
        if (U(v, j) != 0.0) row.push_back({U(v, j), first + j});
      std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
      });
      if (static_cast<int>(row.size()) > keep_) row.resize(keep_);
    }
  }
  HeatField finish(int num_sites) const {
    HeatField f;
    f.num_sites = num_sites;
    f.offsets.assign(rows_.size() + 1, 0);
    for (size_t v = 0; v < rows_.size(); ++v) {
      for (const auto& [h, s] : rows_[v]) {
        f.site.push_back(s);
        f.heat.push_back(h);
      }
      f.offsets[v + 1] = static_cast<int>(f.site.size());
    }
    return f;
  }

 private:
  int keep_;
  std::vector<std::vector<std::pair<double, int>>> rows_;
};

using Poly = std::vector<Eigen::Vector3d>;  // polygon in barycentric coordinates of a face

// Keeps the part of `poly` where g·λ ≥ 0 (g linear in barycentric coordinates λ).
void clip(Poly& poly, const double g[3], Poly& scratch) {
  if (poly.empty()) return;
  thread_local std::vector<double> val;
  val.resize(poly.size());
  bool all_in = true, all_out = true;
  for (size_t p = 0; p < poly.size(); ++p) {
    val[p] = poly[p][0] * g[0] + poly[p][1] * g[1] + poly[p][2] * g[2];
    all_in &= val[p] >= 0;
    all_out &= val[p] < 0;
  }
  if (all_in) return;
  if (all_out) {
    poly.clear();
    return;
  }
  scratch.clear();
  for (size_t p = 0; p < poly.size(); ++p) {
    const size_t q = (p + 1) % poly.size();
    if (val[p] >= 0) scratch.push_back(poly[p]);
    if ((val[p] >= 0) != (val[q] >= 0)) {
      const double t = val[p] / (val[p] - val[q]);
      scratch.push_back(poly[p] + t * (poly[q] - poly[p]));
    }
  }
  poly.swap(scratch);
  if (poly.size() < 3) poly.clear();
}

// Area of a polygon in barycentric coordinates as a fraction of its face's area.
double area_fraction(const Poly& poly) {
  double frac = 0;
  for (size_t p = 1; p + 1 < poly.size(); ++p) {
    const Eigen::Vector3d &a = poly[0], &b = poly[p], &d = poly[p + 1];
    frac += (b[1] - a[1]) * (d[2] - a[2]) - (b[2] - a[2]) * (d[1] - a[1]);
  }
  return std::abs(frac);
}

// Vertex-edge graph with edge lengths (CSR).
struct Graph {
  std::vector<int> off, nbr;
  std::vector<double> len;
};

Graph edge_graph(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  const int n = static_cast<int>(V.rows());
  const std::vector<std::vector<int>> adj = vertex_neighbors(n, F);
  Graph g;
  g.off.assign(n + 1, 0);
  for (int v = 0; v < n; ++v) g.off[v + 1] = g.off[v] + static_cast<int>(adj[v].size());
  for (int v = 0; v < n; ++v)
    for (int w : adj[v]) {
      g.nbr.push_back(w);
      g.len.push_back((V.row(v) - V.row(w)).norm());
    }
  return g;
}

}  // namespace

struct NaturalNeighbourCoordinates::Impl {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
  std::vector<SurfacePoint> sites;
  Eigen::MatrixX3d site_pos;
  NaturalNeighbourOptions options;
  int threads = 1;
  Laplacian lap;
  std::unique_ptr<HeatSolver> solver;
  HeatField field;
  VoronoiDiagram diagram;
  Eigen::VectorXd face_area;
  std::vector<double> vmax;                 // largest site heat per vertex (0 if none)
  std::vector<int> piece_off, piece_site;   // base diagram pieces per original face (CSR)
  std::vector<double> piece_area;
  std::vector<char> face_cut;               // face split between several cells in the base diagram
  std::vector<double> face_floor;           // cut faces: max_j min_corners u_j ≤ max_j u_j anywhere on the face
  std::vector<int> cut_faces;               // faces with face_cut set
  std::vector<int> vf_off, vf;              // incident faces per vertex (CSR)
  std::vector<int> nb_off, nb;              // neighbouring vertices (CSR)
  std::vector<int> vpiece_off, vpiece_site; // per vertex: a third of the pieces of its faces, per site
  std::vector<double> vpiece_area;
  std::vector<char> reached;                // vertex on a component with a site
  double coincide_tol = 0;

  int ns() const { return static_cast<int>(sites.size()); }

  // Area that q steals from each old cell inside face f (not entirely in C_q): clip the face by
  // u_q ≥ u_j for every candidate j (ties go to q), then split by the old cells u_i ≥ u_j.
  void clip_face(int f, const int c[3], const double* uq, std::vector<double>& stolen, std::vector<int>& sites_f,
                 std::vector<std::array<double, 3>>& U, Poly& base, Poly& poly, Poly& scratch) const {
    sites_f.clear();
    for (int k = 0; k < 3; ++k)
      for (int e = field.offsets[c[k]]; e < field.offsets[c[k] + 1]; ++e) sites_f.push_back(field.site[e]);
    std::sort(sites_f.begin(), sites_f.end());
    sites_f.erase(std::unique(sites_f.begin(), sites_f.end()), sites_f.end());
    if (sites_f.empty()) return;
    U.resize(sites_f.size());
    for (size_t j = 0; j < sites_f.size(); ++j)
      for (int k = 0; k < 3; ++k) U[j][k] = field_value(field, c[k], sites_f[j]);
    // C_q ∩ face: u_q ≥ u_j for every candidate j (ties go to q)
    base = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    for (size_t j = 0; j < sites_f.size() && !base.empty(); ++j) {
      const double g[3] = {uq[c[0]] - U[j][0], uq[c[1]] - U[j][1], uq[c[2]] - U[j][2]};
      clip(base, g, scratch);
    }
    if (base.empty()) return;
    // split by the old cells: u_i ≥ u_j (identical heat: the smaller site wins)
    for (size_t i = 0; i < sites_f.size(); ++i) {
      poly = base;
      for (size_t j = 0; j < sites_f.size() && !poly.empty(); ++j) {
        if (j == i) continue;
        const double g[3] = {U[i][0] - U[j][0], U[i][1] - U[j][1], U[i][2] - U[j][2]};
        if (g[0] == 0 && g[1] == 0 && g[2] == 0) {
          if (sites_f[i] > sites_f[j]) poly.clear();
          continue;
        }
        clip(poly, g, scratch);
      }
      if (poly.size() >= 3) stolen[sites_f[i]] += face_area[f] * area_fraction(poly);
    }
  }

  // Exact area stealing given q's heat at every vertex (uq indexed by vertex).
  NaturalNeighbourQuery from_heat(const double* uq, const SurfacePoint& q) const {
    NaturalNeighbourQuery res;
    const Eigen::Vector3d x = position(V, F, q);
    for (int s = 0; s < ns(); ++s)
      if ((site_pos.row(s).transpose() - x).norm() <= coincide_tol) {  // Lagrange: q at a site
        res.weights = {{s, 1.0}};
        res.stolen_area = {{s, diagram.cell_area[s]}};
        res.cell_area = diagram.cell_area[s];
        return res;
      }
    std::vector<double> stolen(ns(), 0.0);
    std::vector<int> sites_f;
    std::vector<std::array<double, 3>> U;
    Poly base, poly, scratch;
    // Visit only the faces with a corner where q's heat wins (each once, from its first winning
    // corner) and the cut faces of the base diagram whose heat floor q's heat can reach.
    const int nv = static_cast<int>(V.rows());
    std::vector<unsigned char> win(nv);
    for (int v = 0; v < nv; ++v) win[v] = uq[v] >= vmax[v];
    // Faces with all corners won lie entirely in C_q (u_q − max_j u_j is concave). Their pieces
    // are summed through per-vertex thirds: every won vertex adds a third of the pieces of its
    // faces, and the faces with a corner that is not won give their won corners' thirds back and
    // are clipped (once, from their first won corner).
    for (int v = 0; v < nv; ++v) {
      if (!win[v]) continue;
      for (int k = vpiece_off[v]; k < vpiece_off[v + 1]; ++k) stolen[vpiece_site[k]] += vpiece_area[k];
      bool interior = true;
      for (int k = nb_off[v]; k < nb_off[v + 1] && interior; ++k) interior = win[nb[k]];
      if (interior) continue;
      for (int i = vf_off[v]; i < vf_off[v + 1]; ++i) {
        const int f = vf[i];
        const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
        if (win[c[0]] && win[c[1]] && win[c[2]]) continue;
        for (int k = piece_off[f]; k < piece_off[f + 1]; ++k) stolen[piece_site[k]] -= piece_area[k] / 3.0;
        int first = 0;
        while (!win[c[first]]) ++first;
        if (c[first] == v) {
          clip_face(f, c, uq, stolen, sites_f, U, base, poly, scratch);
        }
      }
    }
    // Without any winning corner q can only win inside a face where several cells meet (there
    // max_j u_j is a non-linear convex function); on a single-cell face u_q − u_l is linear.
    for (int f : cut_faces) {
      if (win[F(f, 0)] || win[F(f, 1)] || win[F(f, 2)]) continue;  // done above
      if (std::max({uq[F(f, 0)], uq[F(f, 1)], uq[F(f, 2)]}) < face_floor[f]) continue;
      const int c[3] = {F(f, 0), F(f, 1), F(f, 2)};
      clip_face(f, c, uq, stolen, sites_f, U, base, poly, scratch);
    }
    double total = 0;
    const double eps = 1e-12 * diagram.cell_area.sum();  // rounding of the per-vertex thirds
    for (int s = 0; s < ns(); ++s)
      if (stolen[s] > eps) {
        res.stolen_area.push_back({s, stolen[s]});
        total += stolen[s];
      }
    res.cell_area = total;
    if (!(total > 0)) {
      res.stolen_area.clear();
      return res;  // no site reaches q
    }
    for (const auto& [s, a] : res.stolen_area) res.weights.push_back({s, a / total});
    return res;
  }

  void check_point(const SurfacePoint& q, const std::string& what) const {
    if (q.face < 0 || q.face >= F.rows())
      throw InvalidInputError(what + ": face index " + std::to_string(q.face) + " out of range [0, " +
                              std::to_string(F.rows()) + ")");
    if (!q.bary.allFinite() || q.bary.minCoeff() < -1e-9 || std::abs(q.bary.sum() - 1.0) > 1e-6)
      throw InvalidInputError(what + ": barycentric coordinates must be finite, >= 0 and sum to 1");
  }
};

namespace {
// Heat cannot spread over a connected component whose faces all have (numerically) zero area
// (needles, collinear corners): its vertices have no mass, so neither M − tL nor the biharmonic
// system of the propagation is definite there. Such input is rejected up front. Areas are
// compared with the squared bounding-box diagonal, so the test does not depend on the units.
void require_positive_component_areas(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  constexpr double zero_area = 1e-12;  // relative to the squared bounding-box diagonal
  Eigen::VectorXi comp;
  const int nc = connected_components(static_cast<int>(V.rows()), F, comp);
  const Eigen::VectorXd area = face_areas(V, F);
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  std::vector<double> comp_area(nc, 0.0);
  for (int f = 0; f < F.rows(); ++f) comp_area[comp[F(f, 0)]] += area[f];
  for (int c = 0; c < nc; ++c)
    if (!(comp_area[c] > zero_area * diag * diag))
      throw InvalidInputError(nc == 1 ? std::string("the mesh has zero area (every face is degenerate)")
                                      : "connected component " + std::to_string(c) +
                                            " of the mesh has zero area (every face of it is degenerate)");
}
}  // namespace

NaturalNeighbourCoordinates::NaturalNeighbourCoordinates(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                                         const std::vector<SurfacePoint>& sites,
                                                         const NaturalNeighbourOptions& options)
    : impl_(std::make_unique<Impl>()) {
  validate_mesh(V, F, "natural neighbour coordinates: mesh");
  Impl& m = *impl_;
  m.V = V;
  m.F = F;
  m.sites = sites;
  m.options = options;
  if (sites.size() < 2)
    throw InvalidInputError("natural neighbour coordinates need at least 2 sites, got " + std::to_string(sites.size()));
  if (!(options.time_coefficient > 0) || !std::isfinite(options.time_coefficient))
    throw InvalidInputError("natural neighbour coordinates: time_coefficient must be positive and finite");
  if (options.threads < 0) throw InvalidInputError("natural neighbour coordinates: threads must be >= 0");
  if (options.keep_sites_per_vertex < 1)
    throw InvalidInputError("natural neighbour coordinates: keep_sites_per_vertex must be >= 1");
  if (options.samples < 0) throw InvalidInputError("natural neighbour coordinates: samples must be >= 0");
  if (!(options.drop_below >= 0) || !(options.drop_below < 0.5))
    throw InvalidInputError("natural neighbour coordinates: drop_below must be in [0, 0.5)");
  if (options.batch < 1) throw InvalidInputError("natural neighbour coordinates: batch must be >= 1");
  for (size_t s = 0; s < sites.size(); ++s) m.check_point(sites[s], "natural neighbour coordinates: site " + std::to_string(s));
  m.threads = resolve_threads(options.threads);
  const int nv = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows()), ns = m.ns();

  require_positive_component_areas(V, F);
  m.lap = cotan_laplacian(V, F);
  HeatSolverOptions so;
  so.time_coefficient = options.time_coefficient;
  so.threads = m.threads;
  m.solver = std::make_unique<HeatSolver>(m.lap, so);

  // Base diagram: one diffusion per site (eq. 8), blocks of 64 columns, top-k per vertex.
  TopK top(nv, options.keep_sites_per_vertex);
  for (int s0 = 0; s0 < ns; s0 += 64) {
    const int nb = std::min(64, ns - s0);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nv, nb);
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < 3; ++k) rhs(F(sites[s0 + j].face, k), j) += sites[s0 + j].bary[k];
    const Eigen::MatrixXd U = m.solver->solve(rhs);
    if (!U.allFinite()) throw SolverError("natural neighbour coordinates: the heat solve produced non-finite values");
    top.add(U, s0, m.threads);
  }
  m.field = top.finish(ns);
  VoronoiOptions vo;
  vo.keep_sites_per_vertex = options.keep_sites_per_vertex;
  vo.threads = m.threads;
  m.diagram = tessellate(V, F, m.field, vo);
  m.face_area = face_areas(V, F);

  m.vmax.assign(nv, 0.0);
  m.reached.assign(nv, 0);
  for (int v = 0; v < nv; ++v)
    if (m.field.offsets[v + 1] > m.field.offsets[v]) m.vmax[v] = m.field.heat[m.field.offsets[v]];
  {
    Eigen::VectorXi comp;
    const int nc = connected_components(nv, F, comp);
    std::vector<char> has_site(nc, 0);
    for (const SurfacePoint& p : sites) has_site[comp[F(p.face, 0)]] = 1;
    for (int v = 0; v < nv; ++v) m.reached[v] = has_site[comp[v]];
  }
  // base pieces per original face: (site, area), merged per site
  std::vector<std::vector<std::pair<int, double>>> pieces(nf);
  for (int r = 0; r < m.diagram.F.rows(); ++r) {
    const int c = m.diagram.face_cell[r];
    if (c < 0) continue;
    auto& p = pieces[m.diagram.face_parent[r]];
    bool merged = false;
    for (auto& e : p)
      if (e.first == c) e.second += m.diagram.face_area[r], merged = true;
    if (!merged) p.push_back({c, m.diagram.face_area[r]});
  }
  m.piece_off.assign(nf + 1, 0);
  m.face_cut.assign(nf, 0);
  for (int f = 0; f < nf; ++f) {
    std::sort(pieces[f].begin(), pieces[f].end());
    for (const auto& [c, a] : pieces[f]) {
      m.piece_site.push_back(c);
      m.piece_area.push_back(a);
    }
    m.piece_off[f + 1] = static_cast<int>(m.piece_site.size());
    m.face_cut[f] = pieces[f].size() > 1;
  }
  m.vf_off.assign(nv + 1, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++m.vf_off[F(f, k) + 1];
  for (int v = 0; v < nv; ++v) m.vf_off[v + 1] += m.vf_off[v];
  m.vf.resize(m.vf_off[nv]);
  {
    std::vector<int> fill(m.vf_off.begin(), m.vf_off.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) m.vf[fill[F(f, k)]++] = f;
  }
  for (int f = 0; f < nf; ++f)
    if (m.face_cut[f]) m.cut_faces.push_back(f);
  {
    const std::vector<std::vector<int>> adj = vertex_neighbors(nv, F);
    m.nb_off.assign(nv + 1, 0);
    for (int v = 0; v < nv; ++v) {
      m.nb.insert(m.nb.end(), adj[v].begin(), adj[v].end());
      m.nb_off[v + 1] = static_cast<int>(m.nb.size());
    }
    m.vpiece_off.assign(nv + 1, 0);
    std::vector<std::pair<int, double>> acc;
    for (int v = 0; v < nv; ++v) {
      acc.clear();
      for (int i = m.vf_off[v]; i < m.vf_off[v + 1]; ++i) {
        const int f = m.vf[i];
        for (int k = m.piece_off[f]; k < m.piece_off[f + 1]; ++k) {
          bool merged = false;
          for (auto& e : acc)
            if (e.first == m.piece_site[k]) e.second += m.piece_area[k] / 3.0, merged = true;
          if (!merged) acc.push_back({m.piece_site[k], m.piece_area[k] / 3.0});
        }
      }
      for (const auto& [site, a] : acc) {
        m.vpiece_site.push_back(site);
        m.vpiece_area.push_back(a);
      }
      m.vpiece_off[v + 1] = static_cast<int>(m.vpiece_site.size());
    }
  }
  m.face_floor.assign(nf, 0.0);
  for (int f = 0; f < nf; ++f) {
    if (!m.face_cut[f]) continue;
    double floor = 0;
    for (int k = 0; k < 3; ++k)
      for (int e = m.field.offsets[F(f, k)]; e < m.field.offsets[F(f, k) + 1]; ++e) {
        const int s = m.field.site[e];
        floor = std::max(floor, std::min({field_value(m.field, F(f, 0), s), field_value(m.field, F(f, 1), s),
                                          field_value(m.field, F(f, 2), s)}));
      }
    m.face_floor[f] = floor;
  }
  m.site_pos.resize(ns, 3);
  for (int s = 0; s < ns; ++s) m.site_pos.row(s) = position(V, F, sites[s]).transpose();
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  m.coincide_tol = 1e-12 * diag;
}

NaturalNeighbourCoordinates::~NaturalNeighbourCoordinates() = default;
NaturalNeighbourCoordinates::NaturalNeighbourCoordinates(NaturalNeighbourCoordinates&&) noexcept = default;
NaturalNeighbourCoordinates& NaturalNeighbourCoordinates::operator=(NaturalNeighbourCoordinates&&) noexcept = default;

int NaturalNeighbourCoordinates::num_sites() const { return impl_->ns(); }
int NaturalNeighbourCoordinates::num_vertices() const { return static_cast<int>(impl_->V.rows()); }
const VoronoiDiagram& NaturalNeighbourCoordinates::diagram() const { return impl_->diagram; }
const HeatSolver& NaturalNeighbourCoordinates::solver() const { return *impl_->solver; }
const NaturalNeighbourOptions& NaturalNeighbourCoordinates::options() const { return impl_->options; }

NaturalNeighbourQuery NaturalNeighbourCoordinates::query(const SurfacePoint& q) const {
  impl_->check_point(q, "natural neighbour query");
  const Eigen::VectorXd u = impl_->solver->diffuse_from_point(impl_->F, q);
  return impl_->from_heat(u.data(), q);
}

std::vector<NaturalNeighbourQuery> NaturalNeighbourCoordinates::query(const std::vector<SurfacePoint>& points,
                                                                      const NaturalNeighbourProgress& progress) const {
  const Impl& m = *impl_;
  for (size_t i = 0; i < points.size(); ++i) m.check_point(points[i], "natural neighbour query " + std::to_string(i));
  const int nq = static_cast<int>(points.size()), nv = static_cast<int>(m.V.rows());
  std::vector<NaturalNeighbourQuery> out(nq);
  const int batch = m.options.batch;
  for (int q0 = 0; q0 < nq; q0 += batch) {
    const int nb = std::min(batch, nq - q0);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nv, nb);
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < 3; ++k) rhs(m.F(points[q0 + j].face, k), j) += points[q0 + j].bary[k];
    const Eigen::MatrixXd U = m.solver->solve(rhs);
#pragma omp parallel for schedule(dynamic, 1) num_threads(m.threads)
    for (int j = 0; j < nb; ++j) out[q0 + j] = m.from_heat(U.col(j).data(), points[q0 + j]);
    if (progress) progress(q0 + nb, nq);
  }
  return out;
}

namespace {

VertexWeights rows_to_matrix(int nv, int ns, const std::vector<std::vector<std::pair<int, double>>>& rows) {
  std::vector<Eigen::Triplet<double>> trip;
  for (int v = 0; v < nv; ++v)
    for (const auto& [s, w] : rows[v]) trip.emplace_back(v, s, w);
  VertexWeights W(nv, ns);
  W.setFromTriplets(trip.begin(), trip.end());
  W.makeCompressed();
  return W;
}

}  // namespace

VertexWeights NaturalNeighbourCoordinates::vertex_weights_direct(const NaturalNeighbourProgress& progress) const {
  const Impl& m = *impl_;
  const int nv = static_cast<int>(m.V.rows());
  std::vector<int> all(nv);
  for (int v = 0; v < nv; ++v) all[v] = v;
  const auto results = query(surface_points_at_vertices(m.F, nv, all), progress);
  std::vector<std::vector<std::pair<int, double>>> rows(nv);
  for (int v = 0; v < nv; ++v) rows[v] = results[v].weights;
  return rows_to_matrix(nv, m.ns(), rows);
}

std::vector<int> NaturalNeighbourCoordinates::farthest_point_samples(int count) const {
  const Impl& m = *impl_;
  const int nv = static_cast<int>(m.V.rows());
  count = std::min(nv, count);
  const Graph g = edge_graph(m.V, m.F);
  using Item = std::pair<double, int>;
  // Dijkstra from the given sources into `dist` (only improving entries are touched).
  auto relax = [&](std::vector<double>& dist, std::priority_queue<Item, std::vector<Item>, std::greater<Item>>& heap) {
    while (!heap.empty()) {
      const auto [d, v] = heap.top();
      heap.pop();
      if (d > dist[v]) continue;
      for (int e = g.off[v]; e < g.off[v + 1]; ++e) {
        const double nd = d + g.len[e];
        if (nd < dist[g.nbr[e]]) {
          dist[g.nbr[e]] = nd;
          heap.push({nd, g.nbr[e]});
        }
      }
    }
  };
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  // graph distance to the nearest site's nearest corner
  std::vector<int> site_vertex;
  for (const SurfacePoint& p : m.sites) {
    int k = 0;
    p.bary.maxCoeff(&k);
    site_vertex.push_back(m.F(p.face, k));
  }
  std::vector<double> to_site(nv, std::numeric_limits<double>::infinity());
  for (int v : site_vertex) {
    to_site[v] = 0;
    heap.push({0.0, v});
  }
  relax(to_site, heap);
  // Farthest-point sampling in a metric stretched near the sites, where the coordinates have their
  // cone-shaped peaks (b_i(p_i) = 1): within R = 3·spacing of a site distances count up to 1/0.3×,
  // so the samples are up to ~3× denser (linearly) there.
  const double spacing = std::sqrt(surface_area(m.V, m.F) / count), R = 3.0 * spacing;
  std::vector<double> scale(nv);
  for (int v = 0; v < nv; ++v) scale[v] = std::isfinite(to_site[v]) ? 0.3 + 0.7 * std::min(1.0, to_site[v] / R) : 1.0;
  std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
  std::vector<char> is_sample(nv, 0);
  std::vector<int> samples;
  auto add = [&](int v) {
    if (is_sample[v]) return;
    is_sample[v] = 1;
    samples.push_back(v);
    dist[v] = 0;
    heap.push({0.0, v});
  };
  for (int v : site_vertex) add(v);  // exact values where the coordinates peak
  relax(dist, heap);
  std::vector<char> referenced(nv, 0);
  for (int f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) referenced[m.F(f, k)] = 1;
  while (static_cast<int>(samples.size()) < count) {
    int far = -1;
    double best = -1;
    for (int v = 0; v < nv; ++v)  // unreached components (+inf) are sampled first; ties: smallest index
      if (referenced[v] && !is_sample[v] && dist[v] / scale[v] > best) best = dist[v] / scale[v], far = v;
    if (far < 0) break;
    add(far);
    relax(dist, heap);
  }
  return samples;
}

// Biharmonic propagation (see the header): rows of all vertices from the exact rows at `samples`.
std::vector<std::vector<std::pair<int, double>>> NaturalNeighbourCoordinates::propagate(
    const std::vector<int>& samples, const std::vector<std::vector<std::pair<int, double>>>& exact) const {
  const Impl& m = *impl_;
  const int nv = static_cast<int>(m.V.rows()), ns = m.ns();
  const int K = static_cast<int>(samples.size());
  std::vector<std::vector<std::pair<int, double>>> rows(nv);
  std::vector<int> slot(nv, -1);  // sample index, or free index (−2 − i)
  for (int i = 0; i < K; ++i) {
    slot[samples[i]] = i;
    rows[samples[i]] = exact[i];
  }
  std::vector<int> free_vertices;
  for (int v = 0; v < nv; ++v)
    if (slot[v] < 0) {
      slot[v] = -2 - static_cast<int>(free_vertices.size());
      free_vertices.push_back(v);
    }
  const int nfree = static_cast<int>(free_vertices.size());
  if (nfree > 0) {
    // Biharmonic propagation: minimise xᵀ L M⁻¹ L x with x fixed at the samples.
    // Vertices without mass (only degenerate faces around them) get no weight in the energy
    // instead of an infinite one.
    const Eigen::VectorXd minv = m.lap.M.unaryExpr([](double x) { return x > 0 ? 1.0 / x : 0.0; });
    const Eigen::SparseMatrix<double> ML = minv.asDiagonal() * m.lap.L;
    const Eigen::SparseMatrix<double> Q = m.lap.L * ML;
    std::vector<Eigen::Triplet<double>> tff, tfc;
    for (int col = 0; col < Q.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(Q, col); it; ++it) {
        const int r = static_cast<int>(it.row());
        if (slot[r] >= 0) continue;  // rows of fixed vertices are not equations
        const int fr = -2 - slot[r];
        if (slot[col] < 0) tff.emplace_back(fr, -2 - slot[col], it.value());
        else tfc.emplace_back(fr, slot[col], it.value());
      }
    Eigen::SparseMatrix<double> Qff(nfree, nfree), Qfc(nfree, K);
    Qff.setFromTriplets(tff.begin(), tff.end());
    Qfc.setFromTriplets(tfc.begin(), tfc.end());
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> chol;
    chol.compute(Qff);
    if (chol.info() != Eigen::Success)
      throw SolverError("natural neighbour coordinates: the biharmonic propagation system could not be factored");
    // sites that appear in any sample, solved in chunks of columns
    std::vector<int> active;
    {
      std::vector<char> seen(ns, 0);
      for (const auto& e : exact)
        for (const auto& [s, w] : e) seen[s] = 1;
      for (int s = 0; s < ns; ++s)
        if (seen[s]) active.push_back(s);
    }
    const int chunk = 32;
    std::vector<std::pair<double, int>> best(nfree, {-std::numeric_limits<double>::infinity(), -1});
    for (size_t a0 = 0; a0 < active.size(); a0 += chunk) {
      const int na = static_cast<int>(std::min<size_t>(chunk, active.size() - a0));
      Eigen::MatrixXd XC = Eigen::MatrixXd::Zero(K, na);
      for (int i = 0; i < K; ++i)
        for (const auto& [s, w] : exact[i]) {
          const auto it = std::lower_bound(active.begin() + a0, active.begin() + a0 + na, s);
          if (it != active.begin() + a0 + na && *it == s) XC(i, it - (active.begin() + a0)) = w;
        }
      const Eigen::MatrixXd rhs = -(Qfc * XC);
      const Eigen::MatrixXd XF = chol.solve(rhs);
      for (int i = 0; i < nfree; ++i)
        for (int j = 0; j < na; ++j) {
          if (XF(i, j) > m.options.drop_below) rows[free_vertices[i]].push_back({active[a0 + j], XF(i, j)});
          if (XF(i, j) > best[i].first) best[i] = {XF(i, j), active[a0 + j]};
        }
    }
    // renormalise (partition of unity); vertices on components without sites keep empty rows
    for (int i = 0; i < nfree; ++i) {
      const int v = free_vertices[i];
      auto& row = rows[v];
      if (!m.reached[v]) {
        row.clear();
        continue;
      }
      if (row.empty() && best[i].second >= 0) row.push_back({best[i].second, 1.0});  // everything below drop_below
      double sum = 0;
      for (const auto& e : row) sum += e.second;
      if (!(sum > 0)) continue;
      for (auto& e : row) e.second /= sum;
      std::sort(row.begin(), row.end());
    }
  }
  return rows;
}

VertexWeights NaturalNeighbourCoordinates::vertex_weights(const NaturalNeighbourProgress& progress,
                                                          std::vector<int>* exact_vertices) const {
  const Impl& m = *impl_;
  const int nv = static_cast<int>(m.V.rows()), ns = m.ns();
  const int K = std::min(nv, m.options.samples > 0 ? m.options.samples : std::max(500, nv / 20));
  const std::vector<int> order = farthest_point_samples(K);
  const int k1 = std::max(std::min(ns, static_cast<int>(order.size())), static_cast<int>(0.6 * order.size()));
  const std::vector<int> first(order.begin(), order.begin() + k1), check(order.begin() + k1, order.end());
  const int max_extra = K / 2;
  const long total = K + max_extra;
  long done = 0;
  auto exact_rows = [&](const std::vector<int>& vertices) {
    const auto res = query(surface_points_at_vertices(m.F, nv, vertices), [&](long d, long) {
      if (progress) progress(done + d, total);
    });
    done += static_cast<long>(vertices.size());
    std::vector<std::vector<std::pair<int, double>>> rows(res.size());
    for (size_t i = 0; i < res.size(); ++i) rows[i] = res[i].weights;
    return rows;
  };
  std::vector<int> samples = first;
  std::vector<std::vector<std::pair<int, double>>> exact = exact_rows(first);
  if (!check.empty()) {
    // Round 1: propagate from the first 60 % of the samples and compare with the exact values at
    // the remaining 40 % (the farthest-point continuation: the points between the first ones).
    const auto rows1 = propagate(samples, exact);
    const auto exact_check = exact_rows(check);
    std::vector<char> taken(nv, 0);
    for (int v : order) taken[v] = 1;
    std::vector<int> extra;
    for (size_t i = 0; i < check.size(); ++i) {
      Eigen::VectorXd diff = Eigen::VectorXd::Zero(ns);
      for (const auto& [s, w] : exact_check[i]) diff[s] += w;
      for (const auto& [s, w] : rows1[check[i]]) diff[s] -= w;
      if (diff.cwiseAbs().maxCoeff() <= m.options.refine_tolerance) continue;
      // Round 2: where the propagation missed, take the two rings around the check vertex exactly.
      for (int k = m.nb_off[check[i]]; k < m.nb_off[check[i] + 1]; ++k) {
        const int w = m.nb[k];
        for (int j = m.nb_off[w] - 1; j < m.nb_off[w + 1]; ++j) {
          const int x = j < m.nb_off[w] ? w : m.nb[j];
          if (!taken[x] && static_cast<int>(extra.size()) < max_extra) {
            taken[x] = 1;
            extra.push_back(x);
          }
        }
      }
    }
    samples.insert(samples.end(), check.begin(), check.end());
    exact.insert(exact.end(), exact_check.begin(), exact_check.end());
    if (!extra.empty()) {
      const auto exact_extra = exact_rows(extra);
      samples.insert(samples.end(), extra.begin(), extra.end());
      exact.insert(exact.end(), exact_extra.begin(), exact_extra.end());
    }
  }
  const auto rows = propagate(samples, exact);
  if (exact_vertices) {
    *exact_vertices = samples;
    std::sort(exact_vertices->begin(), exact_vertices->end());
  }
  if (progress) progress(total, total);
  return rows_to_matrix(nv, ns, rows);
}

Eigen::MatrixXd interpolate_site_values(const VertexWeights& W, const Eigen::MatrixXd& values) {
  if (values.rows() != W.cols())
    throw InvalidInputError("interpolate_site_values: " + std::to_string(values.rows()) + " rows of values for " +
                            std::to_string(W.cols()) + " sites");
  if (!values.allFinite()) throw InvalidInputError("interpolate_site_values: values have NaN or infinite entries");
  return W * values;
}

}  // namespace heatcvt
