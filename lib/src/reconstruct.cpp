// Surface reconstruction from point clouds: point Laplacian -> heat CVT -> dual triangles ->
// fitted site positions -> orientation / manifold clean-up / small-hole filling -> validation.
#include "heatcvt/reconstruct.h"

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <random>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/cvt.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"
#include "heatcvt/point_laplacian.h"

namespace heatcvt {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void check_options(const ReconstructionOptions& o) {
  auto bad = [](const std::string& m) { throw InvalidInputError("reconstruct_surface: " + m); };
  if (o.sites < 4) bad("sites = " + std::to_string(o.sites) + " (need at least 4)");
  if (o.iterations < 0) bad("iterations = " + std::to_string(o.iterations) + " (must be >= 0)");
  if (o.neighbors < o.min_neighbors || o.neighbors > o.max_neighbors)
    bad("neighbors = " + std::to_string(o.neighbors) + " (must be in [" + std::to_string(o.min_neighbors) + ", " +
        std::to_string(o.max_neighbors) + "])");
  if (!(o.anisotropy >= 0) || !std::isfinite(o.anisotropy)) bad("anisotropy must be a finite number >= 0");
  if (!(o.voxel_size >= 0) || !std::isfinite(o.voxel_size)) bad("voxel_size must be a finite number >= 0");
  if (!(o.time_coefficient > 0) || !std::isfinite(o.time_coefficient)) bad("time_coefficient must be > 0");
  if (o.threads < 0) bad("threads must be >= 0");
  if (o.max_hole_edges < 0) bad("max_hole_edges must be >= 0");
  if (o.relaxation_iterations < 0) bad("relaxation_iterations must be >= 0");
  if (!(o.lloyd_relaxation >= 1 && o.lloyd_relaxation < 2)) bad("lloyd_relaxation must be in [1, 2)");
  if (!(o.lloyd_tolerance >= 0) || !std::isfinite(o.lloyd_tolerance)) bad("lloyd_tolerance must be a finite number >= 0");
  if (o.surface_lloyd_iterations < 0) bad("surface_lloyd_iterations must be >= 0");
  if (!(o.cvt_points_per_site == 0 || o.cvt_points_per_site >= 3) || !std::isfinite(o.cvt_points_per_site))
    bad("cvt_points_per_site must be 0 (every point) or at least 3");
  if (o.denoise && o.denoise_neighbors < 2) bad("denoise_neighbors must be >= 2");
  if (o.denoise && (!(o.denoise_stddev > 0) || !std::isfinite(o.denoise_stddev))) bad("denoise_stddev must be > 0");
}

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const Eigen::MatrixX3d& P) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
  c->resize(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    (*c)[i] = pcl::PointXYZ(static_cast<float>(P(i, 0)), static_cast<float>(P(i, 1)), static_cast<float>(P(i, 2)));
  c->width = static_cast<std::uint32_t>(P.rows());
  c->height = 1;
  c->is_dense = true;
  return c;
}

// Weighted least-squares quadratic height field over the PCA plane of `nb` (indices into P);
// returns the projection of x onto it and the fitted normal (oriented like `orient`).
void fit_and_project(const Eigen::MatrixX3d& P, const std::vector<int>& nb, const Eigen::Vector3d& x,
                     const Eigen::Vector3d& orient, Eigen::Vector3d& out_pos, Eigen::Vector3d& out_normal) {
  const int m = static_cast<int>(nb.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int j : nb) mean += P.row(j).transpose();
  mean /= m;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int j : nb) {
    const Eigen::Vector3d d = P.row(j).transpose() - mean;
    C += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d n = es.eigenvectors().col(0);
  if (n.dot(orient) < 0) n = -n;
  Eigen::Vector3d u = es.eigenvectors().col(2), v = n.cross(u);
  const Eigen::Vector3d xl = x - mean;
  const double sx = xl.dot(u), tx = xl.dot(v);
  // Gaussian weights in the plane around the query; bandwidth = RMS planar radius.
  std::vector<double> s(m), t(m), h(m), w(m);
  double r2 = 0;
  for (int q = 0; q < m; ++q) {
    const Eigen::Vector3d d = P.row(nb[q]).transpose() - mean;
    s[q] = d.dot(u);
    t[q] = d.dot(v);
    h[q] = d.dot(n);
    r2 += (s[q] - sx) * (s[q] - sx) + (t[q] - tx) * (t[q] - tx);
  }
  r2 = std::max(r2 / m, 1e-300);
  for (int q = 0; q < m; ++q) w[q] = std::exp(-((s[q] - sx) * (s[q] - sx) + (t[q] - tx) * (t[q] - tx)) / r2);
  // Local coordinates centred at the query for conditioning.
  Eigen::MatrixXd A(m, 6);
  Eigen::VectorXd b(m);
  for (int q = 0; q < m; ++q) {
    const double a = s[q] - sx, c = t[q] - tx, sw = std::sqrt(w[q]);
    A.row(q) << sw, sw * a, sw * c, sw * a * a, sw * a * c, sw * c * c;
    b[q] = sw * h[q];
  }
  const double radius = std::sqrt(r2);
  double z = 0, gx = 0, gy = 0;
  bool ok = false;
  if (m >= 10) {
    // Scale the columns so that the quadratic terms are O(1).
    Eigen::VectorXd scale(6);
    scale << 1, radius, radius, radius * radius, radius * radius, radius * radius;
    Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(As);
    qr.setThreshold(1e-8);
    if (qr.rank() == 6) {
      const Eigen::VectorXd coef = scale.cwiseInverse().asDiagonal() * qr.solve(b);
      z = coef[0];
      gx = coef[1];
      gy = coef[2];
      ok = std::isfinite(z) && std::isfinite(gx) && std::isfinite(gy) && std::abs(z - xl.dot(n)) < 2 * radius;
    }
  }
  if (!ok) {  // plane fallback: weighted mean height
    double sw = 0, sh = 0;
    for (int q = 0; q < m; ++q) {
      sw += w[q];
      sh += w[q] * h[q];
    }
    z = sw > 0 ? sh / sw : 0;
    gx = gy = 0;
  }
  out_pos = mean + sx * u + tx * v + z * n;
  out_normal = (n - gx * u - gy * v).normalized();
}

struct EdgeKey {
  static long long make(int a, int b) { return (static_cast<long long>(a) << 32) | static_cast<unsigned>(b); }
};

// A spatially uniform subset of about `target` of the points: a voxel grid sized (by a few
// secant steps on the voxel size) so that about `target` voxels are occupied, and in each voxel
// the point nearest the centroid of its points. Returns the chosen indices, ascending, and in
// `representative` (#P) the position in that list of each point's voxel's chosen point.
std::vector<int> voxel_subsample(const Eigen::MatrixX3d& P, long target, std::vector<int>& representative) {
  const Eigen::Vector3d lo = P.colwise().minCoeff().transpose();
  const Eigen::Vector3d extent = P.colwise().maxCoeff().transpose() - lo;
  auto key_of = [&](Eigen::Index i, double size) {
    const Eigen::Vector3d c = ((P.row(i).transpose() - lo) / size).array().floor();
    return (static_cast<long long>(c[0]) * 2097152LL + static_cast<long long>(c[1])) * 2097152LL + static_cast<long long>(c[2]);
  };
  auto occupied = [&](double size) {
    std::unordered_set<long long> keys;
    keys.reserve(static_cast<size_t>(P.rows()));
    for (Eigen::Index i = 0; i < P.rows(); ++i) keys.insert(key_of(i, size));
    return static_cast<long>(keys.size());
  };
  // A surface occupies about area / size² voxels: size ← size · sqrt(count / target).
  double size = std::max(extent.maxCoeff(), 1e-12) / std::sqrt(static_cast<double>(target));
  double best_size = size;
  long best_gap = std::numeric_limits<long>::max();
  for (int step = 0; step < 6; ++step) {
    const long count = occupied(size);
    if (std::labs(count - target) < best_gap) best_gap = std::labs(count - target), best_size = size;
    if (std::labs(count - target) <= target / 50) break;
    size *= std::sqrt(static_cast<double>(count) / static_cast<double>(target));
  }
  std::unordered_map<long long, int> voxel;  // key -> slot
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> members;
  std::vector<int> slot_of(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    auto [it, fresh] = voxel.emplace(key_of(i, best_size), static_cast<int>(sum.size()));
    if (fresh) sum.push_back(Eigen::Vector3d::Zero()), members.push_back(0);
    sum[it->second] += P.row(i).transpose();
    ++members[it->second];
    slot_of[i] = it->second;
  }
  std::vector<int> chosen(sum.size(), -1);
  std::vector<double> best(sum.size(), std::numeric_limits<double>::infinity());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const int v = slot_of[i];
    const double d = (P.row(i).transpose() - sum[v] / members[v]).squaredNorm();
    if (d < best[v]) best[v] = d, chosen[v] = static_cast<int>(i);
  }
  std::vector<int> order(chosen.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return chosen[x] < chosen[y]; });
  std::vector<int> position(chosen.size()), sorted(chosen.size());
  for (size_t r = 0; r < order.size(); ++r) position[order[r]] = static_cast<int>(r), sorted[r] = chosen[order[r]];
  representative.resize(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) representative[i] = position[slot_of[i]];
  return sorted;
}

// Smallest angle of a triangle: the one opposite its shortest edge (one acos instead of three;
// the polish evaluates it millions of times).
double min_angle_pts(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d p[3] = {a, b, c};
  int k = 0;  // the corner opposite the shortest edge
  double shortest = std::numeric_limits<double>::infinity();
  for (int q = 0; q < 3; ++q) {
    const double len = (p[(q + 1) % 3] - p[(q + 2) % 3]).squaredNorm();
    if (len < shortest) shortest = len, k = q;
  }
  const Eigen::Vector3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
  const double n1 = e1.norm(), n2 = e2.norm();
  if (n1 == 0 || n2 == 0 || shortest == 0) return 0;
  return std::acos(std::clamp(e1.dot(e2) / (n1 * n2), -1.0, 1.0));
}

double tri_min_angle(const Eigen::MatrixX3d& V, int a, int b, int c) {
  return min_angle_pts(V.row(a).transpose(), V.row(b).transpose(), V.row(c).transpose());
}

