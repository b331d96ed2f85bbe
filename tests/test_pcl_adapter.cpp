// Tests of the PCL adapter (heatcvt/pcl/*.h): HeatCVTReconstruction gives the same mesh as
// reconstruct_surface() / cloud2mesh, HeatVoronoiSegmentation returns a connected partition that
// matches the heat Voronoi labels (largest heat, eq. 15/17), and bad inputs give PCL_ERROR + an
// empty result.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "heatcvt/heat_solver.h"
#include "heatcvt/pcl/heat_voronoi_segmentation.h"
#include "heatcvt/point_laplacian.h"
#include "test_support.h"

namespace {

using heatcvt::test::data_path;

// Random points on the unit sphere (normalised Gaussians), seeded.
pcl::PointCloud<pcl::PointXYZ>::Ptr sphere_cloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d p(g(rng), g(rng), g(rng));
    p.normalize();
    cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  }
  return cloud;
}

Eigen::MatrixX3d to_eigen(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  Eigen::MatrixX3d P(static_cast<Eigen::Index>(cloud.size()), 3);
  for (std::size_t i = 0; i < cloud.size(); ++i) P.row(static_cast<Eigen::Index>(i)) << cloud[i].x, cloud[i].y, cloud[i].z;
  return P;
}

// Labels per cloud index from clusters; asserts every index appears at most once.
std::vector<int> labels_of(const std::vector<pcl::PointIndices>& clusters, std::size_t n) {
  std::vector<int> label(n, -1);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices) {
      EXPECT_GE(i, 0);
      EXPECT_LT(static_cast<std::size_t>(i), n);
      EXPECT_EQ(label[static_cast<std::size_t>(i)], -1) << "point " << i << " in two clusters";
      label[static_cast<std::size_t>(i)] = static_cast<int>(c);
    }
  return label;
}

// Every cluster is connected in the edge graph of the point Laplacian's local triangles.
void expect_clusters_connected(const std::vector<int>& label, const Eigen::MatrixX3i& T, int num_clusters) {
  const int n = static_cast<int>(label.size());
  std::vector<std::vector<int>> adj(static_cast<std::size_t>(n));
  for (Eigen::Index f = 0; f < T.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = T(f, c), b = T(f, (c + 1) % 3);
      adj[static_cast<std::size_t>(a)].push_back(b);
      adj[static_cast<std::size_t>(b)].push_back(a);
    }
  std::vector<int> comp(static_cast<std::size_t>(n), -1);
  std::vector<int> pieces(static_cast<std::size_t>(num_clusters), 0);
  for (int s = 0; s < n; ++s) {
    if (comp[static_cast<std::size_t>(s)] >= 0) continue;
    ++pieces[static_cast<std::size_t>(label[static_cast<std::size_t>(s)])];
    std::queue<int> q;
    q.push(s);
    comp[static_cast<std::size_t>(s)] = s;
    while (!q.empty()) {
      const int v = q.front();
      q.pop();
      for (int w : adj[static_cast<std::size_t>(v)])
        if (comp[static_cast<std::size_t>(w)] < 0 && label[static_cast<std::size_t>(w)] == label[static_cast<std::size_t>(v)]) {
          comp[static_cast<std::size_t>(w)] = s;
          q.push(w);
        }
    }
  }
  for (int c = 0; c < num_clusters; ++c) EXPECT_LE(pieces[static_cast<std::size_t>(c)], 1) << "cluster " << c << " is split";
}

