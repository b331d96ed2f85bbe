// Neighbourhoods that span the surface (neighbour_spread.h): an isotropic sampling keeps k, the
// rings of a rotating lidar grow it until the neighbourhoods reach the next rings, a wire among a
// surface does not; thread independence; and reconstruct_surface() on a lidar's rings over a
// floor, which without the adjustment falls apart into ring-shaped cells and holes.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/neighbour_spread.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "virtual_scanner.h"

using namespace heatcvt;

namespace {

// A rotating lidar (virtual_scanner.h) 1.8 m above a floor: `beams` beams from 25° to 5° below the
// horizon, a return every `azimuth_deg`, range noise 5 mm. `ring` gets each return's beam.
Eigen::MatrixX3d lidar_floor(int beams, double azimuth_deg, std::vector<int>* ring = nullptr) {
  test::LidarOptions o;
  o.beams = beams;
  o.min_elevation_deg = -25;
  o.max_elevation_deg = -5;
  o.azimuth_step_deg = azimuth_deg;
  o.range_sigma = 0.005;
  const Eigen::MatrixX3d P = test::lidar_scan(test::lidar_scene("floor"), o, 1);
  if (ring)  // the beam of a return on the floor from its elevation seen from the sensor
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      const Eigen::Vector3d d = P.row(i).transpose() - o.origin;
      const double e = std::atan2(d.z(), std::hypot(d.x(), d.y())) * 180 / M_PI;
      ring->push_back(static_cast<int>(std::lround((e - o.min_elevation_deg) / (o.max_elevation_deg - o.min_elevation_deg) * (beams - 1))));
    }
  return P;
}

// Jittered grid samples of the unit square at z = 0, `n` by `n`.
Eigen::MatrixX3d jittered_square(int n) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3 / n, 0.3 / n);
  Eigen::MatrixX3d P(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) P.row(i * n + j) << (i + 0.5) / n + jitter(rng), (j + 0.5) / n + jitter(rng), 0.0;
  return P;
}

}  // namespace

TEST(NeighbourSpread, AnIsotropicSamplingKeepsK) {
  const Eigen::MatrixX3d square = jittered_square(120);
  EXPECT_LE(spanning_neighbours(square), 15);
  EXPECT_EQ(neighbours_for_spread(square, 30), 30);
  // A sphere sampled at random (area-uniform directions).
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  Eigen::MatrixX3d sphere(20000, 3);
  for (Eigen::Index i = 0; i < sphere.rows(); ++i) sphere.row(i) = Eigen::RowVector3d(g(rng), g(rng), g(rng)).normalized();
  EXPECT_EQ(neighbours_for_spread(sphere, 30), 30);
}

TEST(NeighbourSpread, RingsOfALidarGrowTheNeighbourhoodAcrossToTheNextRings) {
  std::vector<int> ring;
  const Eigen::MatrixX3d P = lidar_floor(24, 0.25, &ring);
  // Precondition: 30 neighbours stay on the point's own ring for most points.
  const Eigen::MatrixXi knn30 = k_nearest_neighbors(P, 30);
  auto share_reaching_other_rings = [&](const Eigen::MatrixXi& knn) {
    int reaching = 0;
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      std::set<int> rings_seen;
      for (Eigen::Index q = 0; q < knn.cols(); ++q) rings_seen.insert(ring[knn(i, q)]);
      reaching += rings_seen.size() >= 3 || (rings_seen.size() == 2 && (ring[i] == 0 || ring[i] == 23));
    }
    return static_cast<double>(reaching) / static_cast<double>(P.rows());
  };
  ASSERT_LT(share_reaching_other_rings(knn30), 0.5);
  const int k = neighbours_for_spread(P, 30);
  EXPECT_GT(k, 30);
  EXPECT_LE(k, NeighbourSpreadOptions{}.max_neighbors);
  // With k, nine points in ten see the rings on both sides of their own (one side at the first
  // and last ring).
  EXPECT_GE(share_reaching_other_rings(k_nearest_neighbors(P, k)), 0.9);
}

