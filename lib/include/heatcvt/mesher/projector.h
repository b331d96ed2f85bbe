#pragma once
/// \file projector.h
/// The surface a mesher's vertices live on. Every stage that moves a vertex (tangential
/// relaxation, angle polish, sliver collapse, edge split) projects the new position through a
/// SurfaceProjector, so the same stages run on a point cloud's fitted surface and on an input
/// triangle mesh.
#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "heatcvt/point_index.h"
#include "heatcvt/sample_border.h"

namespace heatcvt {

/// Projection onto a surface known to the mesher only through this interface.
/// Implementations are safe for concurrent const calls with distinct `hint` variables.
class SurfaceProjector {
 public:
  virtual ~SurfaceProjector() = default;
  /// The point of the surface nearest `x` (its local model around x) and the surface's unit
  /// normal there, oriented like the surface's normals. `hint` is a per-vertex warm start
  /// (an index of the implementation's own, −1 = none), updated to the one used.
  virtual void project(const Eigen::Vector3d& x, int& hint, Eigen::Vector3d& position, Eigen::Vector3d& normal) const = 0;
  /// Distance from `x` to the sampled surface (nearest sample point, or nearest surface point):
  /// hole filling asks whether the surface continues beyond a boundary.
  virtual double distance_to_samples(const Eigen::Vector3d& x) const = 0;
  /// Distance from `x` to the border of the sampled surface (the edge of what was scanned, as
  /// far as the samples show it), or 0 where it is not known: hole filling closes a hole far from
  /// every such border, where the surface is sampled all round. Default 0.
  virtual double distance_to_sample_border(const Eigen::Vector3d& x) const {
    (void)x;
    return 0;
  }
  /// Distance from `x` to the edge of the scan: the border of the samples without the isolated
  /// gaps a noisy sampling leaves by chance (border_chains()), or 0 where it is not known. Hole
  /// filling tells a hole in sampled surface from the edge of what was scanned by it. Default
  /// distance_to_sample_border().
  virtual double distance_to_scan_edge(const Eigen::Vector3d& x) const { return distance_to_sample_border(x); }
  /// The mean of the border points of the samples within `radius` of `x` (the edge of the scan
  /// there, averaged over the radius), in `mean`; false (and `mean` left alone) where there is
  /// none or the border is not sampled (an input mesh). Default false.
  virtual bool sample_border_mean(const Eigen::Vector3d& x, double radius, Eigen::Vector3d& mean) const {
    (void)x, (void)radius, (void)mean;
    return false;
  }
  /// Whether the surface's border is known exactly (an input mesh's boundary edges, none for a
  /// closed mesh); a cloud's is not.
  virtual bool border_known() const { return false; }
  /// Whether the border is known and not empty.
  virtual bool has_border() const { return false; }
  /// Where has_border(): the point of the border nearest `x` and the surface's unit normal there.
  /// Returns false (and leaves the outputs alone) where the surface has no border.
  virtual bool project_to_border(const Eigen::Vector3d& x, Eigen::Vector3d& position, Eigen::Vector3d& normal) const {
    (void)x, (void)position, (void)normal;
    return false;
  }
};

/// Options of the cloud's local surface fit.
struct CloudFitOptions {
  /// Points of each fit neighbourhood (the point and its k nearest). Default 30.
  int fit_neighbors = 30;
  /// Neighbours along which project()'s greedy walk towards the nearest point steps (the first
  /// `walk_neighbors` of the fit neighbourhood). Default 30.
  int walk_neighbors = 30;
  /// A neighbourhood keeps only the points whose normal agrees with its centre's (the other side
  /// of a thin part is left out) unless fewer than min(`min_oriented_points`, fit_neighbors / 2)
  /// remain. Default 12.
  int min_oriented_points = 12;
  /// Below this many points the quadratic fit is not tried (weighted mean height instead). Default 10.
  int min_quadratic_points = 10;
  /// Rank threshold of the column-pivoting QR of the quadratic fit. Default 1e-8.
  double rank_threshold = 1e-8;
  /// The quadratic's height at the query is rejected (weighted mean height instead) when it is
  /// farther than this many bandwidths from the query's own height: an extrapolation. Default 2.
  double max_height_bandwidths = 2.0;
  /// Steps of project()'s greedy walk on the kNN graph. Default 1000.
  int max_walk_steps = 1000;
  /// Which points are on the border of the samples (distance_to_sample_border()); its `threads`
  /// is replaced by this struct's.
  SampleBorderOptions border;
  /// distance_to_scan_edge() counts the border points in chains of at least this many
  /// (border_chains() over `border.neighbors`): a hole of the scan some six point spacings
  /// across has a longer chain round it, while the voids of a random sampling leave clusters of
  /// up to about five (measured on 6·10⁴ and 6·10⁵ random points on a sphere). Default 8.
  int scan_edge_chain = 8;
  int threads = 0;  ///< for the kNN search; 0 = all cores. Default 0.
};

/// The surface of a point cloud: at a point c, the weighted least-squares quadratic height field
/// over the PCA plane of c's fit neighbourhood (Gaussian weights of bandwidth the RMS planar
/// radius around the query; a weighted mean height where the quadratic is ill-posed).
/// project() walks greedily on the kNN graph from the hint to the cloud point nearest x and
/// projects onto the fit there.
class CloudSurfaceProjector final : public SurfaceProjector {
 public:
  /// P (#P by 3) and its oriented unit normals N (#P by 3). `knn` (#P by ≥ fit_neighbors, each
  /// point's nearest others, nearest first) is computed when empty.
  CloudSurfaceProjector(Eigen::MatrixX3d P, Eigen::MatrixX3d N, const CloudFitOptions& options = {},
                        Eigen::MatrixXi knn = {});
  void project(const Eigen::Vector3d& x, int& hint, Eigen::Vector3d& position, Eigen::Vector3d& normal) const override;
  /// Nearest cloud point (kd-tree built on first use).
  double distance_to_samples(const Eigen::Vector3d& x) const override;
  /// Nearest cloud point on the border of the samples (sample_border_points() with
  /// `options.border`, found on first use); infinity where there is none.
  double distance_to_sample_border(const Eigen::Vector3d& x) const override;
  /// Nearest border point in a chain of at least `options.scan_edge_chain`; infinity where there is none.
  double distance_to_scan_edge(const Eigen::Vector3d& x) const override;
  bool sample_border_mean(const Eigen::Vector3d& x, double radius, Eigen::Vector3d& mean) const override;

