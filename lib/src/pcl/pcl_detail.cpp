// Non-template part of the PCL adapter: clean-up of gathered points and heat Voronoi labels of
// a point cloud. Kept free of PCL headers (the templates in heatcvt/pcl/impl/*.hpp do the PCL side).
#include "heatcvt/pcl/impl/detail.hpp"

#include <algorithm>
#include <numeric>
#include <string>

#include "heatcvt/cvt.h"
#include "heatcvt/errors.h"
#include "heatcvt/heat_solver.h"
#include "heatcvt/point_laplacian.h"
#include "heatcvt/voronoi.h"

namespace heatcvt {
namespace pcl_detail {

CleanPoints clean_points(const Eigen::MatrixX3d& xyz, const std::vector<int>& cloud_index) {
  const Eigen::Index n = xyz.rows();
  std::vector<Eigen::Index> finite;
  finite.reserve(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    if (xyz.row(i).allFinite()) finite.push_back(i);
  // Same rule as clean_cloud(): lexicographic sort with the index as tie-break, first one kept.
  std::vector<Eigen::Index> sorted = finite;
  std::sort(sorted.begin(), sorted.end(), [&](Eigen::Index a, Eigen::Index b) {
    for (int k = 0; k < 3; ++k)
      if (xyz(a, k) != xyz(b, k)) return xyz(a, k) < xyz(b, k);
    return a < b;
  });
  std::vector<Eigen::Index> first(static_cast<size_t>(n), -1);  // gathered index of the kept copy
  for (size_t s = 0; s < sorted.size(); ++s) {
    const bool dup = s > 0 && (xyz.row(sorted[s]).array() == xyz.row(sorted[s - 1]).array()).all();
    first[static_cast<size_t>(sorted[s])] = dup ? first[static_cast<size_t>(sorted[s - 1])] : sorted[s];
  }
  CleanPoints out;
  out.representative.assign(static_cast<size_t>(n), -1);
  std::vector<int> row_of(static_cast<size_t>(n), -1);
  int m = 0;
  for (Eigen::Index i : finite)
    if (first[static_cast<size_t>(i)] == i) row_of[static_cast<size_t>(i)] = m++;
  out.P.resize(m, 3);
  out.source.resize(static_cast<size_t>(m));
  for (Eigen::Index i : finite) {
    const int r = row_of[static_cast<size_t>(first[static_cast<size_t>(i)])];
    out.representative[static_cast<size_t>(i)] = r;
    if (first[static_cast<size_t>(i)] == i) {
      out.P.row(r) = xyz.row(i);
      out.source[static_cast<size_t>(r)] = cloud_index[static_cast<size_t>(i)];
    }
  }
  return out;
}

SegmentationLabels heat_voronoi_point_labels(const Eigen::MatrixX3d& P, const std::vector<int>& site_rows,
                                             const SegmentationSettings& settings) {
  PointLaplacianOptions lopt;
  lopt.k = settings.k;
  lopt.threads = settings.threads;
  const PointLaplacian pl = point_laplacian(P, lopt);
  const Eigen::MatrixX3i& T = pl.triangles;
  const int n = static_cast<int>(P.rows());

  SegmentationLabels out;
  VoronoiDiagram diagram;
  if (!site_rows.empty()) {
    // A site at point v is the point source e_v: a corner of any local triangle containing v.
    std::vector<int> face_of(static_cast<size_t>(n), -1), corner_of(static_cast<size_t>(n), -1);
    for (int f = static_cast<int>(T.rows()) - 1; f >= 0; --f)
      for (int c = 0; c < 3; ++c) {
        face_of[static_cast<size_t>(T(f, c))] = f;
        corner_of[static_cast<size_t>(T(f, c))] = c;
      }
    std::vector<SurfacePoint> sites;
    sites.reserve(site_rows.size());
    out.site_positions.resize(static_cast<Eigen::Index>(site_rows.size()), 3);
    for (size_t s = 0; s < site_rows.size(); ++s) {
      const int v = site_rows[s];
      if (v < 0 || v >= n) throw InvalidInputError("site " + std::to_string(s) + " is not a usable point");
      if (face_of[static_cast<size_t>(v)] < 0)
        throw InvalidInputError("site " + std::to_string(s) +
                                " lies in no local triangle of the point Laplacian (isolated or degenerate neighbourhood)");
      SurfacePoint sp;
      sp.face = face_of[static_cast<size_t>(v)];
      sp.bary = Eigen::Vector3d::Zero();
      sp.bary[corner_of[static_cast<size_t>(v)]] = 1.0;
      sites.push_back(sp);
      out.site_positions.row(static_cast<Eigen::Index>(s)) = P.row(v);
    }
    HeatSolverOptions sopt;
    sopt.time_coefficient = settings.time_coefficient;
    sopt.threads = settings.threads;
    const HeatSolver solver(pl.laplacian, sopt);
    VoronoiOptions vopt;
    vopt.threads = settings.threads;
    diagram = heat_voronoi(P, T, solver, sites, vopt);
  } else {
    CvtOptions copt;
    copt.sites = settings.sites;
    copt.iterations = settings.iterations;
    copt.seed = settings.seed;
    copt.threads = settings.threads;
    copt.time_coefficient = settings.time_coefficient;
    copt.build_dual = false;
    CvtResult cvt = centroidal_voronoi(P, T, pl.laplacian, copt);
    out.site_positions = cvt.positions;
    diagram = std::move(cvt.diagram);
  }
  // Original vertices keep their indices in the refined mesh; every refined face touching v lies
  // in the cell with the largest heat at v (ties: the first such face in refined order).
  out.labels.assign(static_cast<size_t>(n), -1);
  for (Eigen::Index r = 0; r < diagram.F.rows(); ++r) {
    const int cell = diagram.face_cell[r];
    if (cell < 0) continue;
    for (int c = 0; c < 3; ++c) {
      const int v = diagram.F(r, c);
      if (v < n && out.labels[static_cast<size_t>(v)] < 0) out.labels[static_cast<size_t>(v)] = cell;
    }
  }
  out.unreached = static_cast<int>(std::count(out.labels.begin(), out.labels.end(), -1));
  return out;
}

}  // namespace pcl_detail
}  // namespace heatcvt
