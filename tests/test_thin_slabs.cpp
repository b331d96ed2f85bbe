// Thin slabs (PointLaplacianOptions::across_min_offset, CloudPreparationOptions::
// across_min_offset): the point Laplacian cuts the links between the two faces of a part about as
// thick as its neighbourhoods, and keeps the links of normals flipped within one sheet; and
// reconstruct_surface() on a closed plate thinner than a site spacing, where nearly every point
// has a neighbour on the other face.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cmath>
#include <random>

#include "heatcvt/mesh.h"
#include "heatcvt/point_laplacian.h"
#include "heatcvt/reconstruct.h"
#include "thin_scenes.h"

using namespace heatcvt;

namespace {

// Off-diagonal entries of L linking a point of the first `split` rows to one of the others.
long links_between(const Eigen::SparseMatrix<double>& L, int split) {
  long count = 0;
  for (int c = 0; c < L.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, c); it; ++it)
      count += it.value() != 0 && ((it.row() < split) != (it.col() < split));
  return count;
}

long off_diagonal_links(const Eigen::SparseMatrix<double>& L) {
  long count = 0;
  for (int c = 0; c < L.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, c); it; ++it) count += it.value() != 0 && it.row() != it.col();
  return count;
}

// An n × n jittered grid of spacing h at height z, with normals (0, 0, nz).
void add_sheet(int n, double h, double z, double nz, std::mt19937& rng, Eigen::MatrixX3d& P, Eigen::MatrixX3d& N,
               int& row) {
  std::uniform_real_distribution<double> jitter(-0.2 * h, 0.2 * h);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j, ++row) {
      P.row(row) << i * h + jitter(rng), j * h + jitter(rng), z;
      N.row(row) << 0, 0, nz;
    }
}

}  // namespace

TEST(ThinSlabs, TheTwoFacesOfASlabAreCutApartFlippedNormalsInOneSheetKeepTheirLinks) {
  const int n = 50;
  const double h = 0.02, t = 2 * h;  // the faces 2 spacings apart, inside 30 neighbours
  std::mt19937 rng(4);
  Eigen::MatrixX3d P(2 * n * n, 3), N(2 * n * n, 3);
  int row = 0;
  add_sheet(n, h, 0.0, -1.0, rng, P, N, row);
  add_sheet(n, h, t, 1.0, rng, P, N, row);
  PointLaplacianOptions o;
  o.k = 30;
  const long linked = links_between(point_laplacian(P, o).laplacian.L, n * n);
  ASSERT_GT(linked, 100) << "precondition: the faces are linked";
  o.oriented_normals = &N;
  o.across_min_offset = 0.5;
  const Eigen::SparseMatrix<double> L = point_laplacian(P, o).laplacian.L;
  // Only pairs less than 30° off the tangent plane may stay linked (at the sheets' edges, where
  // the neighbourhoods reach farther along them): a few against the faces' links without the rule.
  EXPECT_LE(links_between(L, n * n), linked / 20);
  for (int c = 0; c < L.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, c); it; ++it)
      if (it.value() != 0 && (it.row() < n * n) != (it.col() < n * n)) {
        const Eigen::RowVector3d d = P.row(it.row()) - P.row(it.col());
        EXPECT_LT(std::abs(d.z()), 0.5 * d.norm());
      }

  // One sheet whose normals are flipped at one point in ten (an orientation error).
  Eigen::MatrixX3d S(n * n, 3), SN(n * n, 3);
  row = 0;
  add_sheet(n, h, 0.0, 1.0, rng, S, SN, row);
  for (int i = 0; i < n * n; i += 10) SN(i, 2) = -1.0;
  PointLaplacianOptions plain;
  plain.k = 30;
  const long all = off_diagonal_links(point_laplacian(S, plain).laplacian.L);
  PointLaplacianOptions cut_all = plain;
  cut_all.oriented_normals = &SN;
  ASSERT_LT(off_diagonal_links(point_laplacian(S, cut_all).laplacian.L), all) << "precondition: offset 0 cuts them";
  PointLaplacianOptions in_plane = cut_all;
  in_plane.across_min_offset = 0.5;
  EXPECT_EQ(off_diagonal_links(point_laplacian(S, in_plane).laplacian.L), all);
}

// A closed plate 3 cm thick, 1 m across, 40,000 points (noise 0.5 mm), at -n 2000 (site spacing
// about 3.3 cm): nearly every point has a neighbour of opposite normal on the other face, so the
// 8 % rule (max_crossing_fraction) does not cut them; without the offset rule the mesh falls
// apart (with the run on finer sites turned off, which mends it another way). With it: one closed piece of genus 0 at the count with the shape targets.
TEST(ThinSlabs, AClosedPlateThinnerThanASiteSpacingIsOneClosedPiece) {
  const Eigen::MatrixX3d P = test::thin_plate(0.03, 40000, 0.0005);
  ReconstructionOptions options;
  options.sites = 2000;
  options.threads = 2;
  ReconstructionOptions off = options;
  off.cloud.across_min_offset = 0;
  off.finer_retry_factor = 1;  // the run on finer sites can mend it another way: test the rule alone
  const ReconstructionResult without = reconstruct_surface(P, off);
  const MeshTopology t0 = mesh_topology(without.mesh.F, static_cast<int>(without.mesh.V.rows()));
  ASSERT_TRUE(t0.components > 1 || t0.boundary_loops > 0) << "precondition: the plate falls apart without the rule";

  const ReconstructionResult with = reconstruct_surface(P, options);
  const MeshTopology t = mesh_topology(with.mesh.F, static_cast<int>(with.mesh.V.rows()));
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.euler_characteristic(), 2);  // closed, genus 0
  EXPECT_NEAR(static_cast<double>(with.mesh.V.rows()), options.sites, 0.02 * options.sites);
  EXPECT_GE(with.min_angle_deg, 25.0);
  EXPECT_GE(with.mean_min_angle_deg, 52.0);
  EXPECT_TRUE(with.validation.ok()) << with.validation.summary();
}
