#include "heatcvt/closest_point.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <string>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
}  // namespace

Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Ericson, "Real-Time Collision Detection" §5.1.5: Voronoi regions of the triangle's features.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 - d3 != 0 ? d1 / (d1 - d3) : 0.0;
    return {1 - v, v, 0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 - d6 != 0 ? d2 / (d2 - d6) : 0.0;
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double denom = (d4 - d3) + (d5 - d6);
    const double w = denom != 0 ? (d4 - d3) / denom : 0.0;
    return {0, 1 - w, w};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return {1, 0, 0};  // degenerate triangle: fall back to a corner
  const double v = vb / sum, w = vc / sum;
  return {1 - v - w, v, w};
}

struct ClosestPointTree::Impl {
  Eigen::MatrixX3d V;
  Eigen::MatrixX3i F;
  std::vector<Triangle> triangles;
  Tree tree;
};

ClosestPointTree::ClosestPointTree(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) : impl_(new Impl) {
  if (F.rows() == 0) throw InvalidInputError("closest_surface_points: the mesh has no faces");
  impl_->V = V;
  impl_->F = F;
  impl_->triangles.reserve(F.rows());
  auto P = [&](int i) { return Point(V(i, 0), V(i, 1), V(i, 2)); };
  for (int f = 0; f < F.rows(); ++f) impl_->triangles.emplace_back(P(F(f, 0)), P(F(f, 1)), P(F(f, 2)));
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

ClosestPointTree::~ClosestPointTree() = default;

SurfacePoint ClosestPointTree::closest(const Eigen::Vector3d& p) const {
  const auto hit = impl_->tree.closest_point_and_primitive(Point(p[0], p[1], p[2]));
  SurfacePoint out;
  out.face = static_cast<int>(hit.second - impl_->triangles.cbegin());
  const Eigen::MatrixX3d& V = impl_->V;
  const Eigen::MatrixX3i& F = impl_->F;
  out.bary = closest_point_barycentric(p, V.row(F(out.face, 0)).transpose(), V.row(F(out.face, 1)).transpose(),
                                       V.row(F(out.face, 2)).transpose());
  return out;
}

std::vector<SurfacePoint> closest_surface_points(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                                 const Eigen::MatrixX3d& points) {
  const ClosestPointTree tree(V, F);
  std::vector<SurfacePoint> out(points.rows());
  for (int i = 0; i < points.rows(); ++i) {
    if (!points.row(i).allFinite())
      throw InvalidInputError("closest_surface_points: point " + std::to_string(i) + " is not finite");
    out[i] = tree.closest(points.row(i).transpose());
  }
  return out;
}

std::vector<SurfacePoint> surface_points_at_vertices(const Eigen::MatrixX3i& F, int num_vertices,
                                                     const std::vector<int>& vertices) {
  std::vector<SurfacePoint> first(num_vertices);  // face = −1 until a face references the vertex
  for (int f = static_cast<int>(F.rows()) - 1; f >= 0; --f)
    for (int k = 0; k < 3; ++k) {
      SurfacePoint& p = first[F(f, k)];
      p.face = f;
      p.bary = Eigen::Vector3d::Zero();
      p.bary[k] = 1.0;
    }
  std::vector<SurfacePoint> out;
  out.reserve(vertices.size());
  for (int v : vertices) {
    if (v < 0 || v >= num_vertices || first[v].face < 0)
      throw InvalidInputError("surface_points_at_vertices: vertex " + std::to_string(v) + " is not used by any face");
    out.push_back(first[v]);
  }
  return out;
}

}  // namespace heatcvt
