// Surface reconstruction from point clouds: a short driver over the cloud preparation (clean-up,
// normals, fitted surface, point Laplacian), the heat CVT and the surface mesher's stages
// (mesher/surface_mesher.h) with the cloud's fitted surface as projector.
#include "heatcvt/reconstruct.h"

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Dense>
#include <algorithm>
#include <optional>
#include <chrono>
#include <functional>
#include <cstdlib>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "heatcvt/closest_point.h"
#include "heatcvt/cloud_io.h"
#include "heatcvt/cvt.h"
#include "heatcvt/cvt/anisotropic_lift.h"
#include "heatcvt/errors.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"
#include "heatcvt/point_laplacian.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/surface_mesher.h"

namespace heatcvt {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void check_options(const ReconstructionOptions& o) {
  auto bad = [](const std::string& m) { throw InvalidInputError("reconstruct_surface: " + m); };
  if (o.sites < 4) bad("sites = " + std::to_string(o.sites) + " (need at least 4)");
  if (o.iterations < 0) bad("iterations = " + std::to_string(o.iterations) + " (must be >= 0)");
  if (o.count_retries < 0) bad("count_retries = " + std::to_string(o.count_retries) + " (must be >= 0)");
  if (!(o.finer_retry_factor >= 1) || !std::isfinite(o.finer_retry_factor)) bad("finer_retry_factor must be >= 1");
  if (!(o.retry_count_error >= 0) || !std::isfinite(o.retry_count_error)) bad("retry_count_error must be >= 0");
  if (!(o.lloyd_mean_tolerance >= 0) || !std::isfinite(o.lloyd_mean_tolerance)) bad("lloyd_mean_tolerance must be >= 0");
  if (o.neighbors < o.min_neighbors || o.neighbors > o.max_neighbors)
    bad("neighbors = " + std::to_string(o.neighbors) + " (must be in [" + std::to_string(o.min_neighbors) + ", " +
        std::to_string(o.max_neighbors) + "])");
  if (!(o.anisotropy >= 0) || !std::isfinite(o.anisotropy)) bad("anisotropy must be a finite number >= 0");
  if (!(o.adaptive.adaptivity >= 0 && o.adaptive.adaptivity <= 2)) bad("adaptive.adaptivity must be in [0, 2]");
  if (!(o.adaptive.max_size_ratio >= 1) || !std::isfinite(o.adaptive.max_size_ratio))
    bad("adaptive.max_size_ratio must be a finite number >= 1");
  if (!(o.voxel_size >= 0) || !std::isfinite(o.voxel_size)) bad("voxel_size must be a finite number >= 0");
  if (!(o.coverage.grow_gap >= 0) || !std::isfinite(o.coverage.grow_gap)) bad("coverage.grow_gap must be a finite number >= 0");
  if (!(o.coverage.max_grown_fraction >= 0 && o.coverage.max_grown_fraction <= 1))
    bad("coverage.max_grown_fraction must be in [0, 1]");
  if (o.coverage.grow_rounds < 0) bad("coverage.grow_rounds must be >= 0");
  if (!(o.coverage.max_uncovered_fraction >= 0 && o.coverage.max_uncovered_fraction <= 1))
    bad("coverage.max_uncovered_fraction must be in [0, 1]");
  if (!(o.coverage.grow_step > 0) || !std::isfinite(o.coverage.grow_step)) bad("coverage.grow_step must be a finite number > 0");
  if (!(o.time_coefficient > 0) || !std::isfinite(o.time_coefficient)) bad("time_coefficient must be > 0");
  if (o.threads < 0) bad("threads must be >= 0");
  if (o.max_hole_edges < 0) bad("max_hole_edges must be >= 0");
  if (o.relaxation_iterations < 0) bad("relaxation_iterations must be >= 0");
  if (!(o.lloyd_relaxation >= 1 && o.lloyd_relaxation < 2)) bad("lloyd_relaxation must be in [1, 2)");
  if (!(o.lloyd_tolerance >= 0) || !std::isfinite(o.lloyd_tolerance)) bad("lloyd_tolerance must be a finite number >= 0");
  if (!(o.tips_max_mean_angle_loss_deg >= 0) || !std::isfinite(o.tips_max_mean_angle_loss_deg))
    bad("tips_max_mean_angle_loss_deg must be a finite number >= 0");
  if (o.surface_lloyd_iterations < 0) bad("surface_lloyd_iterations must be >= 0");
  if (!(o.cvt_points_per_site == 0 || o.cvt_points_per_site >= 3) || !std::isfinite(o.cvt_points_per_site))
    bad("cvt_points_per_site must be 0 (every point) or at least 3");
  if (o.denoise && o.denoise_neighbors < 2) bad("denoise_neighbors must be >= 2");
  check_stray_point_options(o.stray);
  check_dense_piece_options(o.dense_pieces);
  check_cloud_coverage_options(o.cloud_coverage);
  if (o.denoise && (!(o.denoise_stddev > 0) || !std::isfinite(o.denoise_stddev))) bad("denoise_stddev must be > 0");
  const CloudPreparationOptions& c = o.cloud;
  if (c.orientation_neighbors < 1 || c.max_fit_neighbors < 1 || c.smoothing_spacing_neighbors < 1)
    bad("cloud.orientation_neighbors, max_fit_neighbors and smoothing_spacing_neighbors must be >= 1");
  if (!(c.fit_cells > 0) || !std::isfinite(c.fit_cells)) bad("cloud.fit_cells must be a finite number > 0");
  if (!(c.orientation_offset_penalty >= 0) || !std::isfinite(c.orientation_offset_penalty))
    bad("cloud.orientation_offset_penalty must be a finite number >= 0");
  if (!(c.max_crossing_fraction >= 0 && c.max_crossing_fraction <= 1)) bad("cloud.max_crossing_fraction must be in [0, 1]");
  if (!(c.across_min_offset >= 0 && c.across_min_offset <= 1)) bad("cloud.across_min_offset must be in [0, 1]");
  if (!(c.min_thin_pair_share >= 0 && c.min_thin_pair_share <= 1)) bad("cloud.min_thin_pair_share must be in [0, 1]");
  if (!(c.max_subset_fraction > 0 && c.max_subset_fraction <= 1)) bad("cloud.max_subset_fraction must be in (0, 1]");
  if (c.graph_lloyd_iterations < 0) bad("cloud.graph_lloyd_iterations must be >= 0");
  if (!(c.surface_lloyd_relaxation >= 1 && c.surface_lloyd_relaxation < 2)) bad("cloud.surface_lloyd_relaxation must be in [1, 2)");
  if (o.fit.min_oriented_points < 1 || o.fit.min_quadratic_points < 6 || o.fit.max_walk_steps < 0)
    bad("fit.min_oriented_points must be >= 1, fit.min_quadratic_points >= 6 (six coefficients), fit.max_walk_steps >= 0");
  if (o.mesher.min_piece_faces < 0) bad("mesher.min_piece_faces must be >= 0");
  if (!(o.mesher.min_piece_vertex_fraction >= 0 && o.mesher.min_piece_vertex_fraction < 1))
    bad("mesher.min_piece_vertex_fraction must be in [0, 1)");
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


// The cloud after clean-up: its points in the bounding-box frame and what the clean-up did.
struct PreparedCloud {
  Eigen::MatrixX3d P;
  CloudFrame frame;
};

// The rows of P whose mask entry equals `keep`.
Eigen::MatrixX3d rows_where(const Eigen::MatrixX3d& P, const std::vector<char>& mask, char keep) {
  Eigen::MatrixX3d Q(std::count(mask.begin(), mask.end(), keep), 3);
  Eigen::Index r = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    if (mask[i] == keep) Q.row(r++) = P.row(i);
  return Q;
}

// Exact duplicates merged, stray points removed, frame normalised, optional statistical outlier
// removal and voxel grid.
PreparedCloud prepare_cloud(const Eigen::MatrixX3d& P_in, const ReconstructionOptions& options, ReconstructionResult& res) {
  PointCloud cloud;
  cloud.P = P_in;
  CloudReadReport clean_report;
  clean_cloud(cloud, &clean_report);
  res.points_merged = static_cast<int>(clean_report.duplicates_merged);
  if (options.stray.enabled()) {  // before the frame, which they would stretch
    StrayPointOptions stray_options = options.stray;
    if (stray_options.min_group_points > 0)  // a smaller group's neighbourhoods would bridge the gap
      stray_options.min_group_points = std::max(stray_options.min_group_points, options.neighbors);
    const std::vector<char> stray = stray_point_mask(cloud.P, stray_options, options.threads);
    res.points_stray = static_cast<int>(std::count(stray.begin(), stray.end(), 1));
    if (res.points_stray > 0) cloud.P = rows_where(cloud.P, stray, 0);
  }
  PreparedCloud out;
  out.frame = normalize_cloud(cloud);
  Eigen::MatrixX3d P = cloud.P;
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
    const float leaf = static_cast<float>(options.voxel_size / out.frame.scale);
    vg.setLeafSize(leaf, leaf, leaf);
    pcl::PointCloud<pcl::PointXYZ> voxels;
    vg.filter(voxels);
    Eigen::MatrixX3d Q(voxels.size(), 3);
    for (size_t i = 0; i < voxels.size(); ++i) Q.row(i) << voxels[i].x, voxels[i].y, voxels[i].z;
    res.points_voxel_removed = static_cast<int>(P.rows() - Q.rows());
    P = Q;
    if (P.rows() > 0) {  // voxel centroids may coincide in float: merge again
      PointCloud c2;
      c2.P = P;
      clean_cloud(c2);
      P = c2.P;
    }
  }
  out.P = std::move(P);
  return out;
}

// The coverage repair of the tips of closed pieces (ReconstructionOptions::coverage) on the
// mesher's result `mesh` against the CVT points `samples`; undone where it makes faces cross,
// lowers φm by more than `max_loss_deg`, or below `mean_angle_deg` (at all, where it was below):
// noise wider than half a spacing leaves points off the mesh everywhere, not at tips, and chasing
// them costs the shape. Returns whether vertices moved.
bool cover_tips(WorkingMesh& mesh, const SurfaceProjector& fit, const Eigen::MatrixX3d& samples,
                const CoverageRepairOptions& options, double mean_angle_deg, double max_loss_deg,
                CoverageRepairStats& stats) {
  stats = {};
  if (options.rounds <= 0 || mesh.empty()) return false;
  // Vertices of open pieces stay (with the border vertices repair_coverage() locks itself).
  const FaceComponents pieces = face_components(mesh, true);
  const std::vector<char> open = open_pieces(mesh, pieces);
  std::vector<char> fixed(mesh.num_vertices(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (open[pieces.of_face[f]])
      for (int v : mesh.face(f)) fixed[v] = 1;
  if (std::all_of(open.begin(), open.end(), [](char o) { return o != 0; })) return false;
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const double phi_m = mean_min_angle(mesh);
  const double floor = std::max(phi_m - max_loss_deg * M_PI / 180, std::min(phi_m, mean_angle_deg * M_PI / 180));
  stats = repair_coverage(mesh, fit, samples, mean_edge_length(mesh), options, &fixed);
  // Only the faces around moved vertices can cross anything new.
  if (stats.moves > 0 && (mean_min_angle(mesh) < floor || !crossing_face_pairs_after(mesh, before, {}).empty())) {
    mesh.rollback(before);
    stats.moves = 0;
    stats.inserted = 0;
    stats.uncovered_after = stats.uncovered_before;
    stats.gap_after = stats.gap_before;
  }
  return stats.moves > 0;
}

// The CVT's points: every point, or a spatially uniform subset (cvt_points_per_site).
struct CvtPoints {
  std::vector<int> sub;          // CVT point -> cloud point
  std::vector<int> voxel_point;  // cloud point -> the CVT point of its voxel (when subsampled)
  bool subsampled = false;
  Eigen::MatrixX3d PC;           // positions of the CVT points
  Eigen::MatrixXi knn;           // their `neighbors` nearest CVT points
  Eigen::MatrixX3d NC;           // their oriented normals
};

CvtPoints choose_cvt_points(const Eigen::MatrixX3d& P, const ReconstructionOptions& options) {
  const int n = static_cast<int>(P.rows());
  CvtPoints c;
  if (options.cvt_points_per_site > 0) {
    const long target = std::lround(options.cvt_points_per_site * options.sites);
    if (target < options.cloud.max_subset_fraction * n) c.sub = voxel_subsample(P, target, c.voxel_point);
    if (static_cast<int>(c.sub.size()) < std::max(options.sites, options.neighbors + 1)) c.sub.clear();
  }
  c.subsampled = !c.sub.empty();
  if (!c.subsampled) {
    c.sub.resize(n);
    std::iota(c.sub.begin(), c.sub.end(), 0);
  }
  c.PC.resize(static_cast<Eigen::Index>(c.sub.size()), 3);
  for (size_t i = 0; i < c.sub.size(); ++i) c.PC.row(i) = P.row(c.sub[i]);
  return c;
}

// Oriented normals of every cloud point: the CVT point's own, else that of the nearest CVT point
// among its fit neighbours (on the same side of a thin part as the point), else that of the CVT
// point of its voxel.
Eigen::MatrixX3d cloud_normals(const CvtPoints& c, const Eigen::MatrixXi& knn_fit, int n) {
  if (!c.subsampled) return c.NC;
  std::vector<int> cvt_index(n, -1);
  for (size_t i = 0; i < c.sub.size(); ++i) cvt_index[c.sub[i]] = static_cast<int>(i);
  Eigen::MatrixX3d N(n, 3);
  for (int i = 0; i < n; ++i) {
    int k = cvt_index[i];
    for (Eigen::Index q = 0; q < knn_fit.cols() && k < 0; ++q) k = cvt_index[knn_fit(i, q)];
    N.row(i) = c.NC.row(k >= 0 ? k : c.voxel_point[i]);
  }
  return N;
}

// The CVT points onto the fitted surface (each one projected onto the quadratic fitted to its
// neighbourhood of the whole cloud): on a noisy scan the Laplacian is then built on points as
// regular as a clean scan's, whose factor has less fill and whose cells are smoother. A point
// whose projection lies farther than its mean distance to its nearest CVT points stays put: there
// the fit is not to be trusted (tips of thin parts).
void smooth_cvt_points(CvtPoints& c, const CloudSurfaceProjector& fit, const ReconstructionOptions& options) {
  const Eigen::MatrixX3d raw = c.PC;
  const int nc = static_cast<int>(raw.rows());
#pragma omp parallel for num_threads(resolve_threads(options.threads)) schedule(static)
  for (int i = 0; i < nc; ++i) {
    Eigen::Vector3d pos, nrm;
    fit.project_at(c.sub[i], raw.row(i).transpose(), c.NC.row(i).transpose(), pos, nrm);
    double spacing = 0;
    const int near = std::min<int>(options.cloud.smoothing_spacing_neighbors, static_cast<int>(c.knn.cols()));
    for (int q = 0; q < near; ++q) spacing += (raw.row(c.knn(i, q)) - raw.row(i)).norm() / near;
    if (pos.allFinite() && (pos - raw.row(i).transpose()).norm() <= spacing) c.PC.row(i) = pos.transpose();
  }
}

// The cloud's fit: about cloud.fit_cells cells' worth of points, at least `k_cloud` (the
// neighbourhood size, `neighbors` or more where the sampling is in rows: neighbour_spread.h) and
// at most cloud.max_fit_neighbors (or `k_cloud` where it is more); the projector's walk and, where
// the neighbourhoods grew, its border test look at `k_cloud` of them.
CloudFitOptions cloud_fit_options(const ReconstructionOptions& options, int n, int k_cloud) {
  CloudFitOptions fopt = options.fit;
  const bool grown = k_cloud > options.neighbors;
  const int cap = grown ? std::max(options.cloud.max_fit_neighbors, k_cloud) : options.cloud.max_fit_neighbors;
  const int cells = static_cast<int>(std::lround(options.cloud.fit_cells * n / options.sites));
  fopt.fit_neighbors = std::min(std::max(k_cloud, cells), std::min(cap, n - 1));
  fopt.walk_neighbors = grown ? std::min(k_cloud, fopt.fit_neighbors) : options.neighbors;
  if (grown) fopt.border.neighbors = std::max(fopt.border.neighbors, fopt.walk_neighbors);
  fopt.threads = options.threads;
  return fopt;
}

// The CVT points' neighbourhoods and normals: sizes that span the surface (neighbour_spread.h:
// `neighbors`, more where the sampling is in rows), the kNN table, PCA normals oriented along an
// MST (edges leaving the tangent plane are propagated through last, so the two sides of a thin
// part get opposite normals; its k scaled like the neighbourhoods). Returns the cloud fit's
// options; the sizes used go to res.neighbors_cvt / neighbors_fit.
CloudFitOptions orient_cvt_points(CvtPoints& cp, const Eigen::MatrixX3d& P, const ReconstructionOptions& options,
                                  ReconstructionResult& res) {
  const int k_cvt = neighbours_for_spread(cp.PC, options.neighbors, options.cloud.spread, options.threads);
  const int k_cloud =
      cp.subsampled ? neighbours_for_spread(P, options.neighbors, options.cloud.spread, options.threads) : k_cvt;
  cp.knn = k_nearest_neighbors(cp.PC, k_cvt, options.threads);
  cp.NC = estimate_normals(cp.PC, cp.knn, options.threads);
  orient_normals_mst(cp.PC, cp.NC, std::min(k_cvt, options.cloud.orientation_neighbors * k_cvt / options.neighbors),
                     options.threads, options.cloud.orientation_offset_penalty);
  const CloudFitOptions fopt = cloud_fit_options(options, static_cast<int>(P.rows()), k_cloud);
  res.neighbors_cvt = k_cvt;
  res.neighbors_fit = fopt.fit_neighbors;
  return fopt;
}

// Point Laplacian of the CVT points. Where a few points (thin parts) have a neighbour of opposite
// normal, such neighbours are left out of each local triangulation, so that heat (hence a cell)
// does not cross to the other side. Where many do, the orientation is unreliable (clutter, noise)
// unless nearly all of those pairs lie across a thin part (antiparallel normals, off each other's
// tangent plane: a plate or a wall about a neighbourhood thick, two scans of a plane offset by a
// registration error); then those pairs are cut, otherwise none.
PointLaplacian cvt_point_laplacian(const CvtPoints& c, const ReconstructionOptions& options) {
  const int nc = static_cast<int>(c.PC.rows());
  const PointLaplacianOptions defaults;
  const double offset = options.cloud.across_min_offset;
  long crossing_points = 0, crossing_pairs = 0, thin_pairs = 0;
  for (int i = 0; i < nc; ++i) {
    bool crossing = false;
    for (Eigen::Index q = 0; q < c.knn.cols(); ++q) {
      const int j = c.knn(i, q);
      if (c.NC.row(i).dot(c.NC.row(j)) >= 0) continue;
      crossing = true;
      ++crossing_pairs;
      thin_pairs += offset > 0 && across_thin_part(c.PC.row(i), c.NC.row(i), c.PC.row(j), c.NC.row(j), offset,
                                                   defaults.across_max_dot);
    }
    crossing_points += crossing;
  }
  PointLaplacianOptions lopt;
  lopt.k = static_cast<int>(c.knn.cols());
  lopt.threads = options.threads;
  lopt.neighbors = &c.knn;
  if (crossing_points > 0 && crossing_points <= options.cloud.max_crossing_fraction * nc) {
    lopt.oriented_normals = &c.NC;
  } else if (crossing_points > 0 && offset > 0 &&
             thin_pairs >= options.cloud.min_thin_pair_share * static_cast<double>(crossing_pairs)) {
    lopt.oriented_normals = &c.NC;
    lopt.across_min_offset = offset;
  }
  return point_laplacian(c.PC, lopt);
}

// The sites on the fitted surface (positions, fitted normals) as the vertices of the working
// mesh, each anchored at the cloud point of its site's nearest point-triangle corner.
WorkingMesh sites_on_surface(const CvtResult& cvt, const Eigen::MatrixX3i& T, const CvtPoints& c,
                             const CloudSurfaceProjector& fit, int threads) {
  const int ns = cvt.diagram.num_cells();
  Eigen::MatrixX3d S(ns, 3), SN(ns, 3);
  std::vector<int> anchor(ns);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (int s = 0; s < ns; ++s) {
    const SurfacePoint& sp = cvt.sites[s];
    int corner = 0;
    sp.bary.maxCoeff(&corner);
    const int cp = c.sub[T(sp.face, corner)];
    Eigen::Vector3d orient = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) orient += sp.bary[k] * c.NC.row(T(sp.face, k)).transpose();
    if (orient.norm() == 0) orient = fit.normals().row(cp).transpose();
    Eigen::Vector3d pos, nrm;
    fit.project_at(cp, cvt.positions.row(s).transpose(), orient, pos, nrm);
    S.row(s) = pos.transpose();
    SN.row(s) = nrm.transpose();
    anchor[s] = cp;
  }
  return WorkingMesh(std::move(S), std::move(SN), std::move(anchor));
}

// Times consecutive stages into ReconstructionResult::stage_seconds.
struct StageClock {
  ReconstructionResult& res;
  Clock::time_point t = Clock::now();
  void done(const char* name) {
    res.stage_seconds.emplace_back(name, since(t));
    t = Clock::now();
  }
};

void copy_stats(const MesherStats& st, ReconstructionResult& res) {
  res.candidate_triangles = st.candidate_triangles;
  res.rejected_triangles = st.rejected_triangles;
  res.removed_triangles = st.removed_triangles;
  res.holes_filled = st.holes_filled;
  res.star_triangles = st.star_triangles;
  res.trimmed_faces = st.trimmed_faces;
  res.pieces_removed = st.pieces_removed;
  res.filled_hole_edges = st.filled_hole_edges;
  res.flipped_edges = st.flipped_edges;
  res.polish_fallback = st.polish_fallback;
  res.angle_polish_undone = st.angle_polish_undone;
  res.collapsed_edges = st.collapsed_edges;
  res.split_edges = st.split_edges;
  res.faces_turned_outward = st.faces_turned_outward;
  res.sized = st.sized;
  res.crossing_after_sizing = st.crossing_after_sizing;
  res.flying_faces = st.flying_faces;
  res.unused_sites = st.unused_vertices;
  res.stage_seconds.insert(res.stage_seconds.end(), st.stage_seconds.begin(), st.stage_seconds.end());
}

// What one run of the CVT and the mesher reads: the CVT points, their triangles and Laplacian
// (metric_area: the lifted metric's face areas, empty when isotropic), the adaptive sizing of the
// CVT points (null when uniform), the fitted surface, the cloud's frame and the points used.
struct MeshingInputs {
  const CvtPoints& cp;
  const Eigen::MatrixX3i& T;
  const Laplacian& lap;
  const Eigen::VectorXd& metric_area;
  const SurfaceSizing* sizing;
  const Eigen::VectorXd& density;  // the sizing's density at the CVT points (empty when uniform)
  const CloudSurfaceProjector& fit;
  const CloudFrame& frame;
  const Eigen::MatrixX3d& P;  // the points used, in the cloud's frame
};

using StageReport = std::function<void(const std::string&, double)>;

// The vertex count asked for: the sizing's target where one is set (the streamed path runs the
// CVT on fewer sites where the noise is wide and sizes the mesh to the count), else `sites`.
int requested_vertices(const ReconstructionOptions& options) {
  return options.mesher.sizing.target_vertices > 0 ? options.mesher.sizing.target_vertices : options.sites;
}

// The coverage of the points used by `mesh` (in the input's frame), its thickness at the site
// spacing asked for: sqrt(area / vertices asked for) on the CVT points' triangles.
CloudCoverage measure_coverage(const MeshingInputs& in, const ReconstructionOptions& options, const TriangleMesh& mesh) {
  Eigen::MatrixX3d P = in.P;
  restore_frame(P, in.frame);
  CloudCoverageOptions coverage_options = options.cloud_coverage;
  coverage_options.threads = options.threads;
  const double site_spacing = std::sqrt(surface_area(in.cp.PC, in.T) / requested_vertices(options)) * in.frame.scale;
  return cloud_coverage(mesh, P, site_spacing, coverage_options);
}

// Steps 3-5 with the start sites of options.seed: the heat CVT on the CVT points, its dual
// meshed on the fitted surface (surface_mesher.h), the tips, the border fit, quality and CGAL
// validation, into `res`.
void cvt_and_mesh(const MeshingInputs& in, const ReconstructionOptions& options, const StageReport& report,
                  ReconstructionResult& res) {
  StageClock stage{res};
  // 3. Heat CVT on the CVT points.
  const auto t1 = Clock::now();
  report("cvt", 0);
  const CvtResult cvt = centroidal_voronoi(
      in.cp.PC, in.T, in.lap, reconstruction_cvt_options(options), {},
      [&](const CvtIterationStats& st) {
        report("cvt", options.iterations > 0 ? static_cast<double>(st.iteration) / options.iterations : 1.0);
        return true;
      },
      in.metric_area, in.density);
  res.cvt_seconds = since(t1);
  res.factor_seconds = cvt.factor_seconds;
  res.iterations = static_cast<int>(cvt.iterations.size());
  double iteration_sum = 0;
  const double site_spacing = std::sqrt(surface_area(in.cp.PC, in.T) / options.sites);
  for (const auto& st : cvt.iterations) {
    res.iteration_seconds.push_back(st.seconds);
    res.iteration_moves.push_back(st.mean_move / site_spacing);
    iteration_sum += st.seconds;
  }
  // The CVT's own parts: start (factorisation overlapped with the start sites' Lloyd), the
  // quality evaluations of the start sites, the heat Lloyd iterations, and the rest (the final
  // exact diagram and its dual).
  const double cvt_rest = since(stage.t) - cvt.setup_seconds - cvt.start_quality_seconds - iteration_sum;
  res.stage_seconds.emplace_back("cvt start", cvt.setup_seconds);
  res.stage_seconds.emplace_back("cvt start quality", cvt.start_quality_seconds);
  res.stage_seconds.emplace_back("cvt iterations", iteration_sum);
  res.stage_seconds.emplace_back("cvt final diagram", std::max(0.0, cvt_rest));
  stage.t = Clock::now();
  report("mesh", 0);

  // 4. Sites on the fitted surface; dual candidates witnessed by the point triangles and the
  // Voronoi vertices; then the surface mesher's stages with the fit as projector.
  WorkingMesh mesh = sites_on_surface(cvt, in.T, in.cp, in.fit, options.threads);
  DualCandidateOptions candidate_options = options.mesher.candidates;
  candidate_options.threads = options.threads;
  const DualCandidates candidates = dual_candidates(in.T, cell_labels(cvt.diagram, static_cast<int>(in.cp.sub.size())),
                                                    cvt.diagram, mesh, candidate_options);
  stage.done("sites and candidates");
  SurfaceMesherOptions mopt = options.mesher;
  mopt.holes.max_hole_edges = options.max_hole_edges;
  mopt.polish.relaxation_iterations = options.relaxation_iterations;
  mopt.threads = options.threads;
  // The long-edge splits may add vertices up to the vertex count asked for, plus the 2 % the
  // count is allowed to be off by.
  if (mopt.split.max_vertices == 0) mopt.split.max_vertices = options.sites + options.sites / 50;
  // Every piece kept gets its share of the vertex count: sized to -n where the dual fell short.
  if (mopt.sizing.target_vertices == 0) mopt.sizing.target_vertices = options.sites;
  if (in.sizing) mopt.sizing.relative_size = in.sizing->field;
  MesherStats stats;
  mesh_from_candidates(mesh, candidates, in.fit, mopt, stats);
  report("mesh", 0.5);
  stage.t = Clock::now();
  if (mesh.empty())
    throw Error("reconstruct_surface: no triangle could be extracted from the Voronoi diagram of " +
                std::to_string(mesh.num_vertices()) + " sites on " + std::to_string(in.P.rows()) + " points");
  res.mesh = finish_mesh(mesh, in.fit, mopt, stats);
  copy_stats(stats, res);
  stage.t = Clock::now();
  if (cover_tips(mesh, in.fit, in.cp.PC, options.coverage, mopt.sizing.mean_angle_deg,
                 options.tips_max_mean_angle_loss_deg, res.coverage))
    res.mesh = compact_mesh(mesh);
  stage.done("tips");
  // Only an open mesh has a border to fit (a closed one leaves the cloud's border unsearched).
  if (!boundary_edges(res.mesh.F).empty())
    res.border = border_fit(in.fit.sample_border(), res.mesh, mean_edge_length(res.mesh.V, res.mesh.F));
  stage.done("border fit");
  restore_frame(res.mesh.V, in.frame);
  const TriangleQuality tq = triangle_quality(res.mesh.V, res.mesh.F);
  res.min_angle_deg = tq.min_angle_deg;
  res.mean_min_angle_deg = tq.mean_min_angle_deg;
  res.boundary_min_angle_deg = tq.boundary_min_angle_deg;
  stage.done("quality");

  // 5. Validation (open scans legitimately keep boundaries).
  report("validate", 0);
  ValidationOptions vopt;
  vopt.require_closed = false;
  res.validation = validate_triangle_mesh(res.mesh.V, res.mesh.F, vopt);
  stage.done("validate");
  report("validate", 1);
  res.cloud_coverage = measure_coverage(in, options, res.mesh);
  stage.done("cloud coverage");
}

// How far the mesh is off the vertex count asked for, as a fraction of it.
double count_error(const ReconstructionResult& r, const ReconstructionOptions& options) {
  const double asked = requested_vertices(options);
  return std::abs(static_cast<double>(r.mesh.V.rows()) - asked) / asked;
}

// count_error() beyond the count's tolerance (0 within it).
double excess_count_error(const ReconstructionResult& r, const ReconstructionOptions& options) {
  return std::max(0.0, count_error(r, options) - options.mesher.sizing.count_tolerance);
}

// Whether the result covers the cloud only in part where start sites elsewhere may cover it
// whole: not where the points fill a volume (no surface to reach) nor where the largest group
// left out is smaller than a spacing (no site of the count falls there).
bool partial_other_starts_may_mend(const ReconstructionResult& r) {
  const CloudCoverage& c = r.cloud_coverage;
  return c.partial() && !c.volumetric() && c.largest_group_spacings >= 1;
}

// The fewest CVT points per site of the run on finer sites (finer_options()): the point
// Laplacian resolves a cell from about 10 (ReconstructionOptions::cvt_points_per_site), and at 5
// the dual of a tube about 3 site spacings round at twice the count already breaks.
constexpr double kFinerRetryMinPointsPerSite = 10;

// Whether `a` is a better result than `b`: it passes every check where `b` does not, then it
// covers the cloud whole where `b` does not, then it is nearer the count, then its φmin is larger.
bool better_result(const ReconstructionResult& a, const ReconstructionResult& b, const ReconstructionOptions& options) {
  if (a.validation.ok() != b.validation.ok()) return a.validation.ok();
  if (a.cloud_coverage.partial() != b.cloud_coverage.partial()) return !a.cloud_coverage.partial();
  const double ea = excess_count_error(a, options), eb = excess_count_error(b, options);
  if (ea != eb) return ea < eb;
  return a.min_angle_deg > b.min_angle_deg;
}

// cvt_and_mesh() with options.seed; where the mesh is more than retry_count_error off the count
// or covers the cloud only in part (partial_other_starts_may_mend()), again with the next seeds
// (at most count_retries times), keeping the best result (better_result()). A coarse dual that
// crosses itself can lose most of its faces to the untangling, the dual of a sparse part of an
// unevenly dense scan can lose its sites, and start sites a little elsewhere give another dual.
// A retry that fails (nothing extracted from its start sites) is passed over. The stage times of
// every run are kept, those of a retry prefixed with its seed.
ReconstructionResult mesh_with_retries(const MeshingInputs& in, const ReconstructionOptions& options,
                                       const StageReport& report, ReconstructionResult start) {
  ReconstructionResult best = start;
  best.seed_used = options.seed;
  cvt_and_mesh(in, options, report, best);
  std::vector<std::pair<std::string, double>> seconds = best.stage_seconds;
  int retries = 0;
  for (int retry = 1; retry <= options.count_retries; ++retry) {
    if (count_error(best, options) <= options.retry_count_error && !partial_other_starts_may_mend(best)) break;
    retries = retry;
    ReconstructionOptions again = options;
    again.seed = options.seed + static_cast<std::uint32_t>(retry);
    ReconstructionResult r = start;
    r.stage_seconds.clear();
    // One stage of its own in the progress: the first run's stages are done.
    const std::string stage = "retry with seed " + std::to_string(again.seed);
    report(stage, 0);
    bool extracted = true;
    try {
      cvt_and_mesh(in, again, [](const std::string&, double) {}, r);
    } catch (const Error&) {  // nothing extracted from these start sites: the result so far stays
      extracted = false;
    }
    report(stage, 1);
    if (!extracted) continue;
    for (const auto& [name, t] : r.stage_seconds) seconds.emplace_back("seed " + std::to_string(again.seed) + ": " + name, t);
    r.seed_used = again.seed;
    if (better_result(r, best, options)) best = std::move(r);
  }
  best.count_retries = retries;
  best.stage_seconds = std::move(seconds);
  return best;
}

}  // namespace

CvtOptions reconstruction_cvt_options(const ReconstructionOptions& options) {
  CvtOptions copt;
  copt.sites = options.sites;
  copt.iterations = options.iterations;
  copt.seed = options.seed;
  copt.threads = options.threads;
  copt.time_coefficient = options.time_coefficient;
  copt.build_dual = false;
  copt.spatial_site_order = options.spatial_site_order;
  if (options.farthest_point_start) {
    copt.initialization = CvtInitialization::farthest_point;
    copt.graph_lloyd_iterations = options.cloud.graph_lloyd_iterations;
  }
  copt.relaxation = options.lloyd_relaxation;
  copt.tolerance = options.lloyd_tolerance;
  copt.mean_move_tolerance = options.lloyd_mean_tolerance;
  if (options.surface_lloyd_iterations > 0) {
    copt.initialization = CvtInitialization::farthest_point;
    copt.surface_lloyd_iterations = options.surface_lloyd_iterations;
    copt.surface_lloyd_relaxation = options.cloud.surface_lloyd_relaxation;
    copt.surface_lloyd_mean_tolerance = options.surface_lloyd_mean_tolerance;
    // The heat iterations after a surface-Lloyd start already diffuse over one ring of cells
    // (CvtOptions::voronoi_rings_settled); the final diagram does too.
    copt.voronoi_rings = copt.voronoi_rings_settled;
  }
  return copt;
}

namespace {

// A cloud split into its dense pieces (dense_pieces.h) and the rest, in the input's units, with
// what the whole cloud's clean-up did (`prepared`'s point counts) and the area of its CVT
// points' triangles (input units²).
struct DenseSplit {
  std::vector<Eigen::MatrixX3d> pieces;
  std::vector<int> sites;
  Eigen::MatrixX3d rest, used;
  double area = 0;
  ReconstructionResult prepared;
};

// Whether the CVT points cp of the prepared points P (in `frame`) on triangles T hold dense
// pieces; if so, `split` gets them and the rest.
bool split_dense_pieces(const CvtPoints& cp, const Eigen::MatrixX3i& T, const Eigen::MatrixX3d& P,
                        const CloudFrame& frame, const ReconstructionOptions& options, DenseSplit& split) {
  const int n = static_cast<int>(P.rows());
  const auto cvt_point = [&](int i) { return cp.subsampled ? cp.voxel_point[i] : i; };
  std::vector<int> weight(cp.sub.size(), 0);
  for (int i = 0; i < n; ++i) ++weight[cvt_point(i)];
  const DensePieces found = dense_pieces(cp.PC, T, weight, options.sites, options.mesher.min_piece_vertex_fraction,
                                         options.dense_pieces);
  if (found.count() == 0) return false;
  Eigen::MatrixX3d used = P;
  restore_frame(used, frame);
  std::vector<std::vector<int>> rows(found.count() + 1);  // the pieces', then the rest's
  for (int i = 0; i < n; ++i) {
    const int k = found.piece[cvt_point(i)];
    rows[k >= 0 ? k : found.count()].push_back(i);
  }
  const auto gather = [&](const std::vector<int>& r) {
    Eigen::MatrixX3d Q(static_cast<Eigen::Index>(r.size()), 3);
    for (size_t j = 0; j < r.size(); ++j) Q.row(static_cast<Eigen::Index>(j)) = used.row(r[j]);
    return Q;
  };
  for (int k = 0; k < found.count(); ++k) split.pieces.push_back(gather(rows[k]));
  split.rest = gather(rows.back());
  split.sites = found.sites;
  split.area = surface_area(cp.PC, T) * frame.scale * frame.scale;
  split.used = std::move(used);
  return true;
}

// Steps 1-5 of reconstruct_surface() with the retries from other start sites. With `split`, a
// cloud with dense pieces stops after its point Laplacian and returns them in `split` instead.
ReconstructionResult reconstruct_with_retries(const Eigen::MatrixX3d& P_in, const ReconstructionOptions& options,
                                              const ReconstructionCallback& progress, DenseSplit* split) {
  const auto t_start = Clock::now();
  auto report = [&](const std::string& stage, double f) {
    if (progress) progress(stage, std::clamp(f, 0.0, 1.0));
  };
  ReconstructionResult res;
  StageClock stage{res};
  res.points_input = static_cast<int>(P_in.rows());
  if (P_in.rows() == 0) throw InvalidInputError("reconstruct_surface: the point cloud is empty");
  for (Eigen::Index i = 0; i < P_in.rows(); ++i)
    if (!P_in.row(i).allFinite())
      throw InvalidInputError("reconstruct_surface: point " + std::to_string(i) + " has a NaN or infinite coordinate");

  // 1. Clean-up, frame, optional denoising / downsampling; the CVT points.
  report("preprocess", 0);
  const PreparedCloud cloud = prepare_cloud(P_in, options, res);
  const Eigen::MatrixX3d& P = cloud.P;
  const int n = static_cast<int>(P.rows());
  res.points_used = n;
  // Where the clean-up's options took points away, the message says which did.
  std::string after;
  if (options.voxel_size > 0) {
    std::ostringstream size;
    size << options.voxel_size;
    after += " after the voxel grid of size " + size.str();
  }
  if (options.denoise) after += std::string(after.empty() ? " after" : " and") + " the outlier removal";
  if (n < options.neighbors + 1)
    throw InvalidInputError("reconstruct_surface: only " + std::to_string(n) + " usable points" + after +
                            ", need at least " + std::to_string(options.neighbors + 1) + " (neighbors + 1)");
  if (options.sites > n)
    throw InvalidInputError("reconstruct_surface: " + std::to_string(options.sites) + " sites requested but only " +
                            std::to_string(n) + " usable points" + after);
  CvtPoints cp = choose_cvt_points(P, options);
  res.points_cvt = static_cast<int>(cp.sub.size());
  stage.done("preprocess");

  // 2. Normals, the fitted surface, the point Laplacian.
  report("laplacian", 0);
  const auto t0 = Clock::now();
  CloudFitOptions fopt = orient_cvt_points(cp, P, options, res);
  stage.done("normals");
  report("laplacian", 0.2);
  Eigen::MatrixXi knn_fit = fopt.fit_neighbors == res.neighbors_cvt && !cp.subsampled
                                ? cp.knn
                                : k_nearest_neighbors(P, fopt.fit_neighbors, options.threads);
  stage.done("fit neighbourhoods");
  report("laplacian", 0.4);
  Eigen::MatrixX3d N = cloud_normals(cp, knn_fit, n);
  const CloudSurfaceProjector fit(P, std::move(N), fopt, std::move(knn_fit));
  stage.done("cloud normals");
  if (options.smooth_cvt_points) smooth_cvt_points(cp, fit, options);
  stage.done("smoothed cvt points");
  report("laplacian", 0.6);
  PointLaplacian pl = cvt_point_laplacian(cp, options);
  stage.done("point laplacian");
  const Eigen::MatrixX3i& T = pl.triangles;
  Eigen::VectorXd metric_area;
  const Laplacian lap = options.anisotropy > 0 ? lifted_laplacian(cp.PC, cp.NC, T, options.anisotropy, &metric_area)
                                               : std::move(pl.laplacian);
  res.laplacian_seconds = since(t0);
  report("laplacian", 1);
  if (split && split_dense_pieces(cp, T, P, cloud.frame, options, *split)) {
    split->prepared = std::move(res);
    return {};
  }
  // The adaptive sizing on the CVT points (adaptive_sizing.h): the CVT's density and the
  // mesher's relative sizes.
  std::unique_ptr<SurfaceSizing> sizing;
  Eigen::VectorXd density;  // read once: the count retries rerun the CVT with it
  if (options.adaptive.enabled()) {
    sizing = std::make_unique<SurfaceSizing>(surface_sizing(cp.PC, T, cp.NC, options.sites, options.adaptive, options.threads));
    density = sizing->density_at(cp.PC);
    res.size_ratio = sizing->ratio;
    stage.done("adaptive sizing");
  }

  // 3.-5. The CVT, its mesh, the checks and the cloud's coverage; again from other start sites
  // where the mesh is far off the count or covers the cloud in part.
  const MeshingInputs in{cp, T, lap, metric_area, sizing.get(), density, fit, cloud.frame, P};
  res = mesh_with_retries(in, options, report, std::move(res));
  res.total_seconds = since(t_start);
  return res;
}

// The options of the run on finer sites (ReconstructionOptions::finer_retry_factor) after
// `first`: the CVT on factor × sites with its own CVT points, the mesh sized to the count asked
// for, no retries of its own; none where `first` covers the cloud whole or other sites cannot
// reach what it leaves out (partial_other_starts_may_mend()), where the factor is 1 or the
// retries are off, or where the cloud has fewer than max(cvt_points_per_site,
// kFinerRetryMinPointsPerSite) points per finer site.
std::optional<ReconstructionOptions> finer_options(const ReconstructionResult& first, const ReconstructionOptions& options) {
  const int finer = static_cast<int>(std::lround(options.finer_retry_factor * options.sites));
  const double points_needed = std::max(options.cvt_points_per_site, kFinerRetryMinPointsPerSite) * finer;
  if (options.count_retries == 0 || finer <= options.sites || first.points_used < points_needed ||
      !partial_other_starts_may_mend(first))
    return std::nullopt;
  ReconstructionOptions again = options;
  again.sites = finer;
  again.mesher.sizing.target_vertices = requested_vertices(options);
  again.count_retries = 0;
  again.finer_retry_factor = 1;
  return again;
}

// reconstruct_with_retries(), then where its result covers the cloud in part, the run on finer
// sites (finer_options()); `split` as reconstruct_with_retries()'s.
ReconstructionResult reconstruct_whole(const Eigen::MatrixX3d& P_in, const ReconstructionOptions& options,
                                       const ReconstructionCallback& progress, DenseSplit* split) {
  const auto t_start = Clock::now();
  ReconstructionResult best = reconstruct_with_retries(P_in, options, progress, split);
  if (split && !split->pieces.empty()) return best;
  const std::optional<ReconstructionOptions> finer = finer_options(best, options);
  if (!finer) return best;
  // A part too thin for the count's cells: the whole reconstruction once more on finer sites.
  std::optional<ReconstructionResult> r;
  try {
    const std::string prefix = "on " + std::to_string(finer->sites) + " sites: ";
    r = reconstruct_with_retries(P_in, *finer, [&](const std::string& stage, double f) {
      if (progress) progress(prefix + stage, f);
    }, nullptr);
  } catch (const Error&) {  // nothing extracted from the finer sites: the result so far stays
  }
  std::vector<std::pair<std::string, double>> seconds = std::move(best.stage_seconds);
  if (r)
    for (const auto& [name, t] : r->stage_seconds) seconds.emplace_back("finer: " + name, t);
  const int retries = best.count_retries + 1;
  if (r && better_result(*r, best, options)) {
    best = std::move(*r);
    best.finer_retry_sites = finer->sites;
  }
  best.count_retries = retries;
  best.stage_seconds = std::move(seconds);
  best.total_seconds = since(t_start);
  return best;
}

// The options of one part of a split cloud on `sites` sites (and `target` vertices where the
// sizing has a target); where its points were `cleaned` up with the whole cloud, none of its own.
ReconstructionOptions part_options(const ReconstructionOptions& options, int sites, int target, bool cleaned) {
  ReconstructionOptions o = options;
  o.sites = sites;
  if (o.mesher.sizing.target_vertices > 0) o.mesher.sizing.target_vertices = target;
  if (!cleaned) return o;
  o.denoise = false;
  o.voxel_size = 0;
  o.stray.ratio = 0;
  o.stray.sparse_group_fraction = 0;
  o.stray.min_group_points = 0;
  return o;
}

// Adds the counts of `b`'s run to `a`'s, and its mesh to `a`'s mesh.
void add_part(ReconstructionResult& a, ReconstructionResult&& b, const std::string& name) {
  const Eigen::Index nv = a.mesh.V.rows(), nf = a.mesh.F.rows();
  a.mesh.V.conservativeResize(nv + b.mesh.V.rows(), 3);
  a.mesh.V.bottomRows(b.mesh.V.rows()) = b.mesh.V;
  a.mesh.F.conservativeResize(nf + b.mesh.F.rows(), 3);
  a.mesh.F.bottomRows(b.mesh.F.rows()) = b.mesh.F.array() + static_cast<int>(nv);
  using R = ReconstructionResult;
  for (int R::*m : {&R::points_used, &R::points_cvt, &R::points_stray, &R::candidate_triangles, &R::rejected_triangles,
                    &R::removed_triangles, &R::holes_filled, &R::star_triangles, &R::trimmed_faces, &R::pieces_removed,
                    &R::flipped_edges, &R::unused_sites, &R::collapsed_edges, &R::split_edges, &R::flying_faces,
                    &R::faces_turned_outward, &R::count_retries})
    a.*m += b.*m;
  a.filled_hole_edges.insert(a.filled_hole_edges.end(), b.filled_hole_edges.begin(), b.filled_hole_edges.end());
  a.polish_fallback |= b.polish_fallback;
  a.angle_polish_undone |= b.angle_polish_undone;
  a.sized |= b.sized;
  a.crossing_after_sizing += b.crossing_after_sizing;
  a.size_ratio = std::max(a.size_ratio, b.size_ratio);
  a.laplacian_seconds += b.laplacian_seconds, a.factor_seconds += b.factor_seconds, a.cvt_seconds += b.cvt_seconds;
  BorderFit& f = a.border;
  const BorderFit& g = b.border;
  const auto mean = [](double x, int wx, double y, int wy) { return wx + wy > 0 ? (x * wx + y * wy) / (wx + wy) : 0.0; };
  f.edge_covered = mean(f.edge_covered, f.edge_points, g.edge_covered, g.edge_points);
  f.mesh_border_on_edge = mean(f.mesh_border_on_edge, f.mesh_border_vertices, g.mesh_border_on_edge, g.mesh_border_vertices);
  f.edge_distance = std::max(f.edge_distance, g.edge_distance);
  f.mesh_border_distance = std::max(f.mesh_border_distance, g.mesh_border_distance);
  f.edge_points += g.edge_points, f.mesh_border_vertices += g.mesh_border_vertices;
  CoverageRepairStats& c = a.coverage;
  c.uncovered_before += b.coverage.uncovered_before, c.uncovered_after += b.coverage.uncovered_after;
  c.moves += b.coverage.moves, c.inserted += b.coverage.inserted;
  c.gap_before = std::max(c.gap_before, b.coverage.gap_before), c.gap_after = std::max(c.gap_after, b.coverage.gap_after);
  a.finer_retry_sites = std::max(a.finer_retry_sites, b.finer_retry_sites);
  for (const auto& [stage, t] : b.stage_seconds) a.stage_seconds.emplace_back(name + ": " + stage, t);
}

// The rest of a split cloud and each dense piece meshed on its own sites (reconstruct_parts();
// `cleaned`: their points were cleaned up with the whole cloud, so none of their own), the
// coverage measured on `used` at the spacing sqrt(area / the count asked for), with the
// joined mesh's area where `area` is 0.
ReconstructionResult join_parts(const Eigen::MatrixX3d& rest, const std::vector<Eigen::MatrixX3d>& pieces,
                                const std::vector<int>& piece_sites, const ReconstructionOptions& options,
                                const ReconstructionCallback& progress, const Eigen::MatrixX3d& used, double area,
                                bool cleaned) {
  const auto prefixed = [&](const std::string& name) -> ReconstructionCallback {
    return [&, name](const std::string& stage, double f) {
      if (progress) progress(name + ": " + stage, f);
    };
  };
  const int taken = std::accumulate(piece_sites.begin(), piece_sites.end(), 0);
  const int asked = requested_vertices(options);
  ReconstructionResult out =
      reconstruct_whole(rest, part_options(options, options.sites - taken, asked - taken, cleaned), prefixed("rest"), nullptr);
  for (auto& [stage, t] : out.stage_seconds) stage = "rest: " + stage;
  for (size_t k = 0; k < pieces.size(); ++k) {
    const std::string name = "piece " + std::to_string(k + 1);
    try {
      add_part(out, reconstruct_whole(pieces[k], part_options(options, piece_sites[k], piece_sites[k], cleaned),
                                      prefixed(name), nullptr),
               name);
      ++out.dense_pieces;
    } catch (const Error&) {
      ++out.pieces_removed;
    }
  }
  const TriangleQuality tq = triangle_quality(out.mesh.V, out.mesh.F);
  out.min_angle_deg = tq.min_angle_deg;
  out.mean_min_angle_deg = tq.mean_min_angle_deg;
  out.boundary_min_angle_deg = tq.boundary_min_angle_deg;
  ValidationOptions vopt;
  vopt.require_closed = false;
  out.validation = validate_triangle_mesh(out.mesh.V, out.mesh.F, vopt);
  CloudCoverageOptions coverage_options = options.cloud_coverage;
  coverage_options.threads = options.threads;
  if (!(area > 0)) area = surface_area(out.mesh.V, out.mesh.F);
  out.cloud_coverage = cloud_coverage(out.mesh, used, std::sqrt(area / asked), coverage_options);
  return out;
}

// join_parts() on a split cloud, with the whole cloud's clean-up counts and stage times.
ReconstructionResult reconstruct_split(const DenseSplit& split, const ReconstructionOptions& options,
                                       const ReconstructionCallback& progress) {
  ReconstructionResult out = join_parts(split.rest, split.pieces, split.sites, options, progress, split.used, split.area, true);
  const ReconstructionResult& p = split.prepared;
  out.points_input = p.points_input, out.points_merged = p.points_merged, out.points_denoised = p.points_denoised;
  out.points_voxel_removed = p.points_voxel_removed, out.points_stray += p.points_stray;
  out.stage_seconds.insert(out.stage_seconds.begin(), p.stage_seconds.begin(), p.stage_seconds.end());
  return out;
}

}  // namespace

ReconstructionResult reconstruct_surface(const Eigen::MatrixX3d& P_in, const ReconstructionOptions& options,
                                         const ReconstructionCallback& progress) {
  const auto t_start = Clock::now();
  check_options(options);
  DenseSplit split;
  ReconstructionResult r = reconstruct_whole(P_in, options, progress, options.dense_pieces.enabled() ? &split : nullptr);
  if (!split.pieces.empty()) {
    // The whole cloud as one where the rest gives no mesh on its sites, or where the parts' meshes,
    // each checked on its own, fail the checks joined (parts a spacing apart whose faces cross).
    std::optional<ReconstructionResult> parts;
    try {
      parts = reconstruct_split(split, options, progress);
    } catch (const Error&) {
    }
    if (!parts || !parts->validation.ok()) {
      ReconstructionResult whole = reconstruct_whole(P_in, options, progress, nullptr);
      if (!parts || whole.validation.ok()) parts = std::move(whole);
    }
    r = std::move(*parts);
  }
  r.total_seconds = since(t_start);
  return r;
}

ReconstructionResult reconstruct_parts(const Eigen::MatrixX3d& rest, const std::vector<Eigen::MatrixX3d>& pieces,
                                       const std::vector<int>& piece_sites, const ReconstructionOptions& options,
                                       const ReconstructionCallback& progress) {
  const auto t_start = Clock::now();
  check_options(options);
  if (piece_sites.size() != pieces.size()) throw InvalidInputError("reconstruct_parts: one site count per piece is needed");
  int taken = 0;
  Eigen::Index rows = rest.rows();
  for (size_t k = 0; k < pieces.size(); ++k) {
    if (piece_sites[k] < 4) throw InvalidInputError("reconstruct_parts: a piece needs at least 4 sites");
    taken += piece_sites[k];
    rows += pieces[k].rows();
  }
  if (options.sites - taken < 4) throw InvalidInputError("reconstruct_parts: the pieces leave the rest fewer than 4 sites");
  Eigen::MatrixX3d used(rows, 3);
  used.topRows(rest.rows()) = rest;
  rows = rest.rows();
  for (const Eigen::MatrixX3d& piece : pieces) used.middleRows(rows, piece.rows()) = piece, rows += piece.rows();
  ReconstructionResult out = join_parts(rest, pieces, piece_sites, options, progress, used, 0, false);
  out.points_input = static_cast<int>(used.rows());
  out.total_seconds = since(t_start);
  return out;
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
