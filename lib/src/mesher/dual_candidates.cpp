// Candidate triangles of the dual of a surface Voronoi diagram.
#include "heatcvt/mesher/dual_candidates.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>

#include "heatcvt/normals.h"
#include "heatcvt/parallel.h"

namespace heatcvt {
namespace {

// Merges the two sorted witness lists with their multiplicities, orients each triple by its
// sites' normals and sorts it into the coherent or the loose candidates.
DualCandidates classify(const std::vector<MeshFace>& cand, const std::vector<MeshFace>& cand_vv, const WorkingMesh& mesh,
                        const DualCandidateOptions& options) {
  const Eigen::MatrixX3d& S = mesh.V;
  const Eigen::MatrixX3d& SN = mesh.N;
  DualCandidates out;
  size_t i = 0, k = 0;
  while (i < cand.size() || k < cand_vv.size()) {
    MeshFace f;
    if (k >= cand_vv.size() || (i < cand.size() && cand[i] <= cand_vv[k])) f = cand[i];
    else f = cand_vv[k];
    int w = 0, wv = 0;
    while (i < cand.size() && cand[i] == f) ++i, ++w;
    while (k < cand_vv.size() && cand_vv[k] == f) ++k, ++wv;
    const Eigen::Vector3d a = S.row(f[0]), b = S.row(f[1]), c = S.row(f[2]);
    const Eigen::Vector3d fn = (b - a).cross(c - a);
    const Eigen::Vector3d vn = SN.row(f[0]) + SN.row(f[1]) + SN.row(f[2]);
    if (fn.dot(vn) < 0) std::swap(f[1], f[2]);
    const double q = face_min_angle(mesh, f);
    const Eigen::Vector3d fo = (S.row(f[1]) - S.row(f[0])).cross(S.row(f[2]) - S.row(f[0])).transpose();
    bool coherent = fo.norm() > 0;
    double min_dot = 1;
    for (int j = 0; j < 3 && fo.norm() > 0; ++j) min_dot = std::min(min_dot, fo.normalized().dot(SN.row(f[j]).transpose()));
    if (!(min_dot > options.coherent_min_dot)) coherent = false;
    if (q > 0 && coherent) out.coherent.push_back({f, w + wv, wv, q});
    else if (q > 0 && fo.norm() > 0 && min_dot > options.loose_min_dot) out.loose.push_back({f, w + wv, wv, q});
  }
  auto order = [](const DualCandidate& x, const DualCandidate& y) {
    if (x.witnesses != y.witnesses) return x.witnesses > y.witnesses;
    if (x.quality != y.quality) return x.quality > y.quality;
    return x.f < y.f;
  };
  std::stable_sort(out.coherent.begin(), out.coherent.end(), order);
  std::stable_sort(out.loose.begin(), out.loose.end(), order);
  return out;
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Delaunay = CGAL::Delaunay_triangulation_2<
    Kernel, CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>>>;

// The triangles at site i of the Delaunay triangulation of i and its compatible neighbours in
// i's tangent plane, as sorted vertex triples.
std::vector<MeshFace> site_star(const WorkingMesh& mesh, int i, const Eigen::MatrixXi& knn, const StarCandidateOptions& o) {
  const Eigen::Vector3d p = mesh.V.row(i).transpose(), n = mesh.N.row(i).transpose();
  std::vector<MeshFace> out;
  if (!(n.norm() > 0)) return out;
  const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
  std::vector<std::pair<Kernel::Point_2, int>> pts = {{Kernel::Point_2(0, 0), i}};
  for (Eigen::Index q = 0; q < knn.cols(); ++q) {
    const int j = knn(i, q);
    if (j == i || mesh.N.row(j).dot(n) < o.min_normal_dot) continue;
    const Eigen::Vector3d d = mesh.V.row(j).transpose() - p;
    pts.push_back({Kernel::Point_2(d.dot(u), d.dot(w)), j});
  }
  if (pts.size() < 3) return out;
  Delaunay dt;
  dt.insert(pts.begin(), pts.end());
  Delaunay::Vertex_handle centre;
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v)
    if (v->info() == i) centre = v;
  if (centre == Delaunay::Vertex_handle()) return out;
  Delaunay::Face_circulator f = dt.incident_faces(centre), end = f;
  if (f == nullptr) return out;
  do {
    if (!dt.is_infinite(f)) {
      MeshFace t = {f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
      std::sort(t.begin(), t.end());
      out.push_back(t);
    }
  } while (++f != end);
  return out;
}

}  // namespace

std::vector<DualCandidate> star_candidates(const WorkingMesh& mesh, const StarCandidateOptions& options,
                                           const DualCandidateOptions& coherence, int threads) {
  const int ns = mesh.num_vertices();
  const int k = std::min(options.neighbors, ns - 1);
  if (!options.enabled || k < 2) return {};
  const Eigen::MatrixXi knn = k_nearest_neighbors(mesh.V, k, threads);
  // Normals at the sites' own scale: the plane of each site and its nearest sites, turned to the
  // side of the site's normal. Noise and depth steps below the site spacing do not tilt it.
  WorkingMesh sites(mesh.V, estimate_normals(mesh.V, knn, threads), mesh.anchor);
  for (int i = 0; i < ns; ++i)
    if (sites.N.row(i).dot(mesh.N.row(i)) < 0) sites.N.row(i) *= -1;
  std::vector<std::vector<MeshFace>> stars(ns);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 64)
  for (int i = 0; i < ns; ++i) stars[i] = site_star(sites, i, knn, options);
  std::vector<MeshFace> all;
  for (const auto& s : stars) all.insert(all.end(), s.begin(), s.end());
  std::sort(all.begin(), all.end());
  return classify(all, {}, sites, coherence).coherent;
}

std::vector<int> cell_labels(const VoronoiDiagram& D, int num_points) {
  std::vector<int> label(num_points, -1);
  for (Eigen::Index r = 0; r < D.F.rows(); ++r)
    for (int k = 0; k < 3; ++k) {
      const int v = D.F(r, k);
      if (v < num_points && label[v] < 0) label[v] = D.face_cell[r];
    }
  return label;
}

DualCandidates dual_candidates(const Eigen::MatrixX3i& T, const std::vector<int>& label, const VoronoiDiagram& D,
                               const WorkingMesh& mesh, const DualCandidateOptions& options) {
  std::vector<MeshFace> cand;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    MeshFace l = {label[T(t, 0)], label[T(t, 1)], label[T(t, 2)]};
    if (l[0] < 0 || l[1] < 0 || l[2] < 0 || l[0] == l[1] || l[1] == l[2] || l[0] == l[2]) continue;
    std::sort(l.begin(), l.end());
    cand.push_back(l);
  }
  // Voronoi vertices of the exact tessellation (three or more cells meeting inside / on a point
  // triangle) witness their triples too; where > 3 cells meet every triple is a candidate and the
  // greedy extraction picks a consistent subset.
  std::vector<MeshFace> cand_vv;
  for (const VoronoiVertex& vv : D.voronoi_vertices) {
    const auto& c = vv.cells;
    if (static_cast<int>(c.size()) > options.max_cells_per_voronoi_vertex) continue;
    for (size_t x = 0; x < c.size(); ++x)
      for (size_t y = x + 1; y < c.size(); ++y)
        for (size_t z = y + 1; z < c.size(); ++z) {
          MeshFace t = {c[x], c[y], c[z]};
          std::sort(t.begin(), t.end());
          cand_vv.push_back(t);
        }
  }
  std::sort(cand.begin(), cand.end());
  std::sort(cand_vv.begin(), cand_vv.end());
  DualCandidates out = classify(cand, cand_vv, mesh, options);
  out.star = star_candidates(mesh, options.stars, options, options.threads);
  return out;
}

DualCandidates dual_candidates_from_faces(const Eigen::MatrixX3i& F, const WorkingMesh& mesh,
                                          const DualCandidateOptions& options) {
  std::vector<MeshFace> cand;
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    MeshFace l = {F(t, 0), F(t, 1), F(t, 2)};
    if (l[0] == l[1] || l[1] == l[2] || l[0] == l[2]) continue;
    std::sort(l.begin(), l.end());
    cand.push_back(l);
  }
  std::sort(cand.begin(), cand.end());
  DualCandidates out = classify(cand, {}, mesh, options);
  out.star = star_candidates(mesh, options.stars, options, options.threads);
  return out;
}

}  // namespace heatcvt