// Groups the faces around vertex v into fans (connected through edges incident to v).
std::vector<std::vector<int>> vertex_fans(int v, const std::vector<int>& faces, const std::vector<std::array<int, 3>>& F) {
  const int m = static_cast<int>(faces.size());
  std::vector<int> parent(m);
  for (int i = 0; i < m; ++i) parent[i] = i;
  std::function<int(int)> find = [&](int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); };
  std::map<int, int> first_with_other;  // other vertex -> face slot
  for (int i = 0; i < m; ++i) {
    const auto& f = F[faces[i]];
    for (int k = 0; k < 3; ++k) {
      const int o = f[k];
      if (o == v) continue;
      auto it = first_with_other.find(o);
      if (it == first_with_other.end())
        first_with_other[o] = i;
      else
        parent[find(i)] = find(it->second);
    }
  }
  std::map<int, std::vector<int>> groups;
  for (int i = 0; i < m; ++i) groups[find(i)].push_back(faces[i]);
  std::vector<std::vector<int>> out;
  for (auto& g : groups) out.push_back(std::move(g.second));
  return out;
}

// Max-min-angle triangulation of a small polygon loop (indices into V), skipping diagonals in
// `forbidden`. Emits triangles whose orientation is opposite to the loop direction.
bool fill_loop(const std::vector<int>& loop, const Eigen::MatrixX3d& V,
               const std::unordered_map<long long, int>& edge_count, std::vector<std::array<int, 3>>& out) {
  const int L = static_cast<int>(loop.size());
  auto is_edge = [&](int i, int j) {
    const int a = std::min(loop[i], loop[j]), b = std::max(loop[i], loop[j]);
    return edge_count.count(EdgeKey::make(a, b)) > 0;
  };
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
        const double q = std::min({a, b, tri_min_angle(V, loop[i], loop[k], loop[j])});
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

// Max-min-angle edge flips on a consistently oriented manifold mesh (the dual of a CVT is
// Delaunay-like; flips repair the few diagonals the discrete labels got wrong). A flip is done
// only when the new edge does not exist yet, both end vertices keep valence >= 3, the smallest
// angle of the pair increases, and the two new triangles stay within `max_normal_deviation` of
// the old pair's normal (no folds). Returns the number of flips.
int improve_by_flips(const Eigen::MatrixX3d& V, std::vector<std::array<int, 3>>& F, int max_passes,
                     bool valence_mode = false, const std::vector<char>* only_at = nullptr) {
  std::unordered_map<long long, int> dir;  // directed edge -> face
  auto key = [](int a, int b) { return EdgeKey::make(a, b); };
  std::vector<int> valence(V.rows(), 0);
  std::unordered_map<long long, char> undirected;
  for (int f = 0; f < static_cast<int>(F.size()); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F[f][k], b = F[f][(k + 1) % 3];
      dir[key(a, b)] = f;
      if (!undirected.count(key(std::min(a, b), std::max(a, b)))) {
        undirected[key(std::min(a, b), std::max(a, b))] = 1;
        ++valence[a];
        ++valence[b];
      }
    }
  auto normal = [&](int a, int b, int c) -> Eigen::Vector3d {
    return (V.row(b) - V.row(a)).cross(V.row(c) - V.row(a)).transpose();
  };
  int flips = 0;
  for (int pass = 0; pass < max_passes; ++pass) {
    int pass_flips = 0;
    for (int f1 = 0; f1 < static_cast<int>(F.size()); ++f1)
      for (int k = 0; k < 3; ++k) {
        const int a = F[f1][k], b = F[f1][(k + 1) % 3], c = F[f1][(k + 2) % 3];
        auto it = dir.find(key(b, a));
        if (it == dir.end()) continue;
        const int f2 = it->second;
        int d = -1;
        for (int q = 0; q < 3; ++q)
          if (F[f2][q] != a && F[f2][q] != b) d = F[f2][q];
        if (d < 0 || d == c) continue;
        if (only_at && !(*only_at)[a] && !(*only_at)[b]) continue;
        if (undirected.count(key(std::min(c, d), std::max(c, d)))) continue;
        if (valence[a] <= 3 || valence[b] <= 3) continue;
        const double before = std::min(tri_min_angle(V, a, b, c), tri_min_angle(V, b, a, d));
        const double after = std::min(tri_min_angle(V, c, a, d), tri_min_angle(V, d, b, c));
        if (valence_mode) {
          // Botsch–Kobbelt: flip when it brings the four valences closer to 6 (interior target),
          // as long as the smallest angle of the pair stays above 25 degrees or improves.
          auto dev = [](int x) { return (x - 6) * (x - 6); };
          const int dv_before = dev(valence[a]) + dev(valence[b]) + dev(valence[c]) + dev(valence[d]);
          const int dv_after = dev(valence[a] - 1) + dev(valence[b] - 1) + dev(valence[c] + 1) + dev(valence[d] + 1);
          if (dv_after >= dv_before) continue;
          // Only where the pair is nearly flat (dihedral < 20 degrees): never across creases or
          // thin parts, where a valence flip can fold the surface through itself.
          const Eigen::Vector3d o1 = normal(a, b, c).normalized(), o2 = normal(b, a, d).normalized();
          if (!(o1.dot(o2) > std::cos(20.0 * M_PI / 180.0))) continue;
          if (!(after > before || after > 30.0 * M_PI / 180.0)) continue;
        } else if (!(after > before + 1e-9)) {
          continue;
        }
        const Eigen::Vector3d n1 = normal(a, b, c), n2 = normal(b, a, d);
        const Eigen::Vector3d m1 = normal(c, a, d), m2 = normal(d, b, c);
        const Eigen::Vector3d avg = (n1.normalized() + n2.normalized()).normalized();
        if (!(m1.norm() > 0) || !(m2.norm() > 0) || !avg.allFinite()) continue;
        const double cos_limit = std::cos(30.0 * M_PI / 180.0);
        if (m1.normalized().dot(avg) < cos_limit || m2.normalized().dot(avg) < cos_limit) continue;
        // Flip: (a,b,c),(b,a,d) -> (c,a,d),(d,b,c).
        for (int q = 0; q < 3; ++q) {
          dir.erase(key(F[f1][q], F[f1][(q + 1) % 3]));
          dir.erase(key(F[f2][q], F[f2][(q + 1) % 3]));
        }
        undirected.erase(key(std::min(a, b), std::max(a, b)));
        undirected[key(std::min(c, d), std::max(c, d))] = 1;
        --valence[a], --valence[b], ++valence[c], ++valence[d];
        F[f1] = {c, a, d};
        F[f2] = {d, b, c};
        for (int q = 0; q < 3; ++q) {
          dir[key(F[f1][q], F[f1][(q + 1) % 3])] = f1;
          dir[key(F[f2][q], F[f2][(q + 1) % 3])] = f2;
        }
        ++pass_flips;
        break;  // F[f1] changed: move on to the next face
      }
    flips += pass_flips;
    if (pass_flips == 0) break;
  }
  return flips;
}

// Smallest angle of a 2D triangle, or -1 when it is inverted / degenerate (counter-clockwise = valid).
double min_angle_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
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
  return std::atan2(cr, e1.dot(e2));  // |e1 × e2| = cr for every corner of a CCW triangle
}

// Quality of a one-ring: smallest angle over its triangles, and the sum of the triangles'
// smallest angles (what φm averages). Lexicographic on (min(ring min, cap), sum).
struct RingQuality {
  double min = M_PI, sum = 0;
  bool valid = true;
};

// Angle polish: Gauss–Seidel over the vertices (fixed order: deterministic), each moved within its
// tangent plane to the position that maximises the smallest angle of its one-ring (pattern search
// from the ring's area-weighted centroid and the current position), then projected back to the
// fitted surface by `project`; a move is kept only if, measured in 3D after the projection, the
// ring's smallest angle does not drop below min(old, cap) and (ring min, ring sum of smallest
// angles) improves, and no ring triangle turns against the vertex normal. Returns the moves kept.
int angle_polish(Eigen::MatrixX3d& S, Eigen::MatrixX3d& SN, const std::vector<std::array<int, 3>>& F, int rounds,
                 const std::function<void(int, const Eigen::Vector3d&, Eigen::Vector3d&, Eigen::Vector3d&)>& project,
                 const std::vector<char>& frozen, int threads) {
  const int ns = static_cast<int>(S.rows());
  std::vector<std::vector<int>> vf(ns);
  for (int id = 0; id < static_cast<int>(F.size()); ++id)
    for (int v : F[id]) vf[v].push_back(id);
  // Greedy colouring of the vertex graph in index order: a vertex's move only reads its one-ring,
  // so the vertices of one colour move in parallel, with the same result for any thread count.
  std::vector<int> colour(ns, -1);
  std::vector<std::vector<int>> by_colour;
  for (int v = 0; v < ns; ++v) {
    std::vector<char> taken;
    for (int id : vf[v])
      for (int w : F[id])
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
  const double cap = 35.0 * M_PI / 180.0;
  // Ring quality with vertex v at x (3D).
  auto ring3 = [&](int v, const Eigen::Vector3d& x, const Eigen::Vector3d& nv) {
    RingQuality q;
    for (int id : vf[v]) {
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = F[id][k] == v ? x : Eigen::Vector3d(S.row(F[id][k]));
      const Eigen::Vector3d fn = (p[1] - p[0]).cross(p[2] - p[0]);
      if (!(fn.dot(nv) > 0)) q.valid = false;
      const double a = min_angle_pts(p[0], p[1], p[2]);
      q.min = std::min(q.min, a);
      q.sum += a;
    }
    return q;
  };
  auto better = [&](const RingQuality& n, const RingQuality& o) {
    if (!n.valid) return false;
    const double nm = std::min(n.min, cap), om = std::min(o.min, cap);
    if (nm > om + 1e-9) return true;
    if (nm < om - 1e-9) return false;
    return n.sum > o.sum + 1e-9;
  };
  int moves = 0;
  for (int round = 0; round < rounds; ++round) {
    int round_moves = 0;
    for (const std::vector<int>& group : by_colour) {
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 16) reduction(+ : round_moves)
    for (size_t gi = 0; gi < group.size(); ++gi) {
      const int v = group[gi];
      if (vf[v].size() < 3 || frozen[v]) continue;
      const Eigen::Vector3d x = S.row(v), nv = SN.row(v);
      // Tangent frame.
      Eigen::Vector3d u = nv.unitOrthogonal(), w = nv.cross(u);
      // Ring triangles in 2D with v at the origin: (b, c) of each face (a = v), counter-clockwise.
      std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> ring;
      bool boundary_or_bad = false;
      double mean_edge = 0;
      Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
      double area_sum = 0;
      for (int id : vf[v]) {
        int k = 0;
        while (F[id][k] != v) ++k;
        const Eigen::Vector3d b = S.row(F[id][(k + 1) % 3]).transpose() - x, c = S.row(F[id][(k + 2) % 3]).transpose() - x;
        const Eigen::Vector2d b2(b.dot(u), b.dot(w)), c2(c.dot(u), c.dot(w));
        ring.push_back({b2, c2});
        mean_edge += b2.norm();
        const double ar = 0.5 * (b2.x() * c2.y() - b2.y() * c2.x());
        if (!(ar > 0)) boundary_or_bad = true;
        centroid += ar * (b2 + c2) / 3.0;
        area_sum += ar;
      }
      if (boundary_or_bad || !(area_sum > 0)) continue;
      // Only interior vertices: every ring edge (v, b) appears as (c, v) of another face.
      {
        std::vector<int> out_b, in_c;
        for (int id : vf[v]) {
          int k = 0;
          while (F[id][k] != v) ++k;
          out_b.push_back(F[id][(k + 1) % 3]);
          in_c.push_back(F[id][(k + 2) % 3]);
        }
        std::sort(out_b.begin(), out_b.end());
        std::sort(in_c.begin(), in_c.end());
        if (out_b != in_c) continue;
      }
      mean_edge /= ring.size();
      centroid /= area_sum;
      auto q2 = [&](const Eigen::Vector2d& y) {
        RingQuality q;
        for (const auto& [b, c] : ring) {
          const double a = min_angle_2d(y, b, c);
          if (a < 0) {
            q.valid = false;
            return q;
          }
          q.min = std::min(q.min, a);
          q.sum += a;
        }
        return q;
      };
      const RingQuality q_now = q2(Eigen::Vector2d::Zero());
      Eigen::Vector2d best = Eigen::Vector2d::Zero();
      RingQuality qb = q_now;
      if (const RingQuality qc = q2(centroid); better(qc, qb)) best = centroid, qb = qc;
      double step = 0.1 * mean_edge;
      for (int iter = 0; iter < 24 && step > 0.005 * mean_edge; ++iter) {
        bool improved = false;
        for (int d = 0; d < 8; ++d) {
          const double ang = d * M_PI / 4;
          const Eigen::Vector2d y = best + step * Eigen::Vector2d(std::cos(ang), std::sin(ang));
          const RingQuality qy = q2(y);
          if (better(qy, qb)) best = y, qb = qy, improved = true;
        }
        if (!improved) step *= 0.5;
      }
      if (best.squaredNorm() == 0) continue;
      const Eigen::Vector3d target = x + best.x() * u + best.y() * w;
      Eigen::Vector3d pos, nrm;
      project(v, target, pos, nrm);
      if (!pos.allFinite() || !nrm.allFinite()) continue;
      const RingQuality old3 = ring3(v, x, nv);
      const RingQuality new3 = ring3(v, pos, nrm);
      if (better(new3, old3)) {
        S.row(v) = pos.transpose();
        SN.row(v) = nrm.transpose();
        ++round_moves;
      }
    }
    }
    moves += round_moves;
    if (round_moves == 0) break;
  }
  return moves;
}

}  // namespace

