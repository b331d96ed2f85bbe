// The border of open scans: border_fit() measures how far a mesh's border is from the edge of the
// samples; the relaxation's border vertices follow that edge (RelaxationBorder::
// follow_sample_border) and the angle polish moves them within a band along it
// (AnglePolishOptions::sample_border_band); and reconstruct_surface() on open shapes sampled in code gives a mesh
// whose border lies within one site spacing of the scan's edge, with the quality targets met.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/angle_polish.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/tangential_relaxation.h"
#include "heatcvt/mesher/working_mesh.h"
#include "heatcvt/normals.h"
#include "heatcvt/reconstruct.h"
#include "heatcvt/sample_border.h"
#include "heatcvt/validate.h"
#include "open_shapes.h"
#include "test_support.h"

namespace heatcvt {
namespace {

using test::jittered_grid;
using test::up_normals;

TEST(BorderFit, AMeshOnTheScanIsOnItsEdgeAndAnInsetOneIsNot) {
  const Eigen::MatrixX3d P = jittered_grid(40);
  const std::vector<char> on_border = sample_border_points(P, up_normals(P.rows()), k_nearest_neighbors(P, 16));
  // The mesh over the whole scanned square: every edge point within a unit of it and back.
  const BorderFit full = border_fit(P, on_border, test::grid(39, 0, 39, 0, 39), 1.0);
  EXPECT_GE(full.edge_points, 156);
  EXPECT_EQ(full.edge_covered, 1.0);
  EXPECT_LE(full.edge_distance, 0.5);
  EXPECT_EQ(full.mesh_border_vertices, 4 * 39);
  EXPECT_EQ(full.mesh_border_on_edge, 1.0);
  EXPECT_LE(full.mesh_border_distance, 0.5);
  // The same mesh drawn in by 3 units on every side: no edge point within a unit of it, in units
  // of 1 (3 units away, less the jitter and the border band's width) and of 4 (within one).
  const TriangleMesh inset = test::grid(33, 3, 36, 3, 36);
  const BorderFit far = border_fit(P, on_border, inset, 1.0);
  EXPECT_EQ(far.edge_covered, 0.0);
  EXPECT_GE(far.edge_distance, 2.5);
  EXPECT_EQ(far.mesh_border_on_edge, 0.0);
  EXPECT_GE(far.mesh_border_distance, 1.5);
  const BorderFit coarse = border_fit(P, on_border, inset, 4.0);
  EXPECT_GT(coarse.mesh_border_on_edge, 0.9);
  EXPECT_LE(coarse.mesh_border_distance, 1.0);
  EXPECT_THROW(border_fit(P, on_border, inset, 0.0), InvalidInputError);
  EXPECT_THROW(border_fit(P, std::vector<char>(3, 1), inset, 1.0), InvalidInputError);
}

// Largest distance from a border vertex of `mesh` to the samples' border.
double worst_border_gap(const WorkingMesh& mesh, const SurfaceProjector& surface) {
  const BorderLinks links = border_links(mesh);
  double worst = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (links.on(v)) worst = std::max(worst, surface.distance_to_sample_border(mesh.V.row(v).transpose()));
  return worst;
}

TEST(BorderFit, RelaxedBorderVerticesFollowTheEdgeOfTheSamplesInsteadOfBeingDrawnIn) {
  const Eigen::MatrixX3d P = jittered_grid(61);
  const CloudSurfaceProjector surface(P, up_normals(P.rows()));
  // A mesh of the scanned square with edges of 4 units, its border on the outermost points.
  const TriangleMesh start = test::grid(15, 0, 60, 0, 60);
  const double before = worst_border_gap(test::working_mesh(start), surface);
  ASSERT_LE(before, 0.5);
  auto relaxed = [&](bool follow) {
    WorkingMesh mesh = test::working_mesh(start);
    RelaxationBorder border;
    border.follow_sample_border = follow;
    for (int it = 0; it < 10; ++it) tangential_relaxation(mesh, surface, 0, border);
    return mesh;
  };
  // Precondition: border vertices moved towards their ring's centroid leave the edge.
  const WorkingMesh drawn_in = relaxed(false);
  ASSERT_GT(worst_border_gap(drawn_in, surface), 1.5);
  const WorkingMesh followed = relaxed(true);
  EXPECT_LE(worst_border_gap(followed, surface), 1.0);
  // The corners stay, and the sides within a quarter of an edge of their straight course.
  const BorderLinks links = border_links(followed);
  for (int v = 0; v < followed.num_vertices(); ++v) {
    if (!links.on(v)) continue;
    const Eigen::Vector3d x = followed.V.row(v).transpose(), x0 = start.V.row(v).transpose();
    const bool corner = (x0.x() == 0 || x0.x() == 60) && (x0.y() == 0 || x0.y() == 60);
    if (corner) {
      EXPECT_LT((x - x0).norm(), 1e-9) << "corner " << v;
    } else {
      const double off = std::min({std::abs(x.x()), std::abs(x.x() - 60), std::abs(x.y()), std::abs(x.y() - 60)});
      EXPECT_LE(off, 1.0) << "border vertex " << v << " at " << x.transpose();
    }
  }
  // Same result for any thread count.
  WorkingMesh one = test::working_mesh(start);
  RelaxationBorder border;
  border.follow_sample_border = true;
  for (int it = 0; it < 10; ++it) tangential_relaxation(one, surface, 1, border);
  EXPECT_EQ(one.V, followed.V);
}

// Smallest angle of the triangles around vertex v.
double ring_min_angle(const WorkingMesh& mesh, int v) {
  double smallest = M_PI;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const MeshFace& face = mesh.face(f);
    if (face[0] == v || face[1] == v || face[2] == v) smallest = std::min(smallest, face_min_angle(mesh, face));
  }
  return smallest;
}

TEST(BorderFit, TheAnglePolishMovesABorderVertexOffItsChordWithinTheBandAlongTheScansEdge) {
  const Eigen::MatrixX3d P = jittered_grid(61);
  const CloudSurfaceProjector surface(P, up_normals(P.rows()));
  // A mesh of the scanned square with edges of 4 units; one vertex of its lower side pushed 1.5
  // units in, so that the border turns by 41° there and its triangles are squeezed.
  WorkingMesh start = test::working_mesh(test::grid(15, 0, 60, 0, 60));
  int v = -1;
  for (int i = 0; i < start.num_vertices(); ++i)
    if (start.V(i, 0) == 28 && start.V(i, 1) == 0) v = i;
  ASSERT_GE(v, 0);
  start.V(v, 1) = 1.5;
  const double before = ring_min_angle(start, v);
  const std::vector<char> frozen(start.num_vertices(), 0);
  auto polished = [&](double band) {
    WorkingMesh mesh = start;
    AnglePolishOptions o;
    o.sample_border_band = band;
    angle_polish(mesh, surface, 4, frozen, o, 0);
    return mesh;
  };
  // Precondition: moving along its border chord only, where the border turns by more than
  // max_boundary_turn_deg, the vertex stays.
  const WorkingMesh chord = polished(0);
  ASSERT_EQ(chord.V.row(v), start.V.row(v));
  // Within the band: its triangles open up and it stays within one mean edge length (4) of the
  // scan's edge.
  const WorkingMesh band = polished(AnglePolishOptions().sample_border_band);
  EXPECT_GT(ring_min_angle(band, v), before + 10 * M_PI / 180);
  EXPECT_LE(surface.distance_to_sample_border(band.V.row(v).transpose()), 4.0);
  // The same for any thread count.
  WorkingMesh one = start;
  angle_polish(one, surface, 4, frozen, AnglePolishOptions(), 1);
  EXPECT_EQ(one.V, band.V);
}

struct OpenRun {
  BorderFit fit;
  TriangleQuality quality;
  ValidationReport validation;
};

OpenRun reconstruct_open(const Eigen::MatrixX3d& P, int sites, bool follow) {
  ReconstructionOptions o;
  o.sites = sites;
  o.mesher.polish.follow_sample_border = follow;
  const ReconstructionResult r = reconstruct_surface(P, o);
  const Eigen::MatrixXi knn = k_nearest_neighbors(P, 30);
  const std::vector<char> on_border = sample_border_points(P, estimate_normals(P, knn), knn);
  ValidationOptions vo;
  vo.require_closed = false;
  return {border_fit(P, on_border, r.mesh, mean_edge_length(r.mesh.V, r.mesh.F)), triangle_quality(r.mesh.V, r.mesh.F),
          validate_triangle_mesh(r.mesh.V, r.mesh.F, vo)};
}

// The rule, for every shape and count: 90 % of the scan's edge points within one site spacing
// (the mesh's mean edge length) of the mesh, 90 % of the mesh's border vertices within one
// spacing of the scan's edge; a valid mesh with one boundary loop (two around the hole), the
// count within 2 %, φmin ≥ 25°, φm ≥ 52°.
TEST(BorderFit, ReconstructedOpenShapesReachTheScansEdge) {
  struct Case {
    const char* shape;
    int sites, loops;
  };
  // Precondition: without following the edge, the border of the disc is drawn in.
  const Eigen::MatrixX3d disc = test::open_shape_samples("disc", 20000, 1);
  ASSERT_GT(reconstruct_open(disc, 300, false).fit.mesh_border_distance, 1.0);
  for (const Case& c : {Case{"disc", 300, 1}, Case{"disc", 1000, 1}, Case{"saddle", 300, 1}, Case{"saddle", 1000, 1},
                        Case{"hemisphere", 300, 1}, Case{"hemisphere", 1000, 1}, Case{"square", 1000, 1},
                        Case{"square_with_hole", 1000, 2}}) {
    SCOPED_TRACE(std::string(c.shape) + " -n " + std::to_string(c.sites));
    const OpenRun r = reconstruct_open(test::open_shape_samples(c.shape, 20000, 1), c.sites, true);
    EXPECT_TRUE(r.validation.ok()) << r.validation.summary();
    EXPECT_EQ(r.validation.boundary_loops, c.loops);
    EXPECT_LE(std::abs(r.validation.vertices - c.sites), 0.02 * c.sites);
    EXPECT_GE(r.quality.min_angle_deg, 25.0);
    EXPECT_GE(r.quality.mean_min_angle_deg, 52.0);
    EXPECT_LE(r.fit.edge_distance, 1.0);
    EXPECT_LE(r.fit.mesh_border_distance, 1.0);
  }
}

}  // namespace
}  // namespace heatcvt
