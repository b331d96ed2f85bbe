// Per-phase profile of the CVT on a point cloud (development aid for cloud2mesh's speed):
//   bench_point_cvt_profile [mesh=kitten.obj] [points=50000] [sites=3000] [iterations=6] [threads=2]
// Samples `points` points (seed 11, no noise) from ../shared/data/meshes/<mesh>, builds the point
// Laplacian, and runs the heat CVT with cloud2mesh's CVT options (reconstruction_cvt_options() of the
// default ReconstructionOptions: the surface-Lloyd start included), printing the time of each Lloyd
// phase. The reconstruction steps after the CVT are not run.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_util.h"
#include "heatcvt/cvt.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/normals.h"
#include "heatcvt/point_laplacian.h"
#include "heatcvt/reconstruct.h"

using namespace heatcvt;

int main(int argc, char** argv) {
  const std::string mesh = argc > 1 ? argv[1] : "kitten.obj";
  const int points = argc > 2 ? std::atoi(argv[2]) : 50000;
  ReconstructionOptions defaults;
  if (argc > 3) defaults.sites = std::atoi(argv[3]);
  if (argc > 4) defaults.iterations = std::atoi(argv[4]);
  defaults.threads = argc > 5 ? std::atoi(argv[5]) : 2;
  CvtOptions o = reconstruction_cvt_options(defaults);  // the CVT cloud2mesh runs (start included)
  if (const char* e = std::getenv("CVT_DROP_TOLERANCE")) o.drop_tolerance = std::atof(e);  // development override
  const TriangleMesh src = read_mesh(std::string(HEATCVT_DATA_DIR) + "/meshes/" + mesh);
  const Eigen::MatrixX3d P = sample_surface(src.V, src.F, points, 11);
  double t0 = bench::now_seconds();
  (void)k_nearest_neighbors(P, defaults.neighbors, o.threads);
  const double knn_seconds = bench::now_seconds() - t0;
  t0 = bench::now_seconds();
  PointLaplacianOptions lo;
  lo.k = defaults.neighbors;
  lo.threads = o.threads;
  const PointLaplacian pl = point_laplacian(P, lo);
  std::printf("%s: %d points, %ld point triangles, L nnz %ld, point laplacian %.3f s (of which kNN %.3f s)\n", mesh.c_str(), points,
              static_cast<long>(pl.triangles.rows()), static_cast<long>(pl.laplacian.L.nonZeros()),
              bench::now_seconds() - t0, knn_seconds);
  {
    double t1 = bench::now_seconds();
    PointLaplacianOptions extrinsic = lo;
    extrinsic.intrinsic_delaunay = false;
    (void)point_laplacian(P, extrinsic);
    const double extrinsic_seconds = bench::now_seconds() - t1;
    const int fit_k = static_cast<int>(defaults.cloud.fit_cells * points / o.sites);
    t1 = bench::now_seconds();
    (void)k_nearest_neighbors(P, fit_k, o.threads);
    const double fit_knn_seconds = bench::now_seconds() - t1;
    t1 = bench::now_seconds();
    Eigen::MatrixX3d N = pl.normals;
    orient_normals_mst(P, N, defaults.cloud.orientation_neighbors, o.threads);
    std::printf("without intrinsic Delaunay %.3f s; reconstruction's fit kNN (k = %d) %.3f s, MST orientation %.3f s\n",
                extrinsic_seconds, fit_k, fit_knn_seconds, bench::now_seconds() - t1);
  }
  const CvtResult r = centroidal_voronoi(P, pl.triangles, pl.laplacian, o, {}, [](const CvtIterationStats& s) {
    std::printf("it %3d  %.3f s (voronoi %.3f [solve %.3f tess %.3f], centroid %.3f)  |I| %.0f  max move %.3g\n",
                s.iteration, s.seconds, s.voronoi_seconds, s.voronoi_solve_seconds, s.tessellate_seconds,
                s.centroid_seconds, s.mean_index_set, s.max_move);
    return true;
  });
  std::printf("factor %.3f s %.1f MB, graph Lloyd %.3f s, setup %.3f s, total %.3f s\n", r.factor_seconds,
              r.factor_bytes / 1e6, r.graph_lloyd_seconds, r.setup_seconds, r.total_seconds);
  std::printf("start: surface Lloyd %d iterations %.3f s, evaluations and split rounds %.3f s (%d rounds, %d sites inserted)\n",
              r.surface_lloyd_iterations, r.surface_lloyd_seconds, r.start_quality_seconds, r.start_rounds,
              r.inserted_sites);
}
