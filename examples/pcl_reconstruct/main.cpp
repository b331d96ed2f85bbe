// pcl_reconstruct: loads a PCD cloud, reconstructs a triangle mesh with heat CVT
// (heatcvt::HeatCVTReconstruction, the PCL-style class of heatcvt), saves it as binary PLY.
//
//   pcl_reconstruct INPUT.pcd OUTPUT.ply [SITES [ITERATIONS [SEED]]]
//
// Defaults: 1000 sites, 30 iterations, seed 1. Exit code 0 on success, 1 on any failure.
#include <heatcvt/pcl/heat_cvt_reconstruction.h>
#include <pcl/console/time.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  if (argc < 3 || argc > 6) {
    std::fprintf(stderr, "usage: %s INPUT.pcd OUTPUT.ply [SITES=1000 [ITERATIONS=30 [SEED=1]]]\n", argv[0]);
    return 1;
  }
  const int sites = argc > 3 ? std::atoi(argv[3]) : 1000;
  const int iterations = argc > 4 ? std::atoi(argv[4]) : 30;
  const unsigned seed = argc > 5 ? static_cast<unsigned>(std::strtoul(argv[5], nullptr, 10)) : 1u;

  // Load.
  pcl::console::TicToc timer;
  timer.tic();
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  if (pcl::io::loadPCDFile(argv[1], *cloud) < 0) {
    std::fprintf(stderr, "error: cannot read %s\n", argv[1]);
    return 1;
  }
  std::printf("loaded %zu points from %s in %.0f ms\n", static_cast<std::size_t>(cloud->size()), argv[1], timer.toc());

  // Reconstruct (a kd-tree is built internally; errors come as PCL_ERROR + an empty mesh).
  timer.tic();
  heatcvt::HeatCVTReconstruction<pcl::PointXYZ> reconstruction;
  reconstruction.setInputCloud(cloud);
  reconstruction.setNumberOfSites(sites);
  reconstruction.setMaximumIterations(iterations);
  reconstruction.setSeed(seed);
  pcl::PolygonMesh mesh;
  reconstruction.reconstruct(mesh);
  if (mesh.polygons.empty()) {
    std::fprintf(stderr, "error: reconstruction failed\n");
    return 1;
  }
  const auto& result = reconstruction.getReconstructionResult();
  std::printf("reconstructed %u vertices, %zu triangles in %.0f ms (smallest angle %.1f deg, mean %.1f deg)\n",
              mesh.cloud.width * mesh.cloud.height, mesh.polygons.size(), timer.toc(), result.min_angle_deg,
              result.mean_min_angle_deg);

  // Save.
  if (pcl::io::savePLYFileBinary(argv[2], mesh) < 0) {
    std::fprintf(stderr, "error: cannot write %s\n", argv[2]);
    return 1;
  }
  std::printf("saved %s\n", argv[2]);
  return 0;
}
