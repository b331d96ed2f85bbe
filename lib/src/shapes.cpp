// Random sphere triangulations via the convex hull (paper Fig. 3).
#include "heatcvt/shapes.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "heatcvt/errors.h"

namespace heatcvt {

TriangleMesh random_sphere_mesh(int num_random, uint32_t seed, bool biased, double bias) {
  if (num_random < 0) throw InvalidInputError("random_sphere_mesh: num_random must be >= 0");
  if (biased && !(std::isfinite(bias) && bias > 0))
    throw InvalidInputError("random_sphere_mesh: bias must be finite and > 0");
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = K::Point_3;
  std::vector<Point> pts = {Point(1, 0, 0), Point(-1, 0, 0), Point(0, 1, 0),
                            Point(0, -1, 0), Point(0, 0, 1), Point(0, 0, -1)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < num_random; ++i) {
    double x = normal(rng), y = normal(rng), z = normal(rng);
    if (biased) x *= bias;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 1e-12)) {
      --i;
      continue;
    }
    pts.emplace_back(x / len, y / len, z / len);
  }
  CGAL::Surface_mesh<Point> hull;
  CGAL::convex_hull_3(pts.begin(), pts.end(), hull);
  TriangleMesh m;
  std::map<CGAL::Surface_mesh<Point>::Vertex_index, int> id;
  m.V.resize(hull.number_of_vertices(), 3);
  int n = 0;
  for (auto v : hull.vertices()) {
    const Point& p = hull.point(v);
    m.V.row(n) << p.x(), p.y(), p.z();
    id[v] = n++;
  }
  m.F.resize(hull.number_of_faces(), 3);
  int f = 0;
  for (auto fc : hull.faces()) {
    int k = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(fc), hull)) {
      if (k < 3) m.F(f, k) = id[v];
      ++k;
    }
    if (k != 3) throw Error("random_sphere_mesh: the convex hull has a non-triangular face");
    ++f;
  }
  return m;
}

}  // namespace heatcvt