ReconstructionResult reconstruct_surface(const Eigen::MatrixX3d& P_in, const ReconstructionOptions& options,
                                         const ReconstructionCallback& progress) {
  const auto t_start = Clock::now();
  check_options(options);
  auto report = [&](const std::string& stage, double f) {
    if (progress) progress(stage, std::clamp(f, 0.0, 1.0));
  };
  ReconstructionResult res;
  auto t_stage = Clock::now();
  auto stage_done = [&](const char* name) {  // closes the stage that started at t_stage
    res.stage_seconds.emplace_back(name, since(t_stage));
    t_stage = Clock::now();
  };
  res.points_input = static_cast<int>(P_in.rows());
  if (P_in.rows() == 0) throw InvalidInputError("reconstruct_surface: the point cloud is empty");
  for (Eigen::Index i = 0; i < P_in.rows(); ++i)
    if (!P_in.row(i).allFinite())
      throw InvalidInputError("reconstruct_surface: point " + std::to_string(i) + " has a NaN or infinite coordinate");

  // 1. Clean-up, frame, optional denoising / downsampling.
  PointCloud cloud;
  cloud.P = P_in;
  CloudReadReport clean_report;
  clean_cloud(cloud, &clean_report);
  res.points_merged = static_cast<int>(clean_report.duplicates_merged);
  const CloudFrame frame = normalize_cloud(cloud);
  Eigen::MatrixX3d P = cloud.P;
  report("preprocess", 0);
  if (options.denoise && P.rows() > options.denoise_neighbors + 1) {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
    sor.setInputCloud(to_pcl(P));
    sor.setMeanK(options.denoise_neighbors);
    sor.setStddevMulThresh(options.denoise_stddev);
    pcl::Indices kept;
    sor.filter(kept);
    std::sort(kept.begin(), kept.end());
    Eigen::MatrixX3d Q(kept.size(), 3);
    for (size_t i = 0; i < kept.size(); ++i) Q.row(i) = P.row(kept[i]);
    res.points_denoised = static_cast<int>(P.rows() - Q.rows());
    P = Q;
  }
  if (options.voxel_size > 0 && P.rows() > 0) {
    pcl::VoxelGrid<pcl::PointXYZ> vg;
    vg.setInputCloud(to_pcl(P));
    const float leaf = static_cast<float>(options.voxel_size / frame.scale);
    vg.setLeafSize(leaf, leaf, leaf);
    pcl::PointCloud<pcl::PointXYZ> out;
    vg.filter(out);
    Eigen::MatrixX3d Q(out.size(), 3);
    for (size_t i = 0; i < out.size(); ++i) Q.row(i) << out[i].x, out[i].y, out[i].z;
    res.points_voxel_removed = static_cast<int>(P.rows() - Q.rows());
    P = Q;
    if (P.rows() > 0) {  // voxel centroids may coincide in float: merge again
      PointCloud c2;
      c2.P = P;
      clean_cloud(c2);
      P = c2.P;
    }
  }
  const int n = static_cast<int>(P.rows());
  res.points_used = n;
  if (n < options.neighbors + 1)
    throw InvalidInputError("reconstruct_surface: only " + std::to_string(n) + " usable points, need at least " +
                            std::to_string(options.neighbors + 1) + " (neighbors + 1)");
  if (options.sites > n)
    throw InvalidInputError("reconstruct_surface: " + std::to_string(options.sites) + " sites requested but only " +
                            std::to_string(n) + " usable points");

  // The CVT's points: every point, or a spatially uniform subset (cvt_points_per_site). Laplacian,
  // normals, CVT and dual candidates live on them; the fitted surface uses every point.
  std::vector<int> sub;             // CVT point -> cloud point
  std::vector<int> voxel_point;     // cloud point -> the CVT point of its voxel
  if (options.cvt_points_per_site > 0) {
    const long target = std::lround(options.cvt_points_per_site * options.sites);
    if (target < 0.8 * n) sub = voxel_subsample(P, target, voxel_point);
    if (static_cast<int>(sub.size()) < std::max(options.sites, options.neighbors + 1)) sub.clear();
  }
  const bool subsampled = !sub.empty();
  if (!subsampled) {
    sub.resize(n);
    std::iota(sub.begin(), sub.end(), 0);
  }
  const int nc = static_cast<int>(sub.size());
  res.points_cvt = nc;
  Eigen::MatrixX3d PC(nc, 3);
  for (int i = 0; i < nc; ++i) PC.row(i) = P.row(sub[i]);

  // 2. Point Laplacian, normals.
  stage_done("preprocess");
  report("laplacian", 0);
  auto t0 = Clock::now();
  // Neighbourhoods, PCA normals and their orientation first: the Laplacian is then built once,
  // knowing whether the two sides of thin parts must be kept apart.
  const Eigen::MatrixXi knn_cvt = k_nearest_neighbors(PC, options.neighbors, options.threads);
  Eigen::MatrixX3d NC = estimate_normals(PC, knn_cvt, options.threads);
  // Orientation: edges leaving the tangent plane are propagated through last, so that the two
  // sides of a part thinner than the kNN neighbourhood (ears, fingers) get opposite normals.
  orient_normals_mst(PC, NC, std::min(10, options.neighbors), options.threads, 1.0);
  stage_done("normals");
  // Neighbourhoods of the fitted surface: about one output edge length across (4 cells' worth of
  // points), so that noise averages out instead of passing into the vertex positions; at least
  // `neighbors`, at most 100 points.
  const int fit_k = std::min(std::max(options.neighbors, static_cast<int>(std::lround(4.0 * n / options.sites))),
                             std::min(100, n - 1));
  const Eigen::MatrixXi knn_fit =
      fit_k == options.neighbors && !subsampled ? knn_cvt : k_nearest_neighbors(P, fit_k, options.threads);
  // Walks towards the nearest cloud point (polish) step along the first `neighbors` of them.
  const Eigen::MatrixXi knn = knn_fit.leftCols(std::min<Eigen::Index>(knn_fit.cols(), options.neighbors));
  stage_done("fit neighbourhoods");
  // Oriented normals of every cloud point: the CVT point's own, else that of the nearest CVT point
  // among its fit neighbours (on the same side of a thin part as the point), else that of the CVT
  // point of its voxel.
  Eigen::MatrixX3d N;
  if (!subsampled) {
    N = NC;
  } else {
    std::vector<int> cvt_index(n, -1);
    for (int i = 0; i < nc; ++i) cvt_index[sub[i]] = i;
    N.resize(n, 3);
    for (int i = 0; i < n; ++i) {
      int c = cvt_index[i];
      for (Eigen::Index q = 0; q < knn_fit.cols() && c < 0; ++q) c = cvt_index[knn_fit(i, q)];
      N.row(i) = NC.row(c >= 0 ? c : voxel_point[i]);
    }
  }
  stage_done("cloud normals");
  // Fit neighbourhood of cloud point c: c and its fit_k nearest points whose oriented normal
  // agrees with c's (the other side of a thin part is left out), unless too few remain.
  auto fit_neighbourhood = [&](int c) {
    std::vector<int> nb = {c};
    const Eigen::Vector3d nc = N.row(c);
    for (Eigen::Index q = 0; q < knn_fit.cols(); ++q)
      if (N.row(knn_fit(c, q)).dot(nc) > 0) nb.push_back(knn_fit(c, q));
    if (static_cast<int>(nb.size()) < std::min(12, fit_k / 2)) {
      nb.assign(1, c);
      for (Eigen::Index q = 0; q < knn_fit.cols(); ++q) nb.push_back(knn_fit(c, q));
    }
    return nb;
  };
  // The CVT points onto the fitted surface (each one projected onto the quadratic fitted to its
  // neighbourhood of the whole cloud): on a noisy scan the Laplacian is then built on points as
  // regular as a clean scan's, whose factor has less fill and whose cells are smoother. A point
  // whose projection lies farther than its mean distance to its 6 nearest CVT points stays put:
  // there the fit is not to be trusted (tips of thin parts; smoothing every point of the bunny's
  // ears left a Hausdorff distance of 0.035 of the diagonal, against 0.016 without smoothing).
  if (options.smooth_cvt_points) {
    const Eigen::MatrixX3d raw = PC;
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(static)
    for (int i = 0; i < nc; ++i) {
      Eigen::Vector3d pos, nrm;
      fit_and_project(P, fit_neighbourhood(sub[i]), raw.row(i).transpose(), NC.row(i).transpose(), pos, nrm);
      double spacing = 0;
      const int near = std::min<int>(6, static_cast<int>(knn_cvt.cols()));
      for (int q = 0; q < near; ++q) spacing += (raw.row(knn_cvt(i, q)) - raw.row(i)).norm() / near;
      if (pos.allFinite() && (pos - raw.row(i).transpose()).norm() <= spacing) PC.row(i) = pos.transpose();
    }
  }
  stage_done("smoothed cvt points");
  // Points with a neighbour of opposite normal (the other side of a thin part): where there are
  // some, the Laplacian leaves such neighbours out of each local triangulation, so that heat
  // (hence a cell) does not cross to the other side. Only where they are rare (thin parts: 4.5 %
  // on armadillo at 30k points, 5.8 % with noise): where they are common the orientation itself
  // is unreliable (cluttered scene scans: 9-80 %), and cutting the point graph there would leave
  // pieces too small to carry any dual triangle. (Measured on the 10 acceptance clouds and on
  // every cloud of ../shared/data at the all-clouds test's -n 200, k = 12: the same decisions as
  // the previous rule on the built Laplacian, <= 5 % of its triangles joining opposite normals.)
  long crossing_points = 0;
  for (int i = 0; i < nc; ++i)
    for (Eigen::Index q = 0; q < knn_cvt.cols(); ++q)
      if (NC.row(i).dot(NC.row(knn_cvt(i, q))) < 0) {
        ++crossing_points;
        break;
      }
  PointLaplacianOptions lopt;
  lopt.k = options.neighbors;
  lopt.threads = options.threads;
  lopt.neighbors = &knn_cvt;
  if (crossing_points > 0 && crossing_points <= 0.08 * nc) lopt.oriented_normals = &NC;
  PointLaplacian pl = point_laplacian(PC, lopt);
  stage_done("point laplacian");
  const Eigen::MatrixX3i& T = pl.triangles;
  Laplacian lap;
  Eigen::VectorXd metric_area;
  if (options.anisotropy > 0) {
    Eigen::MatrixXd X(nc, 6);
    X.leftCols(3) = PC;
    X.rightCols(3) = options.anisotropy * NC;
    const Eigen::MatrixX3d lengths = face_edge_lengths(X, T);
    lap = cotan_laplacian_from_lengths(lengths, T, nc);
    metric_area.resize(T.rows());
    for (Eigen::Index f = 0; f < T.rows(); ++f) {
      const double a = lengths(f, 0), b = lengths(f, 1), c = lengths(f, 2), s = 0.5 * (a + b + c);
      metric_area[f] = std::sqrt(std::max(0.0, s * (s - a) * (s - b) * (s - c)));
    }
  } else {
    lap = std::move(pl.laplacian);
  }
  res.laplacian_seconds = since(t0);
  report("laplacian", 1);

  // 3. Heat CVT on the points.
  CvtOptions copt;
  copt.sites = options.sites;
  copt.iterations = options.iterations;
  copt.seed = options.seed;
  copt.threads = options.threads;
  copt.time_coefficient = options.time_coefficient;
  copt.build_dual = false;
  if (options.farthest_point_start) {
    copt.initialization = CvtInitialization::farthest_point;
    copt.graph_lloyd_iterations = 20;
  }
  copt.relaxation = options.lloyd_relaxation;
  copt.tolerance = options.lloyd_tolerance;
  t0 = Clock::now();
  report("cvt", 0);
  if (options.surface_lloyd_iterations > 0) {
    copt.initialization = CvtInitialization::farthest_point;
    copt.surface_lloyd_iterations = options.surface_lloyd_iterations;
    copt.surface_lloyd_relaxation = 1.5;
    // The heat iterations after a surface-Lloyd start already diffuse over one ring of cells
    // (CvtOptions::voronoi_rings_settled); the final diagram does too (same cells as two rings
    // on the 10 acceptance clouds, at about half the cost of that last diffusion).
    copt.voronoi_rings = copt.voronoi_rings_settled;
  }
  const CvtResult cvt = centroidal_voronoi(
      PC, T, lap, copt, {},
      [&](const CvtIterationStats& st) {
        report("cvt", options.iterations > 0 ? static_cast<double>(st.iteration) / options.iterations : 1.0);
        return true;
      },
      metric_area);
  res.cvt_seconds = since(t0);
  res.factor_seconds = cvt.factor_seconds;
  res.iterations = static_cast<int>(cvt.iterations.size());
  double iteration_sum = 0;
  for (const auto& st : cvt.iterations) res.iteration_seconds.push_back(st.seconds), iteration_sum += st.seconds;
  res.stage_seconds.emplace_back("cvt start and final diagram", since(t_stage) - iteration_sum);
  res.stage_seconds.emplace_back("cvt iterations", iteration_sum);
  t_stage = Clock::now();
  report("mesh", 0);

  // 4. Cell label of every point (original vertices keep their indices in the refined mesh).
  const VoronoiDiagram& D = cvt.diagram;
  int ns = D.num_cells();  // grows when long edges of slivers are split (below)
  std::vector<int> label(nc, -1);
  for (Eigen::Index r = 0; r < D.F.rows(); ++r)
    for (int k = 0; k < 3; ++k) {
      const int v = D.F(r, k);
      if (v < nc && label[v] < 0) label[v] = D.face_cell[r];
    }

  // 5. Site positions on the fitted surface, fitted normals.
  Eigen::MatrixX3d S(ns, 3), SN(ns, 3);
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(static)
  for (int s = 0; s < ns; ++s) {
    const SurfacePoint& sp = cvt.sites[s];
    int corner = 0;
    sp.bary.maxCoeff(&corner);
    const int c = sub[T(sp.face, corner)];
    const std::vector<int> nb = fit_neighbourhood(c);
    Eigen::Vector3d orient = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) orient += sp.bary[k] * NC.row(T(sp.face, k)).transpose();
    if (orient.norm() == 0) orient = N.row(c).transpose();
    Eigen::Vector3d pos, nrm;
    fit_and_project(P, nb, cvt.positions.row(s).transpose(), orient, pos, nrm);
    S.row(s) = pos.transpose();
    SN.row(s) = nrm.transpose();
  }

  // 6. Candidate dual triangles witnessed by local triangles with three different labels.
  std::vector<std::array<int, 3>> cand;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    std::array<int, 3> l = {label[T(t, 0)], label[T(t, 1)], label[T(t, 2)]};
    if (l[0] < 0 || l[1] < 0 || l[2] < 0 || l[0] == l[1] || l[1] == l[2] || l[0] == l[2]) continue;
    std::sort(l.begin(), l.end());
    cand.push_back(l);
  }
  // Voronoi vertices of the exact heat tessellation (three or more cells meeting inside / on a
  // point triangle) witness their triples too; where > 3 cells meet every triple is a candidate
  // and the greedy extraction picks a consistent subset.
  std::vector<std::array<int, 3>> cand_vv;
  for (const VoronoiVertex& vv : D.voronoi_vertices) {
    const auto& c = vv.cells;
    if (c.size() > 6) continue;
    for (size_t x = 0; x < c.size(); ++x)
      for (size_t y = x + 1; y < c.size(); ++y)
        for (size_t z = y + 1; z < c.size(); ++z) {
          std::array<int, 3> t = {c[x], c[y], c[z]};
          std::sort(t.begin(), t.end());
          cand_vv.push_back(t);
        }
  }
  std::sort(cand.begin(), cand.end());
  std::sort(cand_vv.begin(), cand_vv.end());
  struct Candidate {
    std::array<int, 3> f;
    int witnesses;     // local triangles + Voronoi vertices
    int vv_witnesses;  // of which Voronoi vertices of the heat tessellation
    double quality;
  };
  // Candidates that fail the 75-degree test but whose normal is within about 107 degrees of each
  // site's normal (rims of parts thinner than the site spacing, where the dual triangles turn
  // around the edge) are kept aside and only tried in the second pass, to close holes.
  std::vector<Candidate> cands, loose;
  const double loose_dot = -0.3;
  {
    // Merge the two sorted lists with their multiplicities.
    size_t i = 0, k = 0;
    while (i < cand.size() || k < cand_vv.size()) {
      std::array<int, 3> f;
      if (k >= cand_vv.size() || (i < cand.size() && cand[i] <= cand_vv[k])) f = cand[i];
      else f = cand_vv[k];
      int w = 0, wv = 0;
      while (i < cand.size() && cand[i] == f) ++i, ++w;
      while (k < cand_vv.size() && cand_vv[k] == f) ++k, ++wv;
      const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
      const Eigen::Vector3d fn = (b - a).cross(c - a);
      const Eigen::Vector3d vn = SN.row(f[0]) + SN.row(f[1]) + SN.row(f[2]);
      if (fn.dot(vn) < 0) std::swap(f[1], f[2]);
      const double q = tri_min_angle(S, f[0], f[1], f[2]);
      // A dual triangle spans one sheet of the surface: its normal is within 75 degrees of the
      // fitted normal of each of its three sites. One whose sites' normals disagree with it
      // bridges a thin gap (two sides of a thin part, or noise-ragged cells reaching across) or
      // folds the surface: not a candidate.
      const Eigen::Vector3d fo = (S.row(f[1]) - S.row(f[0])).cross(S.row(f[2]) - S.row(f[0])).transpose();
      bool coherent = fo.norm() > 0;
      double min_dot = 1;
      for (int k = 0; k < 3 && fo.norm() > 0; ++k) min_dot = std::min(min_dot, fo.normalized().dot(SN.row(f[k]).transpose()));
      if (!(min_dot > 0.25)) coherent = false;
      if (q > 0 && coherent) cands.push_back({f, w + wv, wv, q});
      else if (q > 0 && fo.norm() > 0 && min_dot > loose_dot) loose.push_back({f, w + wv, wv, q});
    }
  }
  res.candidate_triangles = static_cast<int>(cands.size());
  stage_done("sites and candidates");
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) {
    if (x.witnesses != y.witnesses) return x.witnesses > y.witnesses;
    if (x.quality != y.quality) return x.quality > y.quality;
    return x.f < y.f;
  });

  // Greedy manifold, consistently oriented extraction.
  std::unordered_map<long long, int> directed;   // directed edge -> face
  std::unordered_map<long long, int> undirected; // undirected edge -> face count
  std::vector<std::array<int, 3>> F;
  for (const Candidate& c : cands) {
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      const int a = c.f[k], b = c.f[(k + 1) % 3];
      if (directed.count(EdgeKey::make(a, b))) ok = false;
      auto it = undirected.find(EdgeKey::make(std::min(a, b), std::max(a, b)));
      if (it != undirected.end() && it->second >= 2) ok = false;
    }
    if (!ok) {
      ++res.rejected_triangles;
      continue;
    }
    const int id = static_cast<int>(F.size());
    F.push_back(c.f);
    for (int k = 0; k < 3; ++k) {
      const int a = c.f[k], b = c.f[(k + 1) % 3];
      directed[EdgeKey::make(a, b)] = id;
      ++undirected[EdgeKey::make(std::min(a, b), std::max(a, b))];
    }
  }

  auto rebuild_edges = [&]() {
    directed.clear();
    undirected.clear();
    for (int id = 0; id < static_cast<int>(F.size()); ++id)
      for (int k = 0; k < 3; ++k) {
        const int a = F[id][k], b = F[id][(k + 1) % 3];
        directed[EdgeKey::make(a, b)] = id;
        ++undirected[EdgeKey::make(std::min(a, b), std::max(a, b))];
      }
  };
  // Non-manifold vertices: keep the largest fan; tiny components (<= 4 faces) dropped.
  auto make_vertices_manifold = [&]() {
    for (int round = 0; round < 10; ++round) {
      std::vector<std::vector<int>> vf(ns);
      for (int id = 0; id < static_cast<int>(F.size()); ++id)
        for (int k = 0; k < 3; ++k) vf[F[id][k]].push_back(id);
      std::vector<char> drop(F.size(), 0);
      bool changed = false;
      for (int v = 0; v < ns; ++v) {
        if (vf[v].size() < 2) continue;
        auto fans = vertex_fans(v, vf[v], F);
        if (fans.size() < 2) continue;
        size_t keep = 0;
        for (size_t i = 1; i < fans.size(); ++i)
          if (fans[i].size() > fans[keep].size()) keep = i;
        for (size_t i = 0; i < fans.size(); ++i)
          if (i != keep)
            for (int f : fans[i]) drop[f] = 1, changed = true;
      }
      if (!changed) break;
      std::vector<std::array<int, 3>> G;
      for (size_t i = 0; i < F.size(); ++i)
        if (!drop[i]) G.push_back(F[i]);
        else ++res.removed_triangles;
      F.swap(G);
    }
    // Components by shared edges.
    std::vector<int> parent(F.size());
    for (size_t i = 0; i < F.size(); ++i) parent[i] = static_cast<int>(i);
    std::function<int(int)> find = [&](int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); };
    std::unordered_map<long long, int> first;
    for (int id = 0; id < static_cast<int>(F.size()); ++id)
      for (int k = 0; k < 3; ++k) {
        const int a = F[id][k], b = F[id][(k + 1) % 3];
        const long long key = EdgeKey::make(std::min(a, b), std::max(a, b));
        auto it = first.find(key);
        if (it == first.end()) first[key] = id;
        else parent[find(id)] = find(it->second);
      }
    std::unordered_map<int, int> size;
    for (size_t i = 0; i < F.size(); ++i) ++size[find(static_cast<int>(i))];
    int largest = 0;
    for (const auto& [root, faces] : size) largest = std::max(largest, faces);
    // (when every piece is that small, e.g. very few sites on a cluttered scene, all are kept)
    std::vector<std::array<int, 3>> G;
    for (size_t i = 0; i < F.size(); ++i)
      if (size[find(static_cast<int>(i))] > 4 || largest <= 4) G.push_back(F[i]);
      else ++res.removed_triangles;
    F.swap(G);
    rebuild_edges();
  };
  make_vertices_manifold();

  // Second pass: candidates that were rejected or removed may fit now, if they keep every edge
  // and every vertex manifold.
  {
    std::set<std::array<int, 3>> present;
    auto canon = [](std::array<int, 3> f) {
      std::sort(f.begin(), f.end());
      return f;
    };
    for (const auto& f : F) present.insert(canon(f));
    std::vector<std::vector<int>> vf(ns);
    for (int id = 0; id < static_cast<int>(F.size()); ++id)
      for (int k = 0; k < 3; ++k) vf[F[id][k]].push_back(id);
    int added = 0;
    std::stable_sort(loose.begin(), loose.end(), [](const Candidate& x, const Candidate& y) {
      if (x.witnesses != y.witnesses) return x.witnesses > y.witnesses;
      if (x.quality != y.quality) return x.quality > y.quality;
      return x.f < y.f;
    });
    std::vector<Candidate> second = cands;
    second.insert(second.end(), loose.begin(), loose.end());
    for (const Candidate& c : second) {
      if (present.count(canon(c.f))) continue;
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        const int a = c.f[k], b = c.f[(k + 1) % 3];
        if (directed.count(EdgeKey::make(a, b))) ok = false;
        auto it = undirected.find(EdgeKey::make(std::min(a, b), std::max(a, b)));
        if (it != undirected.end() && it->second >= 2) ok = false;
      }
      if (!ok) continue;
      const int id = static_cast<int>(F.size());
      F.push_back(c.f);
      for (int k = 0; k < 3 && ok; ++k) {
        std::vector<int> faces = vf[c.f[k]];
        faces.push_back(id);
        if (vertex_fans(c.f[k], faces, F).size() > 1) ok = false;
      }
      if (!ok) {
        F.pop_back();
        continue;
      }
      present.insert(canon(c.f));
      for (int k = 0; k < 3; ++k) {
        const int a = c.f[k], b = c.f[(k + 1) % 3];
        directed[EdgeKey::make(a, b)] = id;
        ++undirected[EdgeKey::make(std::min(a, b), std::max(a, b))];
        vf[c.f[k]].push_back(id);
      }
      ++added;
    }
    res.rejected_triangles -= added;
  }

  // Small holes: boundary loops of <= max_hole_edges edges. A loop of up to 4x that length is
  // filled too when it is a hole of the extraction, not a scan boundary: the centre of the loop
  // is away from every triangle (> h/4, h = mean loop edge) but has cloud points near it (< h/2);
  // and a loop of up to 8x that length when the cloud continues beyond its edges (below).
  auto is_sampled_hole = [&](const std::vector<int>& loop) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double h = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      g += S.row(loop[i]).transpose();
      h += (S.row(loop[i]) - S.row(loop[(i + 1) % loop.size()])).norm();
    }
    g /= static_cast<double>(loop.size());
    h /= static_cast<double>(loop.size());
    double dp = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) dp = std::min(dp, (P.row(i).transpose() - g).squaredNorm());
    if (!(std::sqrt(dp) < 0.5 * h)) return false;
    for (const auto& f : F) {
      const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
      const Eigen::Vector3d bc = closest_point_barycentric(g, a, b, c);
      if ((bc[0] * a + bc[1] * b + bc[2] * c - g).norm() < 0.25 * h) return false;
    }
    return true;
  };
  // Second test for longer or curved loops (whose centre may be off the surface): beyond every
  // boundary edge, one edge length outward in the plane of its triangle, there is sampled surface
  // (a cloud point within half an edge length) for at least 30 % of the edges. Across the
  // border of an open scan there is none.
  auto is_surrounded_hole = [&](const std::vector<int>& loop) {
    int sampled = 0;
    const int L = static_cast<int>(loop.size());
    for (int i = 0; i < L; ++i) {
      const int a = loop[i], b = loop[(i + 1) % L];
      auto it = directed.find(EdgeKey::make(a, b));
      if (it == directed.end()) continue;
      const auto& f = F[it->second];
      const Eigen::Vector3d p0 = S.row(f[0]), p1 = S.row(f[1]), p2 = S.row(f[2]);
      const Eigen::Vector3d fn = (p1 - p0).cross(p2 - p0);
      const Eigen::Vector3d e = S.row(b) - S.row(a);
      if (!(fn.norm() > 0) || !(e.norm() > 0)) continue;
      const Eigen::Vector3d out = e.cross(fn).normalized();
      const double len = e.norm();
      const Eigen::Vector3d probe = 0.5 * (S.row(a) + S.row(b)).transpose() + len * out;
      double dp = std::numeric_limits<double>::infinity();
      for (int q = 0; q < n; ++q) dp = std::min(dp, (P.row(q).transpose() - probe).squaredNorm());
      if (std::sqrt(dp) < 0.5 * len) ++sampled;
    }
    return sampled >= 0.3 * L;
  };
  const int max_loop = 8 * options.max_hole_edges;
  auto fill_holes = [&]() {
  for (int pass = 0; pass < 3; ++pass) {
    std::unordered_map<int, std::vector<int>> next;  // boundary half-edge a->b (face side) by start vertex
    std::vector<std::pair<int, int>> bedges;
    for (const auto& f : F)
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if (!directed.count(EdgeKey::make(b, a))) {
          next[a].push_back(b);
          bedges.push_back({a, b});
        }
      }
    if (bedges.empty()) break;
    std::sort(bedges.begin(), bedges.end());
    std::unordered_map<long long, char> used;
    std::vector<std::array<int, 3>> added;
    int filled = 0;
    for (const auto& [a0, b0] : bedges) {
      if (used.count(EdgeKey::make(a0, b0))) continue;
      std::vector<int> loop = {a0};
      int cur = b0;
      bool simple = true;
      used[EdgeKey::make(a0, b0)] = 1;
      while (cur != a0 && static_cast<int>(loop.size()) <= max_loop + 1) {
        auto it = next.find(cur);
        if (it == next.end() || it->second.size() != 1) {
          simple = false;
          break;
        }
        loop.push_back(cur);
        used[EdgeKey::make(cur, it->second[0])] = 1;
        cur = it->second[0];
      }
      if (!simple || cur != a0 || static_cast<int>(loop.size()) > max_loop || loop.size() < 3) continue;
      if (static_cast<int>(loop.size()) > options.max_hole_edges &&
          !((static_cast<int>(loop.size()) <= 4 * options.max_hole_edges && is_sampled_hole(loop)) ||
            is_surrounded_hole(loop)))
        continue;
      std::vector<int> sorted = loop;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
      std::vector<std::array<int, 3>> tris;
      if (loop.size() == 3) {
        // A 3-loop that is the back of an existing face would duplicate it: skip.
        if (directed.count(EdgeKey::make(loop[1], loop[0])) && directed.count(EdgeKey::make(loop[2], loop[1])) &&
            directed.count(EdgeKey::make(loop[0], loop[2])) &&
            directed[EdgeKey::make(loop[1], loop[0])] == directed[EdgeKey::make(loop[2], loop[1])] &&
            directed[EdgeKey::make(loop[2], loop[1])] == directed[EdgeKey::make(loop[0], loop[2])])
          continue;
      }
      if (!fill_loop(loop, S, undirected, tris)) continue;
      for (const auto& t : tris) added.push_back(t);
      ++filled;
    }
    if (added.empty()) break;
    for (const auto& t : added) F.push_back(t);
    res.holes_filled += filled;
    make_vertices_manifold();
  }
  };
  fill_holes();
  stage_done("extraction and holes");

  // Faces of F involved in a self-intersection (CGAL, face i = F[i]).
  // CGAL checks of the current faces F on the sites S (unused sites left out; face i = F[i]).
  auto check_current = [&](int max_listed) {
    std::vector<int> map(ns, -1);
    int m = 0;
    for (const auto& f : F)
      for (int v : f)
        if (map[v] < 0) map[v] = m++;
    Eigen::MatrixX3d VV(m, 3);
    for (int v = 0; v < ns; ++v)
      if (map[v] >= 0) VV.row(map[v]) = S.row(v);
    Eigen::MatrixX3i FF(F.size(), 3);
    for (size_t i = 0; i < F.size(); ++i)
      for (int k = 0; k < 3; ++k) FF(i, k) = map[F[i][k]];
    ValidationOptions vo;
    vo.require_closed = false;
    vo.max_listed = max_listed;
    return validate_triangle_mesh(VV, FF, vo);
  };
  auto intersecting_faces = [&]() {
    std::vector<int> out;
    if (F.empty()) return out;
    const ValidationReport rep = check_current(std::numeric_limits<int>::max());
    for (const auto& c : rep.checks)
      if (c.name == "no_self_intersections")
        for (const auto& w : c.where)
          for (int f : w) out.push_back(f);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  };
  // Untangling: the faces of every intersecting pair are removed (with their vertex neighbours
  // from the second round on), the mesh is made manifold again and the holes are refilled by the
  // same rules as above (sampled surface beyond them), until no intersection is left.
  auto untangle = [&]() {
    for (int round = 0; round < 4; ++round) {
      const std::vector<int> bad = intersecting_faces();
      if (bad.empty()) break;
      std::vector<char> drop(F.size(), 0);
      std::vector<char> vbad(ns, 0);
      for (int f : bad) {
        drop[f] = 1;
        for (int v : F[f]) vbad[v] = 1;
      }
      if (round > 0)
        for (size_t i = 0; i < F.size(); ++i)
          if (vbad[F[i][0]] || vbad[F[i][1]] || vbad[F[i][2]]) drop[i] = 1;
      std::vector<std::array<int, 3>> G;
      for (size_t i = 0; i < F.size(); ++i)
        if (!drop[i]) G.push_back(F[i]);
        else ++res.removed_triangles;
      F.swap(G);
      make_vertices_manifold();
      fill_holes();
    }
  };
  untangle();
  stage_done("untangle");

  // Interior vertices of valence 3 (a tiny cell squeezed between three others; their triangles
  // cannot have a smallest angle above 30 degrees, and no flip can remove them): the vertex and
  // its three triangles are replaced by the triangle of its ring, when the ring vertices keep
  // valence >= 3, that triangle is new and it faces the same way as the three it replaces.
  auto remove_valence3 = [&](const std::vector<char>* only = nullptr) {
    int removed = 0;
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<std::vector<int>> vf(ns);
      for (int id = 0; id < static_cast<int>(F.size()); ++id)
        for (int v : F[id]) vf[v].push_back(id);
      std::set<std::array<int, 3>> present;
      for (auto f : F) {
        std::sort(f.begin(), f.end());
        present.insert(f);
      }
      std::vector<char> drop(F.size(), 0), touched(ns, 0);
      std::vector<std::array<int, 3>> added;
      for (int v = 0; v < ns; ++v) {
        if (vf[v].size() != 3 || touched[v] || (only && !(*only)[v])) continue;
        // Ring order: for each face (v, x, y) in rotation, x -> y.
        std::map<int, int> next;
        for (int id : vf[v]) {
          int k = 0;
          while (F[id][k] != v) ++k;
          next[F[id][(k + 1) % 3]] = F[id][(k + 2) % 3];
        }
        if (next.size() != 3) continue;
        const int a = next.begin()->first, b = next[a], c = next.count(b) ? next[b] : -1;
        if (c < 0 || !next.count(c) || next[c] != a || a == b || b == c || a == c) continue;
        if (touched[a] || touched[b] || touched[c]) continue;
        if (vf[a].size() < 4 || vf[b].size() < 4 || vf[c].size() < 4) continue;
        std::array<int, 3> key = {a, b, c};
        std::sort(key.begin(), key.end());
        if (present.count(key)) continue;
        const Eigen::Vector3d fn = (S.row(b) - S.row(a)).cross(S.row(c) - S.row(a)).transpose();
        Eigen::Vector3d old_n = Eigen::Vector3d::Zero();
        for (int id : vf[v])
          old_n += (S.row(F[id][1]) - S.row(F[id][0])).cross(S.row(F[id][2]) - S.row(F[id][0])).transpose();
        if (!(fn.dot(old_n) > 0)) continue;
        for (int id : vf[v]) drop[id] = 1;
        touched[v] = touched[a] = touched[b] = touched[c] = 1;
        added.push_back({a, b, c});
        present.insert(key);
      }
      if (added.empty()) break;
      std::vector<std::array<int, 3>> G;
      for (size_t i = 0; i < F.size(); ++i)
        if (!drop[i]) G.push_back(F[i]);
      for (const auto& t : added) G.push_back(t);
      removed += static_cast<int>(added.size());
      F.swap(G);
    }
    rebuild_edges();
    return removed;
  };
  remove_valence3();

  // Max-min-angle flips of wrongly chosen diagonals.
  res.flipped_edges = improve_by_flips(S, F, 20);

  // Optional polish: tangential relaxation of every vertex towards the area-weighted centroid of
  // its one-ring, re-projected onto the fitted surface of the cloud, alternating with flips.
  const Eigen::MatrixX3d S_unpolished = S, SN_unpolished = SN;
  const std::vector<std::array<int, 3>> F_unpolished = F;
  const int flips_unpolished = res.flipped_edges;
  // Anchor (nearest cloud point) of every site, followed by a greedy walk on the kNN graph;
  // project(v, x) = x projected onto the surface fitted around the anchor of x.
  std::vector<int> anchor(ns);
  auto reset_anchors = [&]() {
    for (int s = 0; s < ns; ++s) {
      int corner = 0;
      cvt.sites[s].bary.maxCoeff(&corner);
      anchor[s] = sub[T(cvt.sites[s].face, corner)];
    }
  };
  auto walk = [&](int start, const Eigen::Vector3d& x) {
    int cur = start;
    double best = (P.row(cur).transpose() - x).squaredNorm();
    for (int step = 0; step < 1000; ++step) {
      int nxt = cur;
      for (Eigen::Index q = 0; q < knn.cols(); ++q) {
        const double d = (P.row(knn(cur, q)).transpose() - x).squaredNorm();
        if (d < best) best = d, nxt = knn(cur, q);
      }
      if (nxt == cur) break;
      cur = nxt;
    }
    return cur;
  };
  auto project = [&](int v, const Eigen::Vector3d& target, Eigen::Vector3d& pos, Eigen::Vector3d& nrm) {
    const int c = walk(anchor[v], target);
    const std::vector<int> nb = fit_neighbourhood(c);
    fit_and_project(P, nb, target, N.row(c).transpose(), pos, nrm);
    anchor[v] = c;
  };
  auto polish = [&](bool use_valence) {
  reset_anchors();
  if (options.relaxation_iterations > 0) {
    for (int it = 0; it < options.relaxation_iterations; ++it) {
      Eigen::MatrixX3d C = Eigen::MatrixX3d::Zero(ns, 3);
      Eigen::VectorXd W = Eigen::VectorXd::Zero(ns);
      for (const auto& f : F) {
        const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
        const double area = 0.5 * (b - a).cross(c - a).norm();
        const Eigen::Vector3d g = (a + b + c) / 3.0;
        for (int v : f) {
          C.row(v) += area * g.transpose();
          W[v] += area;
        }
      }
      Eigen::MatrixX3d S2 = S, SN2 = SN;
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(static)
      for (int v = 0; v < ns; ++v) {
        if (!(W[v] > 0)) continue;
        const Eigen::Vector3d x = S.row(v), nv = SN.row(v);
        Eigen::Vector3d d = C.row(v).transpose() / W[v] - x;
        d -= d.dot(nv) * nv;
        const Eigen::Vector3d target = x + d;
        Eigen::Vector3d pos, nrm;
        project(v, target, pos, nrm);
        S2.row(v) = pos.transpose();
        SN2.row(v) = nrm.transpose();
      }
      // Keep a move only if none of the vertex's triangles flips against its normal.
      std::vector<std::vector<int>> vf(ns);
      for (int id = 0; id < static_cast<int>(F.size()); ++id)
        for (int v : F[id]) vf[v].push_back(id);
      for (int v = 0; v < ns; ++v) {
        bool ok = true;
        for (int id : vf[v]) {
          Eigen::Vector3d p[3];
          for (int k = 0; k < 3; ++k) p[k] = (F[id][k] == v ? S2 : S).row(F[id][k]).transpose();
          const Eigen::Vector3d fn = (p[1] - p[0]).cross(p[2] - p[0]);
          if (!(fn.dot(SN2.row(v).transpose()) > 0)) ok = false;
        }
        if (ok) {
          S.row(v) = S2.row(v);
          SN.row(v) = SN2.row(v);
        }
      }
      // Valence-equalising flips in the first iterations, Delaunay (max-min-angle) flips in the
      // last two so that no flip that hurts the smallest angle survives.
      const bool valence_phase = use_valence && it + 2 < options.relaxation_iterations;
      res.flipped_edges += improve_by_flips(S, F, 5, valence_phase);
    }
  }

  };
  // Valence flips can fold thin parts through themselves: if the polished mesh self-intersects,
  // polish again from the unpolished mesh with Delaunay flips only.
  auto self_intersections = [&]() -> long {
    if (F.empty()) return 0;
    return std::max(0L, check_current(1).self_intersecting_pairs);
  };
  polish(true);
  // Where the valence polish folded a thin part through itself, untangle locally first.
  if (options.relaxation_iterations > 0 && self_intersections() > 0) {
    untangle();
    res.flipped_edges += improve_by_flips(S, F, 5, false);
  }
  if (options.relaxation_iterations > 0 && self_intersections() > 0) {
    S = S_unpolished;
    SN = SN_unpolished;
    F = F_unpolished;
    res.flipped_edges = flips_unpolished;
    res.polish_fallback = true;
    polish(false);
    if (self_intersections() > 0) {
      untangle();
      res.flipped_edges += improve_by_flips(S, F, 5, false);
    }
  }

  stage_done("relaxation polish");
  // Angle polish (smallest-angle-improving tangential moves on the fitted surface) alternating
  // with max-min-angle flips. Undone if it makes the mesh self-intersect.
  if (options.relaxation_iterations > 0) {
    const Eigen::MatrixX3d S_before = S, SN_before = SN;
    const std::vector<std::array<int, 3>> F_before = F;
    const int flips_before = res.flipped_edges;
    // Where it makes the mesh self-intersect (thin parts), it is redone from the same start with
    // the vertices of the intersecting triangles and their neighbours held fixed (twice), and
    // undone as a whole only if that does not help.
    std::vector<char> frozen(ns, 0);
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (remove_valence3() > 0) res.flipped_edges += improve_by_flips(S, F, 5, false);
      for (int r = 0; r < 4; ++r) {
        angle_polish(S, SN, F, 2, project, frozen, options.threads);
        res.flipped_edges += improve_by_flips(S, F, 5, false);
      }
      const std::vector<int> bad = intersecting_faces();
      if (bad.empty()) break;
      std::vector<char> vbad(ns, 0);
      for (int f : bad)
        for (int v : F[f]) vbad[v] = 1;
      for (const auto& f : F)
        if (vbad[f[0]] || vbad[f[1]] || vbad[f[2]])
          for (int v : f) frozen[v] = 1;
      S = S_before;
      SN = SN_before;
      F = F_before;
      res.flipped_edges = flips_before;
      if (attempt == 2) res.angle_polish_undone = true;
    }
  }

  stage_done("angle polish");
  // Slivers left where the polish could not reach (filled holes at thin tips, held vertices):
  // an edge of a triangle whose smallest angle is below 25 degrees (the shortest that qualifies) is collapsed when
  // the link condition holds, the two opposite vertices keep valence >= 3, no triangle of the new
  // ring turns by more than 60 degrees, and the ring's smallest angle improves (merged vertex at
  // either end point or at the midpoint projected to the fitted surface, whichever is best).
  // Undone if the result self-intersects.
  if (options.relaxation_iterations > 0) {
    const Eigen::MatrixX3d S_before = S, SN_before = SN;
    const std::vector<std::array<int, 3>> F_before = F;
    const double thr = 25.0 * M_PI / 180.0;
    int collapsed = 0;
    for (int pass = 0; pass < 6; ++pass) {
      std::vector<std::vector<int>> vf(ns);
      for (int id = 0; id < static_cast<int>(F.size()); ++id)
        for (int v : F[id]) vf[v].push_back(id);
      std::vector<char> dead(F.size(), 0), touched(ns, 0);
      // Vertices on a boundary are left alone (collapsing an inner edge between two of them
      // would pinch the surface into a non-manifold vertex).
      {
        std::unordered_map<long long, char> half;
        for (const auto& f : F)
          for (int q = 0; q < 3; ++q) half[EdgeKey::make(f[q], f[(q + 1) % 3])] = 1;
        for (const auto& f : F)
          for (int q = 0; q < 3; ++q)
            if (!half.count(EdgeKey::make(f[(q + 1) % 3], f[q]))) touched[f[q]] = touched[f[(q + 1) % 3]] = 1;
      }
      int pass_done = 0;
      for (int id = 0; id < static_cast<int>(F.size()); ++id) {
        const std::array<int, 3> f = F[id];
        if (dead[id] || touched[f[0]] || touched[f[1]] || touched[f[2]]) continue;
        if (tri_min_angle(S, f[0], f[1], f[2]) >= thr) continue;
        // Edges by increasing length; the first one whose collapse is allowed and helps.
        std::array<int, 3> order = {0, 1, 2};
        std::sort(order.begin(), order.end(), [&](int x, int y) {
          const double lx = (S.row(f[x]) - S.row(f[(x + 1) % 3])).norm(), ly = (S.row(f[y]) - S.row(f[(y + 1) % 3])).norm();
          return lx != ly ? lx < ly : x < y;
        });
        for (int k : order) {
        const int a = f[k], b = f[(k + 1) % 3];
        std::vector<int> shared, others;
        std::set<int> na, nb;
        for (int g : vf[a]) {
          const auto& h = F[g];
          if (h[0] == b || h[1] == b || h[2] == b) shared.push_back(g);
          for (int v : h)
            if (v != a) na.insert(v);
        }
        for (int g : vf[b]) {
          const auto& h = F[g];
          if (!(h[0] == a || h[1] == a || h[2] == a)) others.push_back(g);
          for (int v : h)
            if (v != b) nb.insert(v);
        }
        if (shared.size() != 2) continue;
        std::vector<int> common;
        for (int v : na)
          if (v != b && nb.count(v)) common.push_back(v);
        if (common.size() != 2) continue;
        if (vf[common[0]].size() < 4 || vf[common[1]].size() < 4 || vf[a].size() + vf[b].size() < 7) continue;
        // The ring after the collapse: faces of a and b except the two shared ones, b -> a.
        std::vector<int> ring;
        for (int g : vf[a])
          if (std::find(shared.begin(), shared.end(), g) == shared.end()) ring.push_back(g);
        for (int g : others) ring.push_back(g);
        double old_min = M_PI;
        for (int g : vf[a]) old_min = std::min(old_min, tri_min_angle(S, F[g][0], F[g][1], F[g][2]));
        for (int g : others) old_min = std::min(old_min, tri_min_angle(S, F[g][0], F[g][1], F[g][2]));
        Eigen::Vector3d mid_pos, mid_nrm;
        project(a, 0.5 * (S.row(a) + S.row(b)).transpose(), mid_pos, mid_nrm);
        const Eigen::Vector3d cand_pos[3] = {mid_pos, S.row(a).transpose(), S.row(b).transpose()};
        const Eigen::Vector3d cand_nrm[3] = {mid_nrm, SN.row(a).transpose(), SN.row(b).transpose()};
        double best_min = old_min;
        int best = -1;
        for (int c = 0; c < 3; ++c) {
          if (!cand_pos[c].allFinite() || !cand_nrm[c].allFinite()) continue;
          double m = M_PI;
          bool ok = true;
          for (int g : ring) {
            Eigen::Vector3d p[3];
            for (int q = 0; q < 3; ++q) p[q] = (F[g][q] == a || F[g][q] == b) ? cand_pos[c] : Eigen::Vector3d(S.row(F[g][q]));
            const Eigen::Vector3d old_n =
                (S.row(F[g][1]) - S.row(F[g][0])).cross(S.row(F[g][2]) - S.row(F[g][0])).transpose();
            const Eigen::Vector3d new_n = (p[1] - p[0]).cross(p[2] - p[0]);
            if (!(new_n.norm() > 0) || !(old_n.norm() > 0) || new_n.normalized().dot(old_n.normalized()) < 0.5) {
              ok = false;
              break;
            }
            m = std::min(m, min_angle_pts(p[0], p[1], p[2]));
          }
          if (ok && m > best_min + 1e-9) best_min = m, best = c;
        }
        if (best < 0) continue;
        S.row(a) = cand_pos[best].transpose();
        SN.row(a) = cand_nrm[best].transpose();
        for (int g : shared) dead[g] = 1;
        for (int g : others)
          for (int q = 0; q < 3; ++q)
            if (F[g][q] == b) F[g][q] = a;
        for (int g : ring)
          for (int v : F[g]) touched[v] = 1;
        touched[a] = touched[b] = 1;
        ++pass_done;
        break;
        }
      }
      if (pass_done == 0) break;
      collapsed += pass_done;
      std::vector<std::array<int, 3>> G;
      for (size_t i = 0; i < F.size(); ++i)
        if (!dead[i]) G.push_back(F[i]);
      F.swap(G);
      res.flipped_edges += improve_by_flips(S, F, 5, false);
    }
    if (collapsed > 0 && self_intersections() > 0) {
      S = S_before;
      SN = SN_before;
      F = F_before;
    } else {
      res.collapsed_edges = collapsed;
    }
  }

  // The collapses can leave interior vertices of valence 3 in slivers (< 25°; no flip removes
  // them): those are removed once more, undone if that makes the mesh self-intersect.
  if (options.relaxation_iterations > 0) {
    const std::vector<std::array<int, 3>> F_before = F;
    const int flips_before = res.flipped_edges;
    std::vector<char> in_sliver(ns, 0);
    for (const auto& f : F)
      if (tri_min_angle(S, f[0], f[1], f[2]) < 25.0 * M_PI / 180.0)
        for (int v : f) in_sliver[v] = 1;
    if (remove_valence3(&in_sliver) > 0) {
      res.flipped_edges += improve_by_flips(S, F, 5, false, &in_sliver);
      if (self_intersections() > 0) {
        F = F_before;
        res.flipped_edges = flips_before;
        rebuild_edges();
      }
    }
  }
  stage_done("sliver collapse");

  // Slivers still left have a long edge (a filled hole at a thin tip spans several cell widths):
  // each such edge, > 1.5 × the mean edge length, is split at its midpoint projected onto the
  // fitted surface (both triangles halved), then max-min-angle flips and an angle polish of the
  // new vertices and their neighbours. A split whose neighbourhood then self-intersects (around a
  // tip the midpoint may project onto the other side) is left out and the rest redone.
  if (options.relaxation_iterations > 0) {
    const Eigen::MatrixX3d S_before = S, SN_before = SN;
    const std::vector<std::array<int, 3>> F_before = F;
    const std::vector<int> anchor_before = anchor;
    const int ns_before = ns, flips_before = res.flipped_edges;
    const double thr = 25.0 * M_PI / 180.0;
    std::set<long long> excluded;  // edges (of the original vertices) not to split
    auto restore = [&]() {
      S = S_before;
      SN = SN_before;
      F = F_before;
      anchor = anchor_before;
      ns = ns_before;
      res.flipped_edges = flips_before;
    };
    for (int attempt = 0; attempt < 4; ++attempt) {
      int split = 0;
      std::vector<std::pair<std::array<int, 5>, long long>> made;  // (a, b, c, d, new vertex), split edge
      for (int pass = 0; pass < 3 && !F.empty(); ++pass) {
        double mean_edge = 0;
        std::unordered_map<long long, std::vector<int>> edge_faces;
        for (int id = 0; id < static_cast<int>(F.size()); ++id)
          for (int k = 0; k < 3; ++k) {
            const int a = F[id][k], b = F[id][(k + 1) % 3];
            mean_edge += (S.row(a) - S.row(b)).norm();
            edge_faces[EdgeKey::make(std::min(a, b), std::max(a, b))].push_back(id);
          }
        mean_edge /= 3.0 * static_cast<double>(F.size());
        std::vector<char> touched(F.size(), 0);
        std::vector<std::array<int, 3>> added;
        std::vector<char> near_new(ns, 0);
        for (int id = 0; id < static_cast<int>(F.size()); ++id) {
          const std::array<int, 3> f = F[id];
          if (touched[id] || tri_min_angle(S, f[0], f[1], f[2]) >= thr) continue;
          int k = 0;
          double longest = 0;
          for (int q = 0; q < 3; ++q) {
            const double len = (S.row(f[q]) - S.row(f[(q + 1) % 3])).norm();
            if (len > longest) longest = len, k = q;
          }
          if (!(longest > 1.5 * mean_edge)) continue;
          const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
          const long long key = EdgeKey::make(std::min(a, b), std::max(a, b));
          if (excluded.count(key)) continue;
          const auto& ef = edge_faces[key];
          if (ef.size() != 2) continue;
          const int other = ef[0] == id ? ef[1] : ef[0];
          if (touched[other]) continue;
          int d = -1;
          for (int v : F[other])
            if (v != a && v != b) d = v;
          if (d < 0 || d == c) continue;
          Eigen::Vector3d pos, nrm;
          project(a, 0.5 * (S.row(a) + S.row(b)).transpose(), pos, nrm);
          if (!pos.allFinite() || !nrm.allFinite()) continue;
          const int m = ns++;
          S.conservativeResize(ns, 3);
          SN.conservativeResize(ns, 3);
          S.row(m) = pos.transpose();
          SN.row(m) = nrm.transpose();
          anchor.push_back(anchor[a]);
          // (a, b, c) → (a, m, c), (m, b, c); the neighbour (b, a, d) → (b, m, d), (m, a, d).
          F[id] = {a, m, c};
          added.push_back({m, b, c});
          F[other] = {b, m, d};
          added.push_back({m, a, d});
          touched[id] = touched[other] = 1;
          near_new.resize(ns, 0);
          for (int v : {a, b, c, d, m}) near_new[v] = 1;
          made.push_back({{a, b, c, d, m}, key});
          ++split;
        }
        if (added.empty()) break;
        for (const auto& t : added) F.push_back(t);
        res.flipped_edges += improve_by_flips(S, F, 5, false, &near_new);
        std::vector<char> frozen(ns, 1);
        for (int v = 0; v < ns; ++v)
          if (near_new[v]) frozen[v] = 0;
        angle_polish(S, SN, F, 4, project, frozen, options.threads);
        res.flipped_edges += improve_by_flips(S, F, 5, false, &near_new);
      }
      if (split == 0) break;
      const std::vector<int> bad = intersecting_faces();
      if (bad.empty()) {
        res.split_edges = split;
        break;
      }
      // Leave out the splits whose vertices are in or next to an intersecting face; redo.
      std::vector<char> in_bad(ns, 0), vbad(ns, 0);
      for (int f : bad)
        for (int v : F[f]) in_bad[v] = 1;
      for (const auto& f : F)
        if (in_bad[f[0]] || in_bad[f[1]] || in_bad[f[2]])
          for (int v : f) vbad[v] = 1;
      bool any = false;
      for (const auto& [verts, key] : made)
        if (std::any_of(verts.begin(), verts.end(), [&](int v) { return vbad[v] != 0; })) excluded.insert(key), any = true;
      restore();
      if (!any) break;  // the intersection is not the splits' doing: keep the mesh as it was
    }
  }
  stage_done("long-edge split");
  // Tiny closed pieces (a few sites of a thin tip that closed up on their own, detached from the
  // surface by the clean-up): components of fewer than 20 triangles are dropped.
  // Closed pieces face outward: the normals' global sign comes from the MST orientation's root
  // (the topmost point, made to face +z), which a noisy tip can get wrong, so a closed component
  // with negative enclosed volume is turned inside out. Open pieces (scans) keep their sign.
  {
    std::vector<int> parent(ns);
    for (int i = 0; i < ns; ++i) parent[i] = i;
    std::function<int(int)> find = [&](int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); };
    for (const auto& f : F) {
      parent[find(f[0])] = find(f[1]);
      parent[find(f[1])] = find(f[2]);
    }
    std::vector<int> count(ns, 0);
    for (const auto& f : F) ++count[find(f[0])];
    std::vector<std::array<int, 3>> G;
    for (const auto& f : F)
      if (count[find(f[0])] >= 20) G.push_back(f);
      else ++res.removed_triangles;
    if (!G.empty()) F.swap(G);
    std::unordered_set<long long> half;
    for (const auto& f : F)
      for (int k = 0; k < 3; ++k) half.insert(EdgeKey::make(f[k], f[(k + 1) % 3]));
    std::unordered_map<int, double> volume;
    std::unordered_set<int> open;
    const Eigen::RowVector3d centre = S.colwise().mean();
    for (const auto& f : F) {
      const int root = find(f[0]);
      const Eigen::RowVector3d a = S.row(f[0]) - centre, b = S.row(f[1]) - centre, c = S.row(f[2]) - centre;
      volume[root] += a.dot(b.cross(c)) / 6.0;
      for (int k = 0; k < 3; ++k)
        if (!half.count(EdgeKey::make(f[(k + 1) % 3], f[k]))) open.insert(root);
    }
    for (auto& f : F)
      if (const int root = find(f[0]); !open.count(root) && volume[root] < 0) {
        std::swap(f[1], f[2]);
        ++res.faces_turned_outward;
      }
  }

  // 7. Compact: drop unused sites, restore the frame.
  std::vector<int> remap(ns, -1);
  int nv = 0;
  for (const auto& f : F)
    for (int v : f)
      if (remap[v] < 0) remap[v] = nv++;
  // Keep vertex order by site index for determinism / readability.
  nv = 0;
  std::vector<char> used_site(ns, 0);
  for (const auto& f : F)
    for (int v : f) used_site[v] = 1;
  for (int s = 0; s < ns; ++s) remap[s] = used_site[s] ? nv++ : -1;
  res.unused_sites = ns - nv;
  if (F.empty()) throw Error("reconstruct_surface: no triangle could be extracted from the Voronoi diagram of " +
                             std::to_string(ns) + " sites on " + std::to_string(n) + " points");
  res.mesh.V.resize(nv, 3);
  for (int s = 0; s < ns; ++s)
    if (remap[s] >= 0) res.mesh.V.row(remap[s]) = S.row(s);
  res.mesh.F.resize(F.size(), 3);
  for (size_t i = 0; i < F.size(); ++i)
    for (int k = 0; k < 3; ++k) res.mesh.F(i, k) = remap[F[i][k]];
  restore_frame(res.mesh.V, frame);

  const TriangleQuality tq = triangle_quality(res.mesh.V, res.mesh.F);
  res.min_angle_deg = tq.min_angle_deg;
  res.mean_min_angle_deg = tq.mean_min_angle_deg;
  stage_done("compact");
  report("validate", 0);
  ValidationOptions vopt;
  vopt.require_closed = false;
  res.validation = validate_triangle_mesh(res.mesh.V, res.mesh.F, vopt);
  stage_done("validate");
  report("validate", 1);
  res.total_seconds = since(t_start);
  return res;
}

}  // namespace heatcvt

