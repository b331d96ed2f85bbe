// Surface projectors of the mesher: a point cloud's local quadratic fit and a triangle mesh.
#include "heatcvt/mesher/projector.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "heatcvt/closest_point.h"
#include "heatcvt/cvt/surface_graph.h"
#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/normals.h"

namespace heatcvt {

namespace {

// One thread's scratch space for project_at() and fit_and_project(), which the polish calls for
// every trial move on every core: kept between calls, so that a fit allocates nothing once it has
// seen its size.
struct FitWorkspace {
  std::vector<int> neighbourhood;
  std::vector<double> s, t, h, w;
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
};

FitWorkspace& fit_workspace() {
  thread_local FitWorkspace workspace;
  return workspace;
}

}  // namespace

CloudSurfaceProjector::CloudSurfaceProjector(Eigen::MatrixX3d P, Eigen::MatrixX3d N, const CloudFitOptions& options,
                                             Eigen::MatrixXi knn)
    : P_(std::move(P)), N_(std::move(N)), options_(options), knn_(std::move(knn)) {
  if (P_.rows() < 2 || N_.rows() != P_.rows())
    throw InvalidInputError("CloudSurfaceProjector: need at least 2 points with one normal each");
  if (options_.fit_neighbors < 1 || options_.walk_neighbors < 1)
    throw InvalidInputError("CloudSurfaceProjector: fit_neighbors and walk_neighbors must be >= 1");
  if (knn_.size() == 0)
    knn_ = k_nearest_neighbors(P_, std::min<int>(options_.fit_neighbors, static_cast<int>(P_.rows()) - 1), options_.threads);
}

void CloudSurfaceProjector::neighbourhood(int c, std::vector<int>& nb) const {
  nb.assign(1, c);
  const Eigen::Vector3d nc = N_.row(c);
  for (Eigen::Index q = 0; q < knn_.cols(); ++q)
    if (N_.row(knn_(c, q)).dot(nc) > 0) nb.push_back(knn_(c, q));
  if (static_cast<int>(nb.size()) < std::min(options_.min_oriented_points, static_cast<int>(knn_.cols()) / 2)) {
    nb.assign(1, c);
    for (Eigen::Index q = 0; q < knn_.cols(); ++q) nb.push_back(knn_(c, q));
  }
}

void CloudSurfaceProjector::fit_and_project(const std::vector<int>& nb, const Eigen::Vector3d& x,
                                            const Eigen::Vector3d& orient, Eigen::Vector3d& out_pos,
                                            Eigen::Vector3d& out_normal) const {
  const Eigen::MatrixX3d& P = P_;
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
  FitWorkspace& ws = fit_workspace();
  std::vector<double>& s = ws.s;
  std::vector<double>& t = ws.t;
  std::vector<double>& h = ws.h;
  std::vector<double>& w = ws.w;
  s.resize(m);
  t.resize(m);
  h.resize(m);
  w.resize(m);
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
  Eigen::MatrixXd& A = ws.A;
  Eigen::VectorXd& b = ws.b;
  A.resize(m, 6);
  b.resize(m);
  for (int q = 0; q < m; ++q) {
    const double a = s[q] - sx, c = t[q] - tx, sw = std::sqrt(w[q]);
    A.row(q) << sw, sw * a, sw * c, sw * a * a, sw * a * c, sw * c * c;
    b[q] = sw * h[q];
  }
  const double radius = std::sqrt(r2);
  double z = 0, gx = 0, gy = 0;
  bool ok = false;
  if (m >= options_.min_quadratic_points) {
    // Scale the columns so that the quadratic terms are O(1).
    Eigen::VectorXd scale(6);
    scale << 1, radius, radius, radius * radius, radius * radius, radius * radius;
    A = A * scale.cwiseInverse().asDiagonal();  // coefficient-wise: no aliasing
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr = ws.qr;
    qr.compute(A);
    qr.setThreshold(options_.rank_threshold);
    if (qr.rank() == 6) {
      const Eigen::VectorXd coef = scale.cwiseInverse().asDiagonal() * qr.solve(b);
      z = coef[0];
      gx = coef[1];
      gy = coef[2];
      ok = std::isfinite(z) && std::isfinite(gx) && std::isfinite(gy) &&
           std::abs(z - xl.dot(n)) < options_.max_height_bandwidths * radius;
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

void CloudSurfaceProjector::project_at(int c, const Eigen::Vector3d& x, const Eigen::Vector3d& orient,
                                       Eigen::Vector3d& position, Eigen::Vector3d& normal) const {
  std::vector<int>& nb = fit_workspace().neighbourhood;  // (fit_and_project() reads it only)
  neighbourhood(c, nb);
  fit_and_project(nb, x, orient, position, normal);
}

int CloudSurfaceProjector::walk(int start, const Eigen::Vector3d& x) const {
  const Eigen::Index cols = std::min<Eigen::Index>(knn_.cols(), options_.walk_neighbors);
  int cur = start;
  double best = (P_.row(cur).transpose() - x).squaredNorm();
  for (int step = 0; step < options_.max_walk_steps; ++step) {
    int nxt = cur;
    for (Eigen::Index q = 0; q < cols; ++q) {
      const double d = (P_.row(knn_(cur, q)).transpose() - x).squaredNorm();
      if (d < best) best = d, nxt = knn_(cur, q);
    }
    if (nxt == cur) break;
    cur = nxt;
  }
  return cur;
}

void CloudSurfaceProjector::project(const Eigen::Vector3d& x, int& hint, Eigen::Vector3d& position,
                                    Eigen::Vector3d& normal) const {
  const int c = walk(hint >= 0 && hint < P_.rows() ? hint : 0, x);
  project_at(c, x, N_.row(c).transpose(), position, normal);
  hint = c;
}

double CloudSurfaceProjector::distance_to_samples(const Eigen::Vector3d& x) const {
  std::call_once(samples_once_, [&] { samples_ = std::make_unique<PointIndex>(P_); });
  double d = 0;
  samples_->nearest(x, d);
  return d;
}

const PointIndex& CloudSurfaceProjector::border_index() const {
  std::call_once(border_once_, [&] {
    SampleBorderOptions o = options_.border;
    o.threads = options_.threads;
    const std::vector<char> on_border = sample_border_points(P_, N_, knn_, o);
    const std::vector<char> on_edge = border_chains(on_border, knn_, o.neighbors, options_.scan_edge_chain);
    std::vector<int> rows, edge_rows;
    for (int i = 0; i < static_cast<int>(on_border.size()); ++i) {
      if (on_border[i]) rows.push_back(i);
      if (on_edge[i]) edge_rows.push_back(i);
    }
    border_points_ = P_(rows, Eigen::all);
    border_ = std::make_unique<PointIndex>(border_points_);
    scan_edge_ = std::make_unique<PointIndex>(P_(edge_rows, Eigen::all));
  });
  return *border_;
}

double CloudSurfaceProjector::distance_to_scan_edge(const Eigen::Vector3d& x) const {
  border_index();
  double d = 0;
  scan_edge_->nearest(x, d);
  return d;
}

const Eigen::MatrixX3d& CloudSurfaceProjector::sample_border() const {
  border_index();
  return border_points_;
}

double CloudSurfaceProjector::distance_to_sample_border(const Eigen::Vector3d& x) const {
  double d = 0;
  border_index().nearest(x, d);
  return d;
}

bool CloudSurfaceProjector::sample_border_mean(const Eigen::Vector3d& x, double radius, Eigen::Vector3d& mean) const {
  const std::vector<int> rows = border_index().within(x, radius);
  if (rows.empty()) return false;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int r : rows) sum += border_points_.row(r).transpose();
  mean = sum / static_cast<double>(rows.size());
  return true;
}

MeshSurfaceProjector::MeshSurfaceProjector(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F)
    : V_(V), F_(F), tree_(std::make_unique<ClosestPointTree>(V, F)) {
  VN_ = vertex_normals(V, F);
  vfaces_ = vertex_faces(static_cast<int>(V.rows()), F);
  border_ = boundary_edges(F);
}

bool MeshSurfaceProjector::project_to_border(const Eigen::Vector3d& x, Eigen::Vector3d& position,
                                             Eigen::Vector3d& normal) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [a, b] : border_) {
    const Eigen::Vector3d p = V_.row(a), q = V_.row(b), e = q - p;
    const double len2 = e.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - p).dot(e) / len2, 0.0, 1.0) : 0.0;
    const Eigen::Vector3d c = p + t * e;
    const double d = (c - x).squaredNorm();
    if (!(d < best)) continue;
    best = d;
    position = c;
    const Eigen::Vector3d n = (1 - t) * VN_.row(a).transpose() + t * VN_.row(b).transpose();
    normal = n.norm() > 0 ? n.normalized() : Eigen::Vector3d(VN_.row(a).transpose());
  }
  return std::isfinite(best);
}

