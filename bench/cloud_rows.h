#pragma once
// The table rows of the cloud benchmarks (bench_shared_clouds, bench_lidar_scans): a mesh made
// from a cloud described by its vertex count, pieces, loops, angles, how its border follows the
// cloud's and how much of the cloud it covers; and PCL's greedy projection as the peer row.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_util.h"
#include "heatcvt/cloud_coverage.h"
#include "heatcvt/dual_mesh.h"
#include "heatcvt/mesh.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/validate.h"
#include "peer_pipelines.h"

namespace heatcvt::bench {


struct Row {
  int vertices = 0, components = 0, loops = 0, genus = -1;
  double phi_min = 0, phi_boundary = 180, phi_mean = 0, seconds = 0;
  BorderFit border;  // against the cloud's border points, in the output's mean edge lengths
  double covered = 0;  // fraction of the cloud's points within one mean edge length of the output
  long flying_pixels = -1;  // dropped by the flying-pixel rule; −1 on the peer row (it meshes read_cloud's points, the same ones dropped)
};

inline Row describe(const TriangleMesh& m, double seconds, const Eigen::MatrixX3d& P, const std::vector<char>& on_border) {
  Row r;
  ValidationOptions vo;
  vo.require_closed = false;
  const ValidationReport v = validate_triangle_mesh(m.V, m.F, vo);
  const TriangleQuality q = triangle_quality(m.V, m.F);
  r.vertices = v.vertices;
  r.components = v.components;
  r.loops = v.boundary_loops;
  r.genus = v.genus;
  r.phi_min = q.min_angle_deg;
  r.phi_mean = q.mean_min_angle_deg;
  r.phi_boundary = q.boundary_min_angle_deg;
  r.seconds = seconds;
  if (m.F.rows() == 0) return r;
  const double h = mean_edge_length(m.V, m.F);
  r.border = border_fit(P, on_border, m, h);
  // Every point of clouds up to 100,000 points, an even stride of larger ones (cloud_coverage.h).
  r.covered = P.rows() > 0 ? 1.0 - cloud_coverage(m, P).uncovered_share : 0.0;
  return r;
}

// PCL greedy projection triangulation (the acceptance's peer settings, peer_pipelines.h) of the
// cloud voxel-downsampled to about `target` points, with the peers' normals.
inline Row greedy_projection(const Eigen::MatrixX3d& P, int target, const std::vector<char>& on_border) {
  const double t0 = bench::now_seconds();
  const TriangleMesh m = test::pcl_greedy_projection_at_count(P, target);
  return describe(m, bench::now_seconds() - t0, P, on_border);
}

inline void print(const char* method, const Row& r, int n) {
  std::printf("| %s | %d (%+.1f %%) | %d | %d | %d | %.1f | %.1f | %.1f | %.3f | %.2f | %.3f | %.2f | %s |\n",
              method, r.vertices, 100.0 * (r.vertices - n) / n, r.components, r.loops, r.genus, r.phi_min,
              r.phi_boundary, r.phi_mean, r.border.mesh_border_on_edge, r.border.mesh_border_distance, r.covered, r.seconds,
              r.flying_pixels < 0 ? "-" : std::to_string(r.flying_pixels).c_str());
}

}  // namespace heatcvt::bench