TEST(HeatVoronoiSegmentation, ExplicitSitesMatchLargestHeatAndPartition) {
  const auto cloud = sphere_cloud(3000, 11);
  pcl::Indices sites;
  std::mt19937 rng(5);
  std::set<int> chosen;
  while (chosen.size() < 12) chosen.insert(static_cast<int>(rng() % cloud->size()));
  sites.assign(chosen.begin(), chosen.end());

  heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;
  seg.setInputCloud(cloud);
  seg.setSiteIndices(sites);
  seg.setKSearch(20);
  seg.setNumberOfThreads(2);
  std::vector<pcl::PointIndices> clusters;
  seg.extract(clusters);
  ASSERT_EQ(clusters.size(), sites.size());
  EXPECT_EQ(seg.getNumberOfUnreachedPoints(), 0);

  // Partition: every point exactly once.
  const std::vector<int> label = labels_of(clusters, cloud->size());
  for (std::size_t i = 0; i < label.size(); ++i) ASSERT_GE(label[i], 0) << "point " << i << " in no cluster";
  for (std::size_t s = 0; s < sites.size(); ++s) EXPECT_EQ(label[static_cast<std::size_t>(sites[s])], static_cast<int>(s));

  // Same labels as the largest heat, computed here independently with full solves from each site.
  const Eigen::MatrixX3d P = to_eigen(*cloud);
  heatcvt::PointLaplacianOptions lopt;
  lopt.k = 20;
  const heatcvt::PointLaplacian pl = heatcvt::point_laplacian(P, lopt);
  const heatcvt::HeatSolver solver(pl.laplacian);
  Eigen::MatrixXd U(P.rows(), static_cast<Eigen::Index>(sites.size()));
  for (std::size_t s = 0; s < sites.size(); ++s) U.col(static_cast<Eigen::Index>(s)) = solver.diffuse_from_vertex(sites[s]);
  int compared = 0;
  for (Eigen::Index v = 0; v < P.rows(); ++v) {
    Eigen::Index best;
    const double top = U.row(v).maxCoeff(&best);
    double second = 0;
    for (Eigen::Index s = 0; s < U.cols(); ++s)
      if (s != best) second = std::max(second, U(v, s));
    if (top - second <= 1e-9 * top) continue;  // numerical tie: eq. 19 decides
    ++compared;
    EXPECT_EQ(label[static_cast<std::size_t>(v)], static_cast<int>(best)) << "point " << v;
  }
  EXPECT_GT(compared, static_cast<int>(P.rows()) - 10);

  // Cells of a heat Voronoi diagram on a sphere are connected; cell sizes sum to the points.
  expect_clusters_connected(label, pl.triangles, static_cast<int>(sites.size()));
  ASSERT_EQ(seg.getSitePositions().rows(), static_cast<Eigen::Index>(sites.size()));
  EXPECT_EQ(seg.getSitePositions().row(3), P.row(sites[3]));
}

TEST(HeatVoronoiSegmentation, CvtSitesOnRealScanIndicesNanAndDuplicates) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  ASSERT_EQ(pcl::io::loadPCDFile(data_path("clouds/pcl_bun0.pcd"), *cloud), 0);
  const std::size_t n0 = cloud->size();
  ASSERT_GT(n0, 300u);
  // NaN points and exact duplicates, as in organised / merged scans.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 5; ++i) cloud->push_back(pcl::PointXYZ(nan, nan, nan));
  for (int i = 0; i < 5; ++i) cloud->push_back((*cloud)[static_cast<std::size_t>(37 * i)]);
  // Indices: everything except every 7th original point.
  pcl::IndicesPtr indices(new pcl::Indices);
  for (std::size_t i = 0; i < cloud->size(); ++i)
    if (i >= n0 || i % 7 != 3) indices->push_back(static_cast<int>(i));

  heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;
  seg.setInputCloud(cloud);
  seg.setIndices(indices);
  seg.setNumberOfSites(10);
  seg.setMaximumIterations(5);
  seg.setKSearch(15);
  seg.setNumberOfThreads(2);
  std::vector<pcl::PointIndices> clusters;
  seg.extract(clusters);
  ASSERT_EQ(clusters.size(), 10u);

  const std::vector<int> label = labels_of(clusters, cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const bool indexed = std::binary_search(indices->begin(), indices->end(), static_cast<int>(i));
    const bool finite = std::isfinite((*cloud)[i].x);
    EXPECT_EQ(label[i] >= 0, indexed && finite) << "point " << i;
  }
  for (int i = 0; i < 5; ++i) {
    const std::size_t dup = n0 + 5 + static_cast<std::size_t>(i), orig = static_cast<std::size_t>(37 * i);
    if (label[orig] >= 0) EXPECT_EQ(label[dup], label[orig]) << "duplicate of point " << orig;
  }
  for (const auto& c : clusters) EXPECT_FALSE(c.indices.empty());

  // Deterministic: a second run (other thread count) gives the same clusters.
  seg.setNumberOfThreads(1);
  std::vector<pcl::PointIndices> again;
  seg.extract(again);
  ASSERT_EQ(again.size(), clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) EXPECT_EQ(again[c].indices, clusters[c].indices);
}

