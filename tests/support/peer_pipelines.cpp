#include "peer_pipelines.h"

#include <pcl/filters/voxel_grid.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>

#define CGAL_EIGEN3_ENABLED 1  // CGAL Poisson's sparse solver (Eigen is linked through heatcvt)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <pcl/conversions.h>
#include <pcl/surface/poisson.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "heatcvt/normals.h"

namespace heatcvt::test {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

TriangleMesh from_cgal(const CgalMesh& sm) {
  TriangleMesh m;
  m.V.resize(sm.number_of_vertices(), 3);
  for (auto v : sm.vertices()) m.V.row(v.idx()) << sm.point(v).x(), sm.point(v).y(), sm.point(v).z();
  m.F.resize(sm.number_of_faces(), 3);
  for (auto f : sm.faces()) {
    int k = 0;
    for (auto v : vertices_around_face(sm.halfedge(f), sm)) m.F(f.idx(), k++) = static_cast<int>(v.idx());
  }
  return m;
}

}  // namespace

Eigen::MatrixX3d peer_normals(const Eigen::MatrixX3d& P, int threads) {
  Eigen::MatrixX3d N = estimate_normals(P, 30, threads);
  orient_normals_mst(P, N, 10, threads);
  return N;
}

pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N) {
  pcl::PointCloud<pcl::PointNormal>::Ptr c(new pcl::PointCloud<pcl::PointNormal>);
  c->resize(P.rows());
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    auto& p = (*c)[i];
    p.x = P(i, 0), p.y = P(i, 1), p.z = P(i, 2);
    p.normal_x = N(i, 0), p.normal_y = N(i, 1), p.normal_z = N(i, 2);
  }
  c->width = static_cast<std::uint32_t>(P.rows());
  c->height = 1;
  return c;
}

TriangleMesh from_pcl(const pcl::PolygonMesh& pm) {
  pcl::PointCloud<pcl::PointXYZ> c;
  pcl::fromPCLPointCloud2(pm.cloud, c);
  TriangleMesh m;
  m.V.resize(c.size(), 3);
  for (size_t i = 0; i < c.size(); ++i) m.V.row(i) << c[i].x, c[i].y, c[i].z;
  std::vector<Eigen::Vector3i> f;
  for (const auto& p : pm.polygons)
    for (size_t k = 1; k + 1 < p.vertices.size(); ++k) f.emplace_back(p.vertices[0], p.vertices[k], p.vertices[k + 1]);
  m.F.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) m.F.row(i) = f[i].transpose();
  return m;
}

TriangleMesh compact(const TriangleMesh& m) {
  std::vector<int> map(m.V.rows(), -1);
  int n = 0;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (map[m.F(f, k)] < 0) map[m.F(f, k)] = n++;
  TriangleMesh o;
  o.V.resize(n, 3);
  for (Eigen::Index v = 0; v < m.V.rows(); ++v)
    if (map[v] >= 0) o.V.row(map[v]) = m.V.row(v);
  o.F.resize(m.F.rows(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) o.F(f, k) = map[m.F(f, k)];
  return o;
}

TriangleMesh pcl_poisson(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, int depth) {
  pcl::Poisson<pcl::PointNormal> ps;
  ps.setDepth(depth);
  ps.setInputCloud(with_normals(P, N));
  pcl::PolygonMesh pm;
  ps.reconstruct(pm);
  return compact(from_pcl(pm));
}

TriangleMesh cgal_poisson(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N) {
  using PN = std::pair<K::Point_3, K::Vector_3>;
  std::vector<PN> pn;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    pn.emplace_back(K::Point_3(P(i, 0), P(i, 1), P(i, 2)), K::Vector_3(N(i, 0), N(i, 1), N(i, 2)));
  const double avg = CGAL::compute_average_spacing<CGAL::Sequential_tag>(
      pn, 6, CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PN>()));
  CgalMesh sm;
  if (!CGAL::poisson_surface_reconstruction_delaunay(pn.begin(), pn.end(), CGAL::First_of_pair_property_map<PN>(),
                                                     CGAL::Second_of_pair_property_map<PN>(), sm, avg))
    throw std::runtime_error("CGAL Poisson failed");
  return from_cgal(sm);
}

