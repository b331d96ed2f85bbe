#pragma once
/// \file surface_mesher.h
/// The surface mesher: the stages after the CVT, shared by the reconstruction from a point cloud
/// (the cloud's fitted surface as projector) and the remeshing of a triangle mesh (the input
/// mesh as projector). From dual candidate triangles to a valid, polished mesh:
/// manifold extraction → hole filling → untangling → relaxation polish → angle polish → sliver
/// collapse → long-edge split → small pieces removed → sizing to the vertex count asked for
/// (flying faces removed, isotropic remeshing; isotropic_remesh.h) → closed pieces outward →
/// compaction.
#include <Eigen/Core>

#include "heatcvt/mesh.h"
#include "heatcvt/mesher/border_growth.h"
#include "heatcvt/mesher/cancellation.h"
#include "heatcvt/mesher/compaction.h"
#include "heatcvt/mesher/dual_candidates.h"
#include "heatcvt/mesher/edge_split.h"
#include "heatcvt/mesher/hole_filling.h"
#include "heatcvt/mesher/isotropic_remesh.h"
#include "heatcvt/mesher/manifold_extraction.h"
#include "heatcvt/mesher/mesher_stats.h"
#include "heatcvt/mesher/orientation.h"
#include "heatcvt/mesher/polish.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/sliver_collapse.h"
#include "heatcvt/mesher/untangle.h"
#include "heatcvt/validate.h"

