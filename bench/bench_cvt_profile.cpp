// Quick per-phase profile of the CVT loop (development aid): bench_cvt_profile [ico-level|file] [sites] [iterations] [threads]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_util.h"
#include "heatcvt/cvt.h"
#include "heatcvt/laplacian.h"
#include "heatcvt/mesh_io.h"
#include "heatcvt/subdivision.h"

using namespace heatcvt;

int main(int argc, char** argv) {
  std::string what = argc > 1 ? argv[1] : "5";
  TriangleMesh m = (what.find('.') == std::string::npos) ? bench::icosphere(std::atoi(what.c_str())) : read_mesh(what);
  CvtOptions o;
  o.sites = argc > 2 ? std::atoi(argv[2]) : 500;
  o.iterations = argc > 3 ? std::atoi(argv[3]) : 10;
  o.threads = argc > 4 ? std::atoi(argv[4]) : 1;
  if (argc > 5) o.voronoi_rings_settled = std::atoi(argv[5]);
  if (argc > 6) o.centroid_rings = std::atoi(argv[6]);
  if (const char* d = std::getenv("DROP")) o.drop_tolerance = std::atof(d);
  if (const char* d = std::getenv("CRINGS")) o.centroid_rings = std::atoi(d);
  if (const char* d = std::getenv("TCOEF")) o.time_coefficient = std::atof(d);
  double t0 = bench::now_seconds();
  Laplacian lap = cotan_laplacian(m.V, m.F);
  std::printf("#V %ld, laplacian %.3f s\n", (long)m.V.rows(), bench::now_seconds() - t0);
  CvtResult r = centroidal_voronoi(m.V, m.F, lap, o, {}, [](const CvtIterationStats& s) {
    std::printf("it %3d  %.4f s (voronoi %.4f [solve %.4f tess %.4f], centroid %.4f)  |I| %.0f  move %.3g mean %.3g revived %d  var %.3g\n", s.iteration, s.seconds,
                s.voronoi_seconds, s.voronoi_solve_seconds, s.tessellate_seconds, s.centroid_seconds, s.mean_index_set, s.max_move, s.mean_move, s.revived_sites, s.area_variance);
    return true;
  });
  std::printf("factor %.3f s %.1f MB, setup %.3f s, total %.3f s, final var %.3g\n", r.factor_seconds, r.factor_bytes / 1e6,
              r.setup_seconds, r.total_seconds, r.final_area_variance);
  auto q = triangle_quality(r.dual.V, r.dual.F);
  std::printf("dual: %d triangles, phi_min %.1f, phi_m %.2f, <30: %.1f%%\n", q.triangles, q.min_angle_deg, q.mean_min_angle_deg, 100 * q.below_30_fraction);
}