TEST(NeighbourSpread, AWireAlongASurfaceDoesNotGrowIt) {
  Eigen::MatrixX3d square = jittered_square(120);
  const int wire = 600;  // 4 % of the points on a line leaving the square
  Eigen::MatrixX3d P(square.rows() + wire, 3);
  P.topRows(square.rows()) = square;
  for (int i = 0; i < wire; ++i) P.row(square.rows() + i) << 1.0 + (i + 1) * 0.002, 0.5, 0.0;
  ASSERT_GT(spanning_neighbours(P.bottomRows(wire)), NeighbourSpreadOptions{}.max_neighbors);  // the wire alone never spans
  EXPECT_EQ(neighbours_for_spread(P, 30), 30);
}

TEST(NeighbourSpread, SameForAnyThreadCountAndOffWithFactorZero) {
  const Eigen::MatrixX3d P = lidar_floor(16, 0.3);
  const int one = neighbours_for_spread(P, 30, {}, 1);
  EXPECT_EQ(one, neighbours_for_spread(P, 30, {}, 2));
  EXPECT_EQ(one, neighbours_for_spread(P, 30, {}, 3));
  NeighbourSpreadOptions off;
  off.factor = 0;
  EXPECT_EQ(neighbours_for_spread(P, 30, off), 30);
  NeighbourSpreadOptions bad;
  bad.min_spread = 0;
  EXPECT_THROW(neighbours_for_spread(P, 30, bad), InvalidInputError);
  bad = {};
  bad.max_neighbors = 4;
  EXPECT_THROW(spanning_neighbours(P, bad), InvalidInputError);
}

// The floor seen by a 12-beam lidar (elevations 25°–5° below the horizon, a return every 0.4°):
// at -n 1000 the rings are up to about three site spacings apart at the far end and their
// returns 14 cm apart. With neighbourhoods of 30 points along the rings the mesh covers less than
// half the floor, in pieces; with the adjustment it is one piece at the count covering the
// annulus between the first ring and one site spacing inside the last (the blind circle under
// the scanner may be filled as a hole inside the scan: at most two loops).
TEST(NeighbourSpread, ALidarFloorIsMeshedInOnePiece) {
  const double height = test::LidarOptions{}.origin.z();
  const Eigen::MatrixX3d P = lidar_floor(12, 0.4);
  const double r_in = height / std::tan(25 * M_PI / 180), r_out = height / std::tan(5 * M_PI / 180);
  const double annulus = M_PI * (r_out * r_out - r_in * r_in);
  ReconstructionOptions options;
  options.sites = 1000;
  options.threads = 2;
  const double spacing = std::sqrt(annulus / options.sites);
  ReconstructionOptions off = options;
  off.cloud.spread.factor = 0;
  const ReconstructionResult without = reconstruct_surface(P, off);
  ASSERT_LT(surface_area(without.mesh.V, without.mesh.F), 0.6 * annulus) << "precondition: the rings alone break the floor";

  const ReconstructionResult with = reconstruct_surface(P, options);
  EXPECT_GT(with.neighbors_cvt, options.neighbors);
  const MeshTopology t = mesh_topology(with.mesh.F, static_cast<int>(with.mesh.V.rows()));
  EXPECT_EQ(t.components, 1);
  EXPECT_LE(t.boundary_loops, 2);
  EXPECT_NEAR(static_cast<double>(with.mesh.V.rows()), options.sites, 0.02 * options.sites);
  EXPECT_GE(with.min_angle_deg, 25.0);
  EXPECT_GE(with.mean_min_angle_deg, 52.0);
  EXPECT_TRUE(with.validation.ok()) << with.validation.summary();
  EXPECT_GE(surface_area(with.mesh.V, with.mesh.F), M_PI * ((r_out - spacing) * (r_out - spacing) - r_in * r_in));
}
