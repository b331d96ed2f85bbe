// The border of a sampled surface (sample_border.h) and the hole filling's use of it
// (HoleFillingOptions::sample_border_clearance): holes the extraction leaves in sampled surface
// are closed under every policy, the edge of a scan is not. Shapes built in code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
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

// A noisy random sampling of a closed surface leaves, by chance, a gap wider than max_gap_deg at
// a few points round its voids; only chains of such points as long as an edge (border_chains())
// are the edge of a scan. Uniform random points on the unit sphere, radial noise of a tenth of
// their spacing, their PCA normals; then the half of them above z = 0.
TEST(SampleBorder, ChainsKeepTheEdgeOfAScanAndDropTheGapsOfANoisySampling) {
  const int n = 60000;
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  const double spacing = std::sqrt(4 * M_PI / n);
  Eigen::MatrixX3d P(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    P.row(i) = ((1 + 0.1 * spacing * g(rng)) * d).transpose();
  }
  const CloudFitOptions defaults;
  const int chain = defaults.scan_edge_chain, k = defaults.border.neighbors;
  const Eigen::MatrixXi knn = k_nearest_neighbors(P, k);
  const std::vector<char> gaps = sample_border_points(P, estimate_normals(P, knn), knn);
  ASSERT_GE(std::count(gaps.begin(), gaps.end(), 1), 3);  // the precondition: chance gaps exist
  const std::vector<char> edge = border_chains(gaps, knn, k, chain);
  EXPECT_EQ(std::count(edge.begin(), edge.end(), 1), 0);
  // The cut of the half-sphere is one chain: every point within a fifth of a spacing of it stays.
  std::vector<int> rows;
  for (int i = 0; i < n; ++i)
    if (P(i, 2) >= 0) rows.push_back(i);
  const Eigen::MatrixX3d H = P(rows, Eigen::all);
  const Eigen::MatrixXi hknn = k_nearest_neighbors(H, k);
  const std::vector<char> half = border_chains(sample_border_points(H, estimate_normals(H, hknn), hknn), hknn, k, chain);
  int at_cut = 0, kept = 0;
  for (int i = 0; i < static_cast<int>(H.rows()); ++i)
    if (H(i, 2) < 0.2 * spacing) ++at_cut, kept += half[i];
  ASSERT_GT(at_cut, 50);
  EXPECT_GE(kept, 0.95 * at_cut);
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
    for (HolePolicy policy : {HolePolicy::automatic, HolePolicy::keep})
      for (bool with_void : {false, true}) {
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
      // With a void of the sampling one edge length below the loop (the points within 1.2 edge
      // lengths of a point): the two points beside it have a gap but are no edge of the scan
      // (CloudFitOptions::scan_edge_chain).
      const double edge = (w.V.row(w.face(0)[0]) - w.V.row(w.face(0)[1])).norm();
      const double polar = 2 * std::asin(std::min(1.0, (loop_bottom + edge) / 2));
      const Eigen::RowVector3d void_centre(std::sin(polar), 0, std::cos(polar));
      std::vector<int> kept;
      for (int i = 0; i < fine.V.rows(); ++i)
        if ((sampled || (fine.V.row(i) - Eigen::RowVector3d(0, 0, 1)).norm() >= loop_bottom) &&
            !(with_void && (fine.V.row(i) - void_centre).norm() < 1.2 * edge))
          kept.push_back(i);
      const CloudSurfaceProjector surface(fine.V(kept, Eigen::all), fine_normals(kept, Eigen::all));
      if (with_void) {
        // The precondition: the void leaves border points near the loop, and counting every one
        // of them as the scan's edge leaves the hole open.
        ASSERT_LT(surface.distance_to_sample_border(void_centre.transpose()), 2 * edge);
        CloudFitOptions every_gap;
        every_gap.scan_edge_chain = 0;
        const CloudSurfaceProjector gaps(fine.V(kept, Eigen::all), fine_normals(kept, Eigen::all), every_gap);
        WorkingMesh copy = w;
        HoleFillingOptions o;
        o.policy = policy;
        int removed = 0;
        if (sampled) ASSERT_EQ(fill_holes(copy, gaps, o, {}, removed), 0);
      }
      HoleFillingOptions o;
      o.policy = policy;
      int removed = 0;
      EXPECT_EQ(fill_holes(w, surface, o, {}, removed), sampled ? 1 : 0) << "sampled " << sampled << " void " << with_void;
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