TriangleMesh remesh_to(const TriangleMesh& m, int target_vertices, double* last_run_seconds) {
  std::vector<K::Point_3> pts;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) pts.emplace_back(m.V(i, 0), m.V(i, 1), m.V(i, 2));
  std::vector<std::vector<std::size_t>> polys;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    polys.push_back({static_cast<std::size_t>(m.F(f, 0)), static_cast<std::size_t>(m.F(f, 1)),
                     static_cast<std::size_t>(m.F(f, 2))});
  PMP::repair_polygon_soup(pts, polys);
  PMP::orient_polygon_soup(pts, polys);
  CgalMesh input;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, input);
  double L = std::sqrt(2.0 * PMP::area(input) / (std::sqrt(3.0) * target_vertices));
  TriangleMesh out;
  for (int run = 0; run < kRemeshLengthRuns; ++run) {
    CgalMesh sm = input;
    const auto t0 = std::chrono::steady_clock::now();
    PMP::isotropic_remeshing(faces(sm), L, sm, CGAL::parameters::number_of_iterations(5));
    sm.collect_garbage();
    if (last_run_seconds)
      *last_run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out = from_cgal(sm);
    const double count = static_cast<double>(out.V.rows());
    if (std::abs(count - target_vertices) <= kRemeshCountTolerance * target_vertices || !(count > 0)) break;
    L *= std::sqrt(count / target_vertices);
  }
  return out;
}

std::vector<PeerMesh> two_step_peers(const Eigen::MatrixX3d& P, int target_vertices, int threads) {
  const Eigen::MatrixX3d N = peer_normals(P, threads);
  return {{"PCL Poisson + CGAL remesh", remesh_to(pcl_poisson(P, N), target_vertices)},
          {"CGAL Poisson + CGAL remesh", remesh_to(cgal_poisson(P, N), target_vertices)}};
}

TriangleMesh pcl_greedy_projection(const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N, double radius) {
  pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
  auto cloud = with_normals(P, N);
  pcl::search::KdTree<pcl::PointNormal>::Ptr tree(new pcl::search::KdTree<pcl::PointNormal>);
  tree->setInputCloud(cloud);
  gp3.setSearchRadius(radius);
  gp3.setMu(2.5);
  gp3.setMaximumNearestNeighbors(100);
  gp3.setMaximumSurfaceAngle(M_PI / 4);
  gp3.setMinimumAngle(M_PI / 18);
  gp3.setMaximumAngle(2 * M_PI / 3);
  gp3.setNormalConsistency(false);
  gp3.setInputCloud(cloud);
  gp3.setSearchMethod(tree);
  pcl::PolygonMesh pm;
  gp3.reconstruct(pm);
  return compact(from_pcl(pm));
}

TriangleMesh pcl_greedy_projection_at_count(const Eigen::MatrixX3d& P, int target) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (Eigen::Index i = 0; i < P.rows(); ++i) cloud->push_back(pcl::PointXYZ(P(i, 0), P(i, 1), P(i, 2)));
  const Eigen::Vector3d extent = P.colwise().maxCoeff() - P.colwise().minCoeff();
  double leaf = extent.maxCoeff() / std::sqrt(static_cast<double>(target));
  pcl::PointCloud<pcl::PointXYZ>::Ptr down(new pcl::PointCloud<pcl::PointXYZ>);
  for (int step = 0; step < 8; ++step) {  // secant steps on the leaf size: occupied voxels ~ area / leaf²
    pcl::VoxelGrid<pcl::PointXYZ> vg;
    vg.setInputCloud(cloud);
    vg.setLeafSize(leaf, leaf, leaf);
    vg.filter(*down);
    if (std::abs(static_cast<double>(down->size()) - target) <= 0.02 * target) break;
    leaf *= std::sqrt(static_cast<double>(down->size()) / target);
  }
  Eigen::MatrixX3d D(static_cast<Eigen::Index>(down->size()), 3);
  for (size_t i = 0; i < down->size(); ++i) D.row(static_cast<Eigen::Index>(i)) << (*down)[i].x, (*down)[i].y, (*down)[i].z;
  return pcl_greedy_projection(D, peer_normals(D), 3.0 * leaf);
}

}  // namespace heatcvt::test
