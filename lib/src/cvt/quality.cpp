// Quality control of a CVT: evaluation, targets, splitting, refinement. See cvt/quality.h.
#include "heatcvt/cvt/quality.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <limits>

namespace heatcvt {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

std::vector<int> nonmanifold_cells(const DualMesh& dual, int ns, bool closed, int* spots) {
  std::vector<unsigned char> flag(ns, 0);
  *spots = 0;
  std::vector<std::pair<std::int64_t, int>> edges;
  edges.reserve(3 * dual.F.rows());
  std::vector<std::vector<int>> star(ns);
  for (Eigen::Index t = 0; t < dual.F.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = dual.F(t, k), b = dual.F(t, (k + 1) % 3);
      edges.push_back({static_cast<std::int64_t>(std::min(a, b)) * ns + std::max(a, b), static_cast<int>(t)});
      star[a].push_back(static_cast<int>(t));
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    const size_t count = j - i;
    if (count > 2 || (closed && count == 1)) {
      ++*spots;
      flag[edges[i].first / ns] = flag[edges[i].first % ns] = 1;
    }
    i = j;
  }
  // vertex fans: the link edges (opposite edges) of a vertex must form one connected piece
  std::vector<int> local, parent;
  for (int v = 0; v < ns; ++v) {
    if (star[v].empty()) continue;
    local.clear();
    for (int t : star[v])
      for (int k = 0; k < 3; ++k)
        if (dual.F(t, k) != v) local.push_back(dual.F(t, k));
    std::sort(local.begin(), local.end());
    local.erase(std::unique(local.begin(), local.end()), local.end());
    parent.resize(local.size());
    for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
    auto find = [&](int x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (int t : star[v]) {
      int ids[2], m = 0;
      for (int k = 0; k < 3; ++k)
        if (dual.F(t, k) != v) ids[m++] = static_cast<int>(std::lower_bound(local.begin(), local.end(), dual.F(t, k)) - local.begin());
      if (m == 2) parent[find(ids[0])] = find(ids[1]);
    }
    int roots = 0;
    for (size_t i = 0; i < parent.size(); ++i) roots += find(static_cast<int>(i)) == static_cast<int>(i);
    if (roots > 1) {
      ++*spots;
      flag[v] = 1;
    }
  }
  for (int s : dual.unused_sites)
    if (s >= 0 && s < ns) {
      ++*spots;
      flag[s] = 1;
    }
  std::vector<int> out;
  for (int s = 0; s < ns; ++s)
    if (flag[s]) out.push_back(s);
  return out;
}

EdgeTopology edge_topology(const Eigen::MatrixX3i& F, int n) {
  std::vector<std::int64_t> keys;
  keys.reserve(3 * F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t a = F(f, k), b = F(f, (k + 1) % 3);
      keys.push_back(std::min(a, b) * n + std::max(a, b));
    }
  std::sort(keys.begin(), keys.end());
  EdgeTopology t;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    t.closed &= j - i >= 2;
    t.manifold_edges &= j - i <= 2;
    i = j;
  }
  return t;
}

std::vector<SurfacePoint> split_cells(const CvtSurface& surface, const HeatField& field, const Eigen::MatrixX3d& P,
                                      const std::vector<int>& bad, double min_distance) {
  std::vector<int> slot(P.rows(), -1);
  for (size_t i = 0; i < bad.size(); ++i) slot[bad[i]] = static_cast<int>(i);
  std::vector<double> far_d(bad.size(), -1);
  std::vector<int> far_v(bad.size(), -1);
  for (int v = 0; v < surface.num_vertices(); ++v) {
    if (field.offsets[v + 1] == field.offsets[v]) continue;
    const int c = field.site[field.offsets[v]];
    if (slot[c] < 0) continue;
    const double dist = (surface.V.row(v) - P.row(c)).squaredNorm();
    if (dist > far_d[slot[c]]) far_d[slot[c]] = dist, far_v[slot[c]] = v;
  }
  std::vector<SurfacePoint> added;
  for (size_t i = 0; i < bad.size(); ++i) {
    if (far_v[i] < 0 || far_d[i] < min_distance * min_distance) continue;
    added.push_back(vertex_point(surface.F, surface.vfaces, far_v[i]));
  }
  return added;
}

std::vector<SurfacePoint> small_angle_sites(const CvtSurface& surface, const VoronoiDiagram& diagram,
                                            const DualMesh& dual, double phi_min_deg, int count) {
  std::vector<std::pair<double, int>> small;
  const Eigen::VectorXd angles = smallest_angles(dual.V, dual.F) * (180.0 / M_PI);
  for (Eigen::Index t = 0; t < dual.F.rows(); ++t)
    if (angles[t] < phi_min_deg) small.push_back({angles[t], static_cast<int>(t)});
  std::sort(small.begin(), small.end());
  std::vector<int> wanted;  // refined-mesh vertices of the bad Voronoi vertices
  for (size_t i = 0; i < small.size() && static_cast<int>(wanted.size()) < count; ++i)
    wanted.push_back(dual.face_source[small[i].second]);
  std::sort(wanted.begin(), wanted.end());
  wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
  // the closest original vertex of a refined face around each wanted Voronoi vertex
  const Eigen::MatrixX3d& V = surface.V;
  const Eigen::MatrixX3i& F = surface.F;
  std::vector<int> chosen(wanted.size(), -1);
  for (Eigen::Index r = 0; r < diagram.F.rows(); ++r)
    for (int k = 0; k < 3; ++k) {
      const int rv = diagram.F(r, k);
      const auto pos = std::lower_bound(wanted.begin(), wanted.end(), rv);
      if (pos == wanted.end() || *pos != rv || chosen[pos - wanted.begin()] >= 0) continue;
      const int parent = diagram.face_parent[r];
      const Eigen::Vector3d x = diagram.V.row(rv);
      int best = F(parent, 0);
      for (int j = 1; j < 3; ++j)
        if ((V.row(F(parent, j)).transpose() - x).squaredNorm() < (V.row(best).transpose() - x).squaredNorm())
          best = F(parent, j);
      chosen[pos - wanted.begin()] = best;
    }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  std::vector<SurfacePoint> added;
  for (int v : chosen)
    if (v >= 0) added.push_back(vertex_point(F, surface.vfaces, v));
  return added;
}

CvtQualityControl::CvtQualityControl(const CvtSurface& surface, const CvtOptions& options, int initial_sites,
                                     double spacing, int threads)
    : surface_(surface), options_(options), initial_sites_(initial_sites), spacing_(spacing), threads_(threads),
      fewest_spots_(std::numeric_limits<int>::max()) {
  if (options.split_nonmanifold_cells) {
    const EdgeTopology t = edge_topology(surface.F, surface.num_vertices());
    closed_input_ = t.closed;
    // On an input with non-manifold edges the dual cannot be a manifold: nothing to split for.
    split_enabled_ = check_spots_ = t.manifold_edges;
  }
}

int CvtQualityControl::budget(const CvtResult& result) const {
  return static_cast<int>(options_.max_inserted_fraction * initial_sites_) - result.inserted_sites;
}

bool CvtQualityControl::evaluate(LloydState& lloyd, CvtIterationStats& st, int it, CvtResult& result) {
  // The diagram of the current sites: its heat field is the next iteration's Voronoi step (kept).
  const auto tf = Clock::now();
  field_ = lloyd.heat_field(&field_index_);
  field_seconds_ = since(tf);
  have_field_ = false;
  const auto tq = Clock::now();
  VoronoiOptions vo;
  vo.keep_sites_per_vertex = options_.keep_sites_per_vertex;
  vo.threads = threads_;
  VoronoiDiagram d = tessellate(surface_.V, surface_.F, field_, vo);
  const Eigen::MatrixX3d P = lloyd.positions();
  DualMesh dual = dual_mesh(d, P);
  const TriangleQuality q = triangle_quality(dual.V, dual.F);
  st.phi_min_deg = q.min_angle_deg;
  st.phi_mean_deg = q.mean_min_angle_deg;
  std::vector<int> bad;
  if (check_spots_) {
    int spots = 0;
    bad = nonmanifold_cells(dual, lloyd.num_sites(), closed_input_, &spots);
    st.nonmanifold_spots = spots;
    // Safeguard: splitting that makes things clearly worse is stopped (the quality target
    // still requires a dual without such spots).
    fewest_spots_ = std::min(fewest_spots_, spots);
    if (spots > options_.tuning.spot_growth_factor * fewest_spots_ + options_.tuning.spot_growth_slack)
      split_enabled_ = false;
  }
  if (q.mean_min_angle_deg > best_phi_mean_ + options_.tuning.patience_gain_deg) {
    best_phi_mean_ = q.mean_min_angle_deg;
    evaluations_since_best_ = 0;
  } else {
    ++evaluations_since_best_;
  }
  const bool targets_met = (options_.target_phi_mean_deg > 0 || options_.target_phi_min_deg > 0) &&
                           q.mean_min_angle_deg >= options_.target_phi_mean_deg &&
                           q.min_angle_deg >= options_.target_phi_min_deg && bad.empty();
  const int room = budget(result);
  last_bad_spots_ = static_cast<int>(bad.size());
  if (targets_met) {
    result.reached_quality = true;
    result.diagram = std::move(d);
    result.dual = std::move(dual);
    st.quality_seconds = since(tq);
    return true;
  }
  if (split_enabled_ && !bad.empty() && room > 0 && it < options_.iterations) {
    if (static_cast<int>(bad.size()) > room) bad.resize(room);
    const std::vector<SurfacePoint> added =
        split_cells(surface_, field_, P, bad, options_.tuning.split_min_distance * spacing_);
    st.inserted_sites = static_cast<int>(added.size());
    if (!added.empty()) {
      result.inserted_sites += st.inserted_sites;
      lloyd.add_sites(added, true);
    }
  }
  have_field_ = st.inserted_sites == 0;
  st.quality_seconds = since(tq);
  last_diagram_ = std::move(d);
  last_dual_ = std::move(dual);
  return false;
}

bool CvtQualityControl::only_phi_min_missed(const CvtIterationStats& st) const {
  return st.inserted_sites == 0 && options_.refine_small_angles && last_bad_spots_ == 0 &&
         st.phi_min_deg < options_.target_phi_min_deg && st.phi_mean_deg >= options_.target_phi_mean_deg &&
         options_.iterations > 0;
}

int CvtQualityControl::refine_small_angles(LloydState& lloyd, CvtResult& result) {
  const int ns = lloyd.num_sites();
  const int per_round = std::min(
      budget(result), std::max(1, static_cast<int>(options_.tuning.refine_fraction_per_round * ns)));
  const std::vector<SurfacePoint> added =
      small_angle_sites(surface_, last_diagram_, last_dual_, options_.target_phi_min_deg, per_round);
  if (added.empty()) return 0;
  result.inserted_sites += static_cast<int>(added.size());
  result.refined_sites += static_cast<int>(added.size());
  lloyd.add_sites(added, false);
  have_field_ = false;
  return static_cast<int>(added.size());
}

bool CvtQualityControl::take_field(HeatField& field, double& seconds, double& mean_index_set) {
  if (!have_field_) return false;
  field = std::move(field_);
  seconds = field_seconds_;
  mean_index_set = field_index_;
  have_field_ = false;
  return true;
}

}  // namespace heatcvt
