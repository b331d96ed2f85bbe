// Candidate triangles of the dual of a surface Voronoi diagram.
#include "heatcvt/mesher/dual_candidates.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>

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

}  // namespace

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
  return classify(cand, cand_vv, mesh, options);
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
  return classify(cand, {}, mesh, options);
}

}  // namespace heatcvt
