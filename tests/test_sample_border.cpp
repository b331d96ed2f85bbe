// The border of a sampled surface (sample_border.h) and the hole filling's use of it
// (HoleFillingOptions::sample_border_clearance): holes the extraction leaves in sampled surface
// are closed under every policy, the edge of a scan is not. Shapes built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "heatcvt/mesh.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/normals.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/validate.h"
#include "open_shapes.h"
#include "test_support.h"

namespace heatcvt {
namespace {

// A jittered n × n grid of points on z = 0 with spacing 1, normals +z.
void jittered_grid(int n, Eigen::MatrixX3d& P, Eigen::MatrixX3d& N) {
  P = test::jittered_grid(n);
  N = test::up_normals(P.rows());
}

TEST(SampleBorder, TheEdgeOfAPlanarScanAndNoPointOfAClosedOne) {
  Eigen::MatrixX3d P, N;
  jittered_grid(40, P, N);
  const std::vector<char> b = sample_border_points(P, N, k_nearest_neighbors(P, 16));
  // Every point of the outermost rows and columns is on the border, none two rows in or more.
  int edge = 0, edge_flagged = 0, inner_flagged = 0;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const bool on_edge = i == 0 || j == 0 || i == 39 || j == 39;
      const bool inner = i >= 2 && j >= 2 && i <= 37 && j <= 37;
      edge += on_edge;
      edge_flagged += on_edge && b[j * 40 + i];
      inner_flagged += inner && b[j * 40 + i];
    }
  EXPECT_EQ(edge, 156);
  EXPECT_EQ(edge_flagged, edge);
  EXPECT_EQ(inner_flagged, 0);
  // A sphere sampled all round (its vertex normals, and their opposites: the sign does not matter).
  const TriangleMesh s = test::icosphere(4);
  const Eigen::MatrixX3d SN = vertex_normals(s.V, s.F);
  const Eigen::MatrixXi knn = k_nearest_neighbors(s.V, 16);
  for (const Eigen::MatrixX3d& normals : {SN, Eigen::MatrixX3d(-SN)}) {
    const std::vector<char> none = sample_border_points(s.V, normals, knn);
    EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
  }
  // The same for any thread count.
  SampleBorderOptions one;
  one.threads = 1;
  EXPECT_EQ(sample_border_points(P, N, k_nearest_neighbors(P, 16), one), b);
}

// Boundary loops and their lengths.
std::vector<int> loop_lengths(const WorkingMesh& w) {
  std::map<int, int> next;
  for (const MeshFace& f : w.faces())
    for (int k = 0; k < 3; ++k)
      if (!w.has_half_edge(f[(k + 1) % 3], f[k])) next[f[k]] = f[(k + 1) % 3];
  std::vector<int> lengths;
  std::map<int, char> seen;
  for (const auto& [start, unused] : next) {
    if (seen[start]) continue;
    int L = 0;
    for (int v = start; !seen[v]; v = next.at(v)) seen[v] = 1, ++L;
    lengths.push_back(L);
  }
  return lengths;
}

TEST(HoleFilling, AHoleInSampledSurfaceIsClosedUnderEveryPolicyAndTheEdgeOfAScanIsNot) {
  // The working mesh of a sphere without its faces within 0.8 of the north pole: a loop longer
  // than any the auto policy's own tests take (surrounded_hole_factor · max_hole_edges). The
  // cloud is a finer sphere sampled all round (the extraction lost the cells there) or without
  // its points above the loop (the edge of the scan).
  const TriangleMesh coarse = test::icosphere(4), fine = test::icosphere(5);
  const Eigen::MatrixX3d fine_normals = vertex_normals(fine.V, fine.F);
  const HoleFillingOptions defaults;
  for (bool sampled : {true, false})
    for (HolePolicy policy : {HolePolicy::automatic, HolePolicy::keep}) {
      WorkingMesh cut = test::working_mesh(coarse);
      std::vector<char> drop(cut.num_faces(), 0);
      double loop_bottom = 1;
      for (int f = 0; f < cut.num_faces(); ++f)
        for (int v : cut.face(f)) drop[f] |= (cut.V.row(v) - Eigen::RowVector3d(0, 0, 1)).norm() < 0.8;
      cut.remove_faces(drop);
      WorkingMesh w = test::working_mesh(compact_mesh(cut));  // no site left inside the hole
      const std::vector<int> before = loop_lengths(w);
      ASSERT_EQ(before.size(), 1u);
      ASSERT_GT(before[0], defaults.surrounded_hole_factor * defaults.max_hole_edges);
      for (const MeshFace& f : w.faces())
        for (int v : f) loop_bottom = std::min(loop_bottom, (w.V.row(v) - Eigen::RowVector3d(0, 0, 1)).norm());
      std::vector<int> kept;
      for (int i = 0; i < fine.V.rows(); ++i)
        if (sampled || (fine.V.row(i) - Eigen::RowVector3d(0, 0, 1)).norm() >= loop_bottom) kept.push_back(i);
      const CloudSurfaceProjector surface(fine.V(kept, Eigen::all), fine_normals(kept, Eigen::all));
      HoleFillingOptions o;
      o.policy = policy;
      int removed = 0;
      EXPECT_EQ(fill_holes(w, surface, o, {}, removed), sampled ? 1 : 0) << "sampled " << sampled;
      const TriangleMesh m = compact_mesh(w);
      ValidationOptions vo;
      vo.require_closed = sampled;
      const ValidationReport r = validate_triangle_mesh(m.V, m.F, vo);
      EXPECT_TRUE(r.ok()) << r.summary();
      EXPECT_EQ(r.boundary_loops, sampled ? 0 : 1);
      EXPECT_EQ(r.genus, 0);
    }
}

}  // namespace
}  // namespace heatcvt
