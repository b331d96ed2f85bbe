// Random sphere triangulations via the convex hull (paper Fig. 3); a Klein bottle and two
// interpenetrating sheets (intrinsic, self-intersecting surfaces).
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

TriangleMesh klein_bottle_mesh(int nu, int nv, double r) {
  if (nu < 3 || nv < 4 || nv % 2 != 0)
    throw InvalidInputError("klein_bottle_mesh: need nu >= 3 and an even nv >= 4, got nu = " + std::to_string(nu) +
                            ", nv = " + std::to_string(nv));
  if (!(r > 1) || !std::isfinite(r)) throw InvalidInputError("klein_bottle_mesh: r must be finite and > 1");
  TriangleMesh m;
  m.V.resize(static_cast<Eigen::Index>(nu) * nv, 3);
  auto id = [&](int i, int j) {  // grid (i, j) with the identifications of the Klein bottle
    j = ((j % nv) + nv) % nv;
    if (i == nu) return nv - 1 - j;  // (u + 2π, v) ~ (u, −v): column 0, mirrored row
    return i * nv + j;
  };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2.0 * M_PI * i / nu, v = 2.0 * M_PI * (j + 0.5) / nv;
      const double rad = r + std::cos(u / 2) * std::sin(v) - std::sin(u / 2) * std::sin(2 * v);
      m.V.row(i * nv + j) << rad * std::cos(u), rad * std::sin(u),
          std::sin(u / 2) * std::sin(v) + std::cos(u / 2) * std::sin(2 * v);
    }
  m.F.resize(2 * static_cast<Eigen::Index>(nu) * nv, 3);
  int f = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.F.row(f++) << a, b, c;
      m.F.row(f++) << a, c, d;
    }
  return m;
}

TriangleMesh interpenetrating_sheets_mesh(int n, double angle, double size) {
  if (n < 1) throw InvalidInputError("interpenetrating_sheets_mesh: n must be >= 1");
  if (!(size > 0) || !std::isfinite(size)) throw InvalidInputError("interpenetrating_sheets_mesh: size must be > 0");
  if (!std::isfinite(angle)) throw InvalidInputError("interpenetrating_sheets_mesh: angle must be finite");
  const int side = n + 1, per_sheet = side * side;
  const double h = size / n, c = std::cos(angle), s = std::sin(angle);
  TriangleMesh m;
  m.V.resize(2 * per_sheet, 3);
  m.F.resize(4 * n * n, 3);
  int f = 0;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const int base = sheet * per_sheet;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double x = -size / 2 + i * h + (sheet ? 0.5 * h : 0.0), y = -size / 2 + j * h;
        if (sheet == 0) m.V.row(base + i * side + j) << x, y, 0.0;
        else m.V.row(base + i * side + j) << x, c * y, s * y;  // rotation about the x axis
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int a = base + i * side + j, b = a + side, cc = b + 1, d = a + 1;
        if ((i + j) % 2 == 0) {
          m.F.row(f++) << a, b, cc;
          m.F.row(f++) << a, cc, d;
        } else {
          m.F.row(f++) << a, b, d;
          m.F.row(f++) << b, cc, d;
        }
      }
  }
  return m;
}

}  // namespace heatcvt