MeshSurfaceProjector::~MeshSurfaceProjector() = default;

Eigen::Vector3d MeshSurfaceProjector::face_normal(int f) const {
  const Eigen::Vector3d a = V_.row(F_(f, 0)), b = V_.row(F_(f, 1)), c = V_.row(F_(f, 2));
  return (b - a).cross(c - a);
}

void MeshSurfaceProjector::project(const Eigen::Vector3d& x, int& hint, Eigen::Vector3d& position,
                                   Eigen::Vector3d& normal) const {
  SurfacePoint sp = tree_->closest(x);
  // The other side of a thin part: stay on the hint's sheet.
  if (hint >= 0 && hint < F_.rows() && sp.face != hint && face_normal(sp.face).dot(face_normal(hint)) < 0) {
    SurfacePoint start;
    start.face = hint;
    start.bary = Eigen::Vector3d::Constant(1.0 / 3.0);
    sp = project_local(V_, F_, vfaces_, start, x);
  }
  position = heatcvt::position(V_, F_, sp);
  Eigen::Vector3d nrm = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) nrm += sp.bary[k] * VN_.row(F_(sp.face, k)).transpose();
  if (!(nrm.norm() > 0)) {  // opposite vertex normals cancel: the face's own normal
    const Eigen::Vector3d a = V_.row(F_(sp.face, 0)), b = V_.row(F_(sp.face, 1)), c = V_.row(F_(sp.face, 2));
    nrm = (b - a).cross(c - a);
  }
  normal = nrm.normalized();
  hint = sp.face;
}

double MeshSurfaceProjector::distance_to_samples(const Eigen::Vector3d& x) const {
  const SurfacePoint sp = tree_->closest(x);
  return (heatcvt::position(V_, F_, sp) - x).norm();
}

}  // namespace heatcvt