namespace heatcvt {

/// Options of every stage of the surface mesher, each with its documented defaults.
struct SurfaceMesherOptions {
  DualCandidateOptions candidates;
  ManifoldOptions manifold;
  HoleFillingOptions holes;
  UntangleOptions untangle;
  PolishOptions polish;  ///< polish.relaxation_iterations = 0 skips every polish stage
  BorderGrowthOptions borders;
  SliverCollapseOptions slivers;
  BoundaryTrimOptions boundary_slivers;
  EdgeSplitOptions split;
  /// Sizing to the vertex count asked for (isotropic remeshing where the dual left sites out or
  /// the shape targets are missed); sizing.target_vertices = 0 (the default) turns it off.
  IsotropicRemeshOptions sizing;
  /// Vertex-connected pieces with fewer faces are removed at the end. Default 20.
  int min_piece_faces = 20;
  /// ... and so are the stray pieces with fewer vertices than this fraction of the mesh's (bits of
  /// clutter, flying pixels, a few sites cut off at a depth jump); 0 keeps them
  /// (cloud2mesh --keep-small). Default 0.01.
  double min_piece_vertex_fraction = 0.01;
  /// Where the dual triangles given to mesh_dual_surface() form an oriented 2-manifold (every
  /// edge on at most two faces, once in each direction; a heat Voronoi diagram with the
  /// closed-ball property on an input mesh) and the extraction's result has other components,
  /// boundary loops or another Euler characteristic, the dual's own triangles replace that result before
  /// polish_extracted(). The extraction orients every triangle by its sites' normals and sets
  /// aside those whose normal is far from a site's (candidates.coherent_min_dot): the triangles
  /// that turn around a part thinner than the site spacing (an ear at 300 sites), which it then
  /// cuts off. Where it keeps the topology its result stays (it also mends the dual's shape at
  /// sharp creases). Default false (a cloud's dual is never trusted); meshcvt sets it.
  bool keep_manifold_dual = false;
  /// The topology to keep (remesh_cvt() sets the input mesh's: components, boundary loops, Euler
  /// characteristic): the hole filling after the extraction, each polish stage and the sizing's
  /// removal of flying faces are undone where they break it (breaks_topology()), and the sizing
  /// undoes and retries such steps (IsotropicRemeshOptions::keep_topology). The extraction may
  /// still close the dual's own holes, and small pieces are still removed. Not enabled by
  /// default (a cloud).
  TopologyTarget keep_topology;
  /// Where the sizing left faces crossing, untangle() takes them out and refills their holes;
  /// the slivers of those fills then get the best of their local edits that makes no faces
  /// cross (repair_slivers_without_crossings() with sizing.repair, the count kept within
  /// sizing.count_tolerance). Default true.
  bool repair_after_untangle = true;
  /// Worker threads of the parallel stages (overrides polish.threads and split.threads);
  /// 0 = all cores. Results do not depend on it. Default 0.
  int threads = 0;
  /// Asked after each stage and by the sizing (overrides sizing.cancelled): where it returns true
  /// the stages stop with StagesCancelled (mesher/cancellation.h; remesh_cvt() stops a run it
  /// started ahead on another thread once the run turns out unneeded). Default none.
  CancelQuery cancelled;
};

/// Runs the stages from manifold extraction to long-edge split on `mesh` (vertices = sites with
/// normals and projector anchors, no faces yet) with the candidates `candidates`, each stage
/// timed into stats.stage_seconds ("extraction and holes", "untangle", "relaxation polish",
/// "angle polish", "sliver collapse", "long-edge split").
void mesh_from_candidates(WorkingMesh& mesh, const DualCandidates& candidates, const SurfaceProjector& surface,
                          const SurfaceMesherOptions& options, MesherStats& stats);

/// The first stage of mesh_from_candidates(), timed as "extraction and holes": the manifold
/// extraction of the coherent candidates, the compatible candidates and stars added, holes filled.
void extract_from_candidates(WorkingMesh& mesh, const DualCandidates& candidates, const SurfaceProjector& surface,
                             const SurfaceMesherOptions& options, MesherStats& stats);

/// The stages of mesh_from_candidates() after the extraction and hole filling, from the border
/// growth to the long-edge split, on a mesh that has its faces.
void polish_extracted(WorkingMesh& mesh, const SurfaceProjector& surface, const SurfaceMesherOptions& options,
                      MesherStats& stats);

/// Removes the small pieces, sizes the rest to options.sizing.target_vertices (size_to_target(),
/// stage "sizing"), takes out faces the sizing left crossing and refills their holes (untangle()
/// without its regrowing rounds, "untangle after sizing"), turns closed pieces outward and
/// compacts ("compact").
/// \throw Error when no face is left.
TriangleMesh finish_mesh(WorkingMesh& mesh, const SurfaceProjector& surface, const SurfaceMesherOptions& options,
                         MesherStats& stats);

/// Result of mesh_dual_surface().
struct DualSurfaceResult {
  TriangleMesh mesh;            ///< the repaired, polished surface
  ValidationReport validation;  ///< validate_triangle_mesh() of `mesh` (require_closed = false)
  MesherStats stats;            ///< counts and stage_seconds ("sites", the stages above, "compact", "validate")
};

/// The post-CVT stages on a dual triangulation: `sites` (#S by 3, e.g. CvtResult::dual.V) are
/// projected to `surface` (positions and normals), the triangles of `dual_faces` (#F by 3 site
/// indices, e.g. CvtResult::dual.F) are the candidates (dual_candidates_from_faces()), then
/// mesh_from_candidates() (with options.keep_manifold_dual, the faces themselves where the
/// extraction changed their topology) and finish_mesh().
/// \note The defaults are the reconstruction's. Two of them trade the vertex count and thin parts
/// for robustness on noisy clouds: candidates.coherent_min_dot = 0.25 drops dual triangles whose
/// normal is more than about 75° from a site's normal, which on a coarse dual of a thin handle
/// (elephant.off at 1,000 sites) removes the handle, where −0.3 keeps it; valence-3 removal
/// (polish.valence3, slivers.valence3; passes = 0 turns it off) drops the sites of tiny cells
/// (about 3 % of the sites on that dual), which lowers the vertex count below the site count.
/// \throw InvalidInputError on an index out of range or a non-finite site; Error when no face is
/// left; StagesCancelled where options.cancelled says so.
DualSurfaceResult mesh_dual_surface(const Eigen::MatrixX3d& sites, const Eigen::MatrixX3i& dual_faces,
                                    const SurfaceProjector& surface, const SurfaceMesherOptions& options = {});

}  // namespace heatcvt
