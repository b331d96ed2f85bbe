// Index sets of the Lloyd iterations (paper §6–7.1: a site's Voronoi diffusion is localized to its
// cell and neighbouring cells). Sites that have settled, together with their neighbours, use one
// ring of cells instead of two; the cells must be those of the two-ring diffusion.
#include <gtest/gtest.h>

#include <cmath>

#include "heatcvt/cvt.h"
#include "heatcvt/laplacian.h"
#include "test_support.h"

using namespace heatcvt;

TEST(CvtLocalization, SettledSitesWithOneRingGiveTheCellsOfTwoRings) {
  const test::UnitSphere unit = test::unit_area_sphere(5);
  const TriangleMesh& sphere = unit.mesh;
  const Laplacian& lap = unit.laplacian;
  CvtOptions o;
  o.sites = 300;
  o.iterations = 15;
  o.seed = 7;
  o.relaxation = 1.5;  // keeps a few sites travelling: the per-site rule matters, the global one not
  o.voronoi_rings_settled = 2;
  const CvtResult two = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  o.voronoi_rings_settled = 1;
  const CvtResult one = centroidal_voronoi(sphere.V, sphere.F, lap, o);
  ASSERT_EQ(two.iterations.size(), one.iterations.size());
  // The one-ring run really used smaller index sets once sites settled.
  EXPECT_LT(one.iterations.back().mean_index_set, 0.8 * two.iterations.back().mean_index_set);
  // Same sites up to the truncation of the heat outside one ring (measured: 0.15 % of the spacing
  // after 15 iterations) ...
  const double spacing = std::sqrt(1.0 / o.sites);
  const double max_site_difference = (one.positions - two.positions).rowwise().norm().maxCoeff();
  std::printf("[ info ] mean |I| two rings %.0f, one ring when settled %.0f; max site difference %.3g spacing\n",
              two.iterations.back().mean_index_set, one.iterations.back().mean_index_set,
              max_site_difference / spacing);
  EXPECT_LT(max_site_difference, 1e-2 * spacing);
  // ... and the same cells: the same neighbours, areas within 1 % (measured 0.5 %).
  ASSERT_EQ(one.diagram.num_cells(), two.diagram.num_cells());
  int differing = 0;
  for (int c = 0; c < one.diagram.num_cells(); ++c) differing += one.diagram.cell_adjacency[c] != two.diagram.cell_adjacency[c];
  EXPECT_EQ(differing, 0);
  EXPECT_LT((one.diagram.cell_area - two.diagram.cell_area).cwiseAbs().maxCoeff(), 1e-2 * two.diagram.cell_area.mean());
  EXPECT_NEAR(one.final_area_variance, two.final_area_variance, 1e-3 * two.final_area_variance);
}