  /// The fit neighbourhood of cloud point c into `nb` (its storage reused): c and its nearest
  /// points whose normal agrees with c's (all of them when too few agree).
  void neighbourhood(int c, std::vector<int>& nb) const;
  /// Projects x onto the fit around cloud point c; the normal is oriented like `orient`.
  void project_at(int c, const Eigen::Vector3d& x, const Eigen::Vector3d& orient, Eigen::Vector3d& position,
                  Eigen::Vector3d& normal) const;
  /// Projects x onto the quadratic fitted to the points `nb`; the normal is oriented like `orient`.
  void fit_and_project(const std::vector<int>& nb, const Eigen::Vector3d& x, const Eigen::Vector3d& orient,
                       Eigen::Vector3d& position, Eigen::Vector3d& normal) const;
  /// The cloud point nearest x reached by a greedy walk on the kNN graph from `start`.
  int walk(int start, const Eigen::Vector3d& x) const;

  const Eigen::MatrixX3d& points() const { return P_; }
  const Eigen::MatrixX3d& normals() const { return N_; }
  const Eigen::MatrixXi& knn() const { return knn_; }
  /// The cloud's points on the border of the samples (sample_border_points() with
  /// `options.border`).
  const Eigen::MatrixX3d& sample_border() const;

 private:
  Eigen::MatrixX3d P_, N_;
  CloudFitOptions options_;
  Eigen::MatrixXi knn_;
  // Built on first use (hole filling and borders only): every point, the border points, and
  // those of them in chains (distance_to_scan_edge()).
  const PointIndex& border_index() const;
  mutable std::once_flag samples_once_, border_once_;
  mutable std::unique_ptr<PointIndex> samples_, border_, scan_edge_;
  mutable Eigen::MatrixX3d border_points_;
};

class ClosestPointTree;

/// The surface of a triangle mesh: exact closest point (CGAL AABB tree) and the normal
/// interpolated there from the mesh's area-weighted vertex normals. `hint` (a face of the mesh,
/// or −1) is the face the point was on before it moved: where the closest point lies on a face
/// facing against the hint's (the other side of a part thinner than the move: an ear, a fin),
/// the point stays on the hint's side, at the closest point a walk over the faces from the
/// hint reaches (project_local()). On return `hint` is the face of the result.
class MeshSurfaceProjector final : public SurfaceProjector {
 public:
  /// \throw InvalidInputError on a mesh without faces.
  MeshSurfaceProjector(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F);
  ~MeshSurfaceProjector() override;
  void project(const Eigen::Vector3d& x, int& hint, Eigen::Vector3d& position, Eigen::Vector3d& normal) const override;
  double distance_to_samples(const Eigen::Vector3d& x) const override;
  /// The mesh's boundary edges (edges of one face), searched exhaustively: borders are short.
  bool border_known() const override { return true; }
  bool has_border() const override { return !border_.empty(); }
  bool project_to_border(const Eigen::Vector3d& x, Eigen::Vector3d& position, Eigen::Vector3d& normal) const override;

 private:
  Eigen::Vector3d face_normal(int f) const;  // not normalised
  Eigen::MatrixX3d V_, VN_;
  Eigen::MatrixX3i F_;
  std::vector<std::vector<int>> vfaces_;
  std::vector<std::pair<int, int>> border_;
  std::unique_ptr<ClosestPointTree> tree_;
};

}  // namespace heatcvt