namespace heatcvt {

Eigen::MatrixX3d sample_surface(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, int count, std::uint32_t seed,
                                double noise_sigma) {
  if (count < 1) throw InvalidInputError("sample_surface: count must be >= 1");
  if (!(noise_sigma >= 0) || !std::isfinite(noise_sigma)) throw InvalidInputError("sample_surface: noise_sigma must be >= 0");
  if (F.rows() == 0) throw InvalidInputError("sample_surface: the mesh has no faces");
  const Eigen::VectorXd A = face_areas(V, F);
  std::vector<double> cum(A.size());
  double total = 0;
  for (Eigen::Index f = 0; f < A.size(); ++f) cum[f] = (total += A[f]);
  if (!(total > 0)) throw InvalidInputError("sample_surface: the mesh has zero area");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::MatrixX3d P(count, 3);
  for (int i = 0; i < count; ++i) {
    const double r = uni(rng) * total;
    const int f = static_cast<int>(std::min<std::ptrdiff_t>(std::lower_bound(cum.begin(), cum.end(), r) - cum.begin(),
                                                            static_cast<std::ptrdiff_t>(cum.size()) - 1));
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    Eigen::Vector3d p = (1 - a - b) * V.row(F(f, 0)).transpose() + a * V.row(F(f, 1)).transpose() +
                        b * V.row(F(f, 2)).transpose();
    if (noise_sigma > 0) {
      const double g0 = gauss(rng), g1 = gauss(rng), g2 = gauss(rng);
      p += noise_sigma * Eigen::Vector3d(g0, g1, g2);
    }
    P.row(i) = p.transpose();
  }
  return P;
}

SurfaceDistance surface_distance(const Eigen::MatrixX3d& VA, const Eigen::MatrixX3i& FA, const Eigen::MatrixX3d& VB,
                                 const Eigen::MatrixX3i& FB, int samples, std::uint32_t seed) {
  if (samples < 1) throw InvalidInputError("surface_distance: samples must be >= 1");
  if (FA.rows() == 0 || FB.rows() == 0) throw InvalidInputError("surface_distance: empty mesh");
  SurfaceDistance d;
  auto one_side = [&](const Eigen::MatrixX3d& V1, const Eigen::MatrixX3i& F1, const Eigen::MatrixX3d& V2,
                      const Eigen::MatrixX3i& F2, std::uint32_t s, double& mean, double& mx) {
    const Eigen::MatrixX3d Q = sample_surface(V1, F1, samples, s);
    const std::vector<SurfacePoint> cp = closest_surface_points(V2, F2, Q);
    double sum = 0;
    mx = 0;
    for (int i = 0; i < samples; ++i) {
      const double e = (position(V2, F2, cp[i]) - Q.row(i).transpose()).norm();
      sum += e;
      mx = std::max(mx, e);
    }
    mean = sum / samples;
  };
  double h1 = 0, h2 = 0;
  one_side(VA, FA, VB, FB, seed, d.mean_a_to_b, h1);
  one_side(VB, FB, VA, FA, seed + 1, d.mean_b_to_a, h2);
  d.mean = 0.5 * (d.mean_a_to_b + d.mean_b_to_a);
  d.hausdorff = std::max(h1, h2);
  return d;
}

}  // namespace heatcvt
