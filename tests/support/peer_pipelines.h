#pragma once
// The peer reconstruction pipelines that the reconstruction acceptance compares heatcvt with, shared
// by tests/test_reconstruct.cpp and bench/bench_reconstruct.cpp: normals as heatcvt estimates
// them, PCL Poisson and CGAL Poisson, and CGAL isotropic remeshing to a vertex count (the
// two-step pipelines "Poisson + remesh" that a careful user would run).
#include <pcl/PolygonMesh.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "heatcvt/mesh.h"

namespace heatcvt::test {

/// Unit normals for the peers: PCA over k = 30 neighbours, oriented by a minimum spanning tree over
/// k = 10 neighbours (heatcvt's own estimate, normals.h), `threads` as there (0 = all).
Eigen::MatrixX3d peer_normals(const Eigen::MatrixX3d& P, int threads = 0);

/// Points with normals as a PCL cloud.
pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N);

/// A PCL polygon mesh (x, y, z of its cloud; polygons fanned into triangles) as a TriangleMesh.
TriangleMesh from_pcl(const pcl::PolygonMesh& pm);

/// The mesh without its unreferenced vertices (faces renumbered, order kept).
TriangleMesh compact(const TriangleMesh& m);

/// PCL Poisson surface reconstruction (octree depth `depth`, PCL's other defaults), compacted.
TriangleMesh pcl_poisson(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, int depth = 8);

/// CGAL Poisson surface reconstruction (poisson_surface_reconstruction_delaunay with the average
/// spacing over 6 neighbours). Throws std::runtime_error when CGAL reports a failure.
TriangleMesh cgal_poisson(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N);

/// CGAL isotropic remeshing (5 iterations) of a mesh, after repairing and orienting it as a polygon
/// soup, to `target_vertices` vertices: the first run uses the target edge length of an
/// equilateral mesh of that many vertices of the same area (CGAL's split and collapse bounds then
/// give about 15 % more), each next one that length scaled by √(count / target), until the count
/// is within kRemeshCountTolerance of the target or after kRemeshLengthRuns runs (as
/// bench_remesh calibrates it): the peers are compared at the vertex count heatcvt is asked for.
/// `last_run_seconds` (optional) gets the time of the last run alone, what a user who knew the
/// length would spend.
constexpr double kRemeshCountTolerance = 0.02;
constexpr int kRemeshLengthRuns = 4;
TriangleMesh remesh_to(const TriangleMesh& m, int target_vertices, double* last_run_seconds = nullptr);

/// PCL's GreedyProjectionTriangulation (search radius `radius`, mu 2.5, at most 100 neighbours,
/// surface angle 45°, triangle angles 10–120°, no normal consistency), compacted.
TriangleMesh pcl_greedy_projection(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, double radius);

/// The usual PCL meshing of an open scan at about `target` vertices: the cloud voxel-downsampled
/// (pcl::VoxelGrid, leaf found by secant steps on the occupied-voxel count) to within 2 % of
/// `target` points, peer_normals, then pcl_greedy_projection with a radius of 3 leaves.
TriangleMesh pcl_greedy_projection_at_count(const Eigen::MatrixX3d& P, int target);

/// One two-step peer result: its name and mesh.
struct PeerMesh {
  std::string method;
  TriangleMesh mesh;
};

/// The two two-step peers of the acceptance on the bare points P: normals (peer_normals), then
/// "PCL Poisson + CGAL remesh" and "CGAL Poisson + CGAL remesh" to `target_vertices` vertices.
std::vector<PeerMesh> two_step_peers(const Eigen::MatrixX3d& P, int target_vertices, int threads = 0);

}  // namespace heatcvt::test