TEST(HeatVoronoiSegmentation, CvtClustersAreConnectedAndEvenedOut) {
  const auto cloud = sphere_cloud(2000, 3);
  heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;
  seg.setInputCloud(cloud);
  seg.setNumberOfSites(16);
  seg.setMaximumIterations(15);
  seg.setKSearch(20);
  seg.setNumberOfThreads(2);
  std::vector<pcl::PointIndices> clusters;
  seg.extract(clusters);
  ASSERT_EQ(clusters.size(), 16u);
  const std::vector<int> label = labels_of(clusters, cloud->size());
  for (int l : label) ASSERT_GE(l, 0);
  heatcvt::PointLaplacianOptions lopt;
  lopt.k = 20;
  const heatcvt::PointLaplacian pl = heatcvt::point_laplacian(to_eigen(*cloud), lopt);
  expect_clusters_connected(label, pl.triangles, 16);
  // Lloyd iterations even out the cells: the spread of the cluster sizes is well below the one of
  // the seeded random start (measured: std 78 points at 0 iterations, 40 after 15).
  auto size_std = [](const std::vector<pcl::PointIndices>& cl) {
    double mean = 0, var = 0;
    for (const auto& c : cl) mean += static_cast<double>(c.indices.size()) / static_cast<double>(cl.size());
    for (const auto& c : cl) var += std::pow(static_cast<double>(c.indices.size()) - mean, 2) / static_cast<double>(cl.size());
    return std::sqrt(var);
  };
  heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> start;
  start.setInputCloud(cloud);
  start.setNumberOfSites(16);
  start.setMaximumIterations(0);
  start.setKSearch(20);
  std::vector<pcl::PointIndices> initial;
  start.extract(initial);
  ASSERT_EQ(initial.size(), 16u);
  EXPECT_LT(size_std(clusters), 0.6 * size_std(initial));
  // Sites lie on the local triangles of the point Laplacian, i.e. on chords just inside the unit
  // sphere (measured: norms >= 0.989 with k = 20 at 2000 points).
  for (Eigen::Index s = 0; s < seg.getSitePositions().rows(); ++s) {
    EXPECT_LE(seg.getSitePositions().row(s).norm(), 1.0 + 1e-6);
    EXPECT_GE(seg.getSitePositions().row(s).norm(), 0.98);
  }
}

// Runs extract() and returns (clusters, captured stderr).
std::pair<std::vector<pcl::PointIndices>, std::string> extract_capturing(
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ>& seg) {
  std::vector<pcl::PointIndices> clusters(3);  // non-empty on entry: must be cleared
  testing::internal::CaptureStderr();
  seg.extract(clusters);
  return {clusters, testing::internal::GetCapturedStderr()};
}

TEST(HeatVoronoiSegmentation, BadInputsGivePclErrorAndEmptyResult) {
  const std::string tag = "[heatcvt::HeatVoronoiSegmentation::extract]";
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // no input
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find(tag), std::string::npos) << err;
    EXPECT_NE(err.find("No input"), std::string::npos) << err;
  }
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // empty cloud
    seg.setInputCloud(pcl::PointCloud<pcl::PointXYZ>::Ptr(new pcl::PointCloud<pcl::PointXYZ>));
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find("empty"), std::string::npos) << err;
  }
  {
    pcl::PointCloud<pcl::PointXYZ>::Ptr nan_cloud(new pcl::PointCloud<pcl::PointXYZ>);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int i = 0; i < 50; ++i) nan_cloud->push_back(pcl::PointXYZ(nan, 0, 0));
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // only NaN points
    seg.setInputCloud(nan_cloud);
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find("no finite point"), std::string::npos) << err;
  }
  const auto cloud = sphere_cloud(200, 1);
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // too many CVT sites
    seg.setInputCloud(cloud);
    seg.setNumberOfSites(201);
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find("Too many sites"), std::string::npos) << err;
  }
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // zero sites
    seg.setInputCloud(cloud);
    seg.setNumberOfSites(0);
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find(tag), std::string::npos) << err;
  }
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // site index outside the cloud
    seg.setInputCloud(cloud);
    seg.setSiteIndices(pcl::Indices{0, 5, 200});
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find("Site 2 (point 200)"), std::string::npos) << err;
  }
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // site not among the indices
    seg.setInputCloud(cloud);
    seg.setIndices(pcl::IndicesPtr(new pcl::Indices{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
    seg.setSiteIndices(pcl::Indices{2, 50});
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find("Site 1 (point 50)"), std::string::npos) << err;
  }
  {
    heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ> seg;  // bad parameter, thrown by the core
    seg.setInputCloud(cloud);
    seg.setNumberOfSites(5);
    seg.setKSearch(2);
    const auto [c, err] = extract_capturing(seg);
    EXPECT_TRUE(c.empty());
    EXPECT_NE(err.find(tag), std::string::npos) << err;
  }
}

}  // namespace
