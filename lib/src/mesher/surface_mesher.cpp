// The surface mesher's driver: the post-CVT stages in order, each timed.
#include "heatcvt/mesher/surface_mesher.h"

#include <chrono>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/sliver_repair.h"
#include "heatcvt/mesher/untangle.h"

namespace heatcvt {
namespace {

using Clock = std::chrono::steady_clock;

// Times consecutive stages into stats.stage_seconds; after each one, throws StagesCancelled where
// `cancelled` (SurfaceMesherOptions::cancelled) says the result is no longer needed.
class StageTimer {
 public:
  StageTimer(MesherStats& stats, const CancelQuery& cancelled)
      : stats_(stats), cancelled_(cancelled), t_(Clock::now()) {}
  void done(const char* name) {
    const auto now = Clock::now();
    stats_.stage_seconds.emplace_back(name, std::chrono::duration<double>(now - t_).count());
    t_ = now;
    throw_if_cancelled(cancelled_);
  }

 private:
  MesherStats& stats_;
  const CancelQuery& cancelled_;
  Clock::time_point t_;
};

// Runs stages on `mesh` and undoes one (mesh and counters) where it breaks the topology to keep
// (breaks_topology(), SurfaceMesherOptions::keep_topology); without a target it only runs them.
class TopologyGuard {
 public:
  TopologyGuard(WorkingMesh& mesh, const TopologyTarget& keep, MesherStats& stats)
      : mesh_(mesh), keep_(keep), stats_(stats) {}
  template <class Stage>
  void run(Stage stage) const {
    if (!keep_.enabled()) {
      stage();
      return;
    }
    const TopologyTarget before = topology_of(mesh_);
    const WorkingMesh::Checkpoint checkpoint = mesh_.checkpoint();
    const MesherStats stats = stats_;
    stage();
    if (!breaks_topology(keep_, before, topology_of(mesh_))) return;
    mesh_.rollback(checkpoint);
    std::vector<std::pair<std::string, double>> seconds = std::move(stats_.stage_seconds);
    stats_ = stats;
    stats_.stage_seconds = std::move(seconds);
  }

 private:
  WorkingMesh& mesh_;
  const TopologyTarget keep_;
  MesherStats& stats_;
};

// Whether the boundary loops of `extracted` and of `dual` (labels of boundary_loop_labels() over
// the same vertices) correspond one to one: each extracted loop shares vertices with exactly one of
// the dual's, and no two with the same. Equal counts can hide a cut and a join (an ear cut open
// while two holes near each other merge): the extracted loop of the cut shares no vertex with the
// dual's border, the joined one shares vertices with two of its loops.
bool loops_correspond(const Eigen::VectorXi& extracted, const Eigen::VectorXi& dual) {
  std::map<int, std::set<int>> touched;  // extracted loop -> the dual's loops it shares vertices with
  for (Eigen::Index v = 0; v < extracted.size(); ++v)
    if (extracted[v] >= 0) {
      std::set<int>& t = touched[extracted[v]];
      if (dual[v] >= 0) t.insert(dual[v]);
    }
  std::set<int> used;
  for (const auto& [loop, t] : touched)
    if (t.size() != 1 || !used.insert(*t.begin()).second) return false;
  return true;
}

// Whether the dual triangles F form an oriented 2-manifold (every edge on at most two faces,
// once in each direction) whose components, boundary loops or Euler characteristic the extraction's
// result `mesh` does not have, or whose loops its loops do not match (loops_correspond()): it cut
// or closed the surface (an ear thinner than a cell cut off).
bool changes_topology(const WorkingMesh& mesh, const Eigen::MatrixX3i& F) {
  const MeshTopology dual = mesh_topology(F, mesh.num_vertices());
  if (F.rows() == 0 || dual.nonmanifold_edges > 0 || dual.inconsistent_edges > 0) return false;
  Eigen::MatrixX3i E(mesh.num_faces(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) E(f, k) = mesh.face(f)[k];
  const MeshTopology extracted = mesh_topology(E, mesh.num_vertices());
  if (extracted.components != dual.components || extracted.boundary_loops != dual.boundary_loops ||
      extracted.euler_characteristic() != dual.euler_characteristic())
    return true;
  Eigen::VectorXi extracted_loops, dual_loops;
  boundary_loop_labels(mesh.num_vertices(), E, extracted_loops);
  boundary_loop_labels(mesh.num_vertices(), F, dual_loops);
  return !loops_correspond(extracted_loops, dual_loops);
}

}  // namespace

void extract_from_candidates(WorkingMesh& mesh, const DualCandidates& candidates, const SurfaceProjector& surface,
                             const SurfaceMesherOptions& options, MesherStats& stats) {
  StageTimer timer(stats, options.cancelled);
  stats.candidate_triangles = static_cast<int>(candidates.coherent.size());
  stats.rejected_triangles += extract_manifold(mesh, candidates.coherent);
  stats.removed_triangles += make_vertices_manifold(mesh, options.manifold);
  stats.rejected_triangles -= add_compatible_candidates(mesh, candidates.coherent, {});
  stats.star_triangles += add_compatible_candidates(mesh, candidates.star, candidates.loose);
  stats.holes_filled +=
      fill_holes(mesh, surface, options.holes, options.manifold, stats.removed_triangles, &stats.filled_hole_edges);
  timer.done("extraction and holes");
}

void mesh_from_candidates(WorkingMesh& mesh, const DualCandidates& candidates, const SurfaceProjector& surface,
                          const SurfaceMesherOptions& options, MesherStats& stats) {
  extract_from_candidates(mesh, candidates, surface, options, stats);
  polish_extracted(mesh, surface, options, stats);
}

void polish_extracted(WorkingMesh& mesh, const SurfaceProjector& surface, const SurfaceMesherOptions& options,
                      MesherStats& stats) {
  PolishOptions polish = options.polish;
  polish.threads = options.threads;
  EdgeSplitOptions split = options.split;
  split.threads = options.threads;
  StageTimer timer(stats, options.cancelled);
  BorderGrowthOptions borders = options.borders;
  borders.threads = options.threads;
  const TopologyGuard guard(mesh, options.keep_topology, stats);
  guard.run([&] {
    stats.border_triangles += grow_borders(mesh, borders);
    stats.holes_filled +=
        fill_holes(mesh, surface, options.holes, options.manifold, stats.removed_triangles, &stats.filled_hole_edges);
  });
  timer.done("border growth");
  untangle(mesh, surface, options.untangle, options.holes, options.manifold, stats);
  timer.done("untangle");
  guard.run([&] { relaxation_polish(mesh, surface, polish, options.untangle, options.holes, options.manifold, stats); });
  timer.done("relaxation polish");
  const bool polishing = polish.relaxation_iterations > 0;
  guard.run([&] {
    // Slivers flat along the border first: the angle polish then moves the vertices they expose.
    if (polishing) stats.trimmed_faces += trim_boundary_slivers(mesh, options.boundary_slivers);
    angle_polish_stage(mesh, surface, polish, stats);
  });
  timer.done("angle polish");
  guard.run([&] {
    if (polishing) stats.collapsed_edges = collapse_slivers(mesh, surface, options.slivers, stats);
  });
  timer.done("sliver collapse");
  guard.run([&] {
    if (polishing) stats.split_edges = split_long_edges(mesh, surface, split, stats);
  });
  timer.done("long-edge split");
  guard.run([&] {
    if (polishing) stats.trimmed_faces += trim_boundary_slivers(mesh, options.boundary_slivers);
  });
  timer.done("boundary sliver trim");
}

namespace {

// The sizing stage: where it remeshes (sizing_reshapes()), flying faces removed with the small
// pieces they cut off (so that the count is shared among the pieces that stay), then
// size_to_target() (again without following the samples' border where that is refused). Where
// the sizing is then needed but refused (it would be worse on a target), the mesh is left as it
// came, flying faces and all.
bool size_mesh(WorkingMesh& mesh, const SurfaceProjector& surface, const SurfaceMesherOptions& options,
               MesherStats& stats) {
  IsotropicRemeshOptions sizing = options.sizing;
  sizing.threads = options.threads;
  sizing.cancelled = options.cancelled;
  sizing.keep_topology = options.keep_topology;
  sizing.min_piece_faces = options.min_piece_faces;
  sizing.min_piece_vertex_fraction = options.min_piece_vertex_fraction;
  // The hole policy decides what the sizing may open or close: no flying face is removed where a
  // watertight mesh is asked for, no notch closed where no surface may be invented.
  if (options.holes.policy == HolePolicy::fill) sizing.remove_flying = sizing.cut_unrepairable = false;
  if (options.holes.policy == HolePolicy::keep) sizing.fill_notches = false;
  if (!needs_sizing(mesh, surface, sizing)) return false;
  const WorkingMesh::Checkpoint unsized = mesh.checkpoint();
  const MesherStats stats_unsized = stats;
  if (sizing.remove_flying && sizing_reshapes(mesh, surface, sizing)) {
    TopologyGuard(mesh, options.keep_topology, stats).run([&] {
      stats.flying_faces += remove_flying_faces(mesh, surface, sizing);
      stats.removed_triangles += remove_small_pieces(mesh, options.min_piece_faces, options.min_piece_vertex_fraction,
                                                     &stats.pieces_removed);
    });
  }
  if (size_to_target(mesh, surface, sizing, stats)) return true;
  // Border vertices held to the samples' border constrain the remeshing; where its result is
  // refused, it is tried once more with the border free to slide along its own course.
  if (sizing.follow_sample_border) {
    sizing.follow_sample_border = false;
    if (size_to_target(mesh, surface, sizing, stats)) return true;
  }
  if (needs_sizing(mesh, surface, sizing) && stats.flying_faces > stats_unsized.flying_faces) {
    mesh.rollback(unsized);
    stats = stats_unsized;
  }
  return false;
}

}  // namespace

TriangleMesh finish_mesh(WorkingMesh& mesh, const SurfaceProjector& surface, const SurfaceMesherOptions& options,
                         MesherStats& stats) {
  StageTimer timer(stats, options.cancelled);
  stats.removed_triangles +=
      remove_small_pieces(mesh, options.min_piece_faces, options.min_piece_vertex_fraction, &stats.pieces_removed);
  stats.sized = size_mesh(mesh, surface, options, stats);
  timer.done("sizing");
  // The sizing checks its own edits, but where it remeshed a dual that kept few of its sites
  // (a cloud far sparser than -n asks for), faces may still cross: untangle()'s last step takes
  // them out and refills the holes where the fill crosses nothing. No rounds that regrow borders:
  // they would put the sites the sizing left out back into the mesh, off the count.
  stats.crossing_after_sizing = self_intersecting_pairs(mesh);
  if (stats.crossing_after_sizing > 0) {
    UntangleOptions last_step = options.untangle;
    last_step.rounds = 0;
    untangle(mesh, surface, last_step, options.holes, options.manifold, stats);
    // The refilled holes may hold slivers, with no polish after them: the sizing's last repair,
    // its edits checked against the pairs crossing now, the count kept within its tolerance.
    if (options.repair_after_untangle)
      repair_slivers_without_crossings(mesh, surface, options.sizing.repair, std::vector<char>(mesh.num_vertices(), 0),
                                       count_floor(options.sizing), crossing_face_pairs(mesh));
  }
  timer.done("untangle after sizing");
  stats.faces_turned_outward += orient_closed_pieces_outward(mesh);
  if (mesh.empty())
    throw Error("surface mesher: no triangle could be extracted from the dual of " +
                std::to_string(mesh.num_vertices()) + " sites");
  TriangleMesh out = compact_mesh(mesh, &stats.unused_vertices);
  timer.done("compact");
  return out;
}

DualSurfaceResult mesh_dual_surface(const Eigen::MatrixX3d& sites, const Eigen::MatrixX3i& dual_faces,
                                    const SurfaceProjector& surface, const SurfaceMesherOptions& options) {
  DualSurfaceResult out;
  StageTimer timer(out.stats, options.cancelled);
  const int ns = static_cast<int>(sites.rows());
  if (!sites.allFinite()) throw InvalidInputError("mesh_dual_surface: a site has a NaN or infinite coordinate");
  if (dual_faces.size() > 0 && (dual_faces.minCoeff() < 0 || dual_faces.maxCoeff() >= ns))
    throw InvalidInputError("mesh_dual_surface: a face refers to a site out of range");
  WorkingMesh mesh(sites, Eigen::MatrixX3d::Zero(ns, 3), std::vector<int>(ns, -1));
  for (int s = 0; s < ns; ++s) {
    Eigen::Vector3d pos, nrm;
    surface.project(sites.row(s).transpose(), mesh.anchor[s], pos, nrm);
    mesh.V.row(s) = pos.transpose();
    mesh.N.row(s) = nrm.transpose();
  }
  DualCandidateOptions candidate_options = options.candidates;
  candidate_options.threads = options.threads;
  const DualCandidates candidates = dual_candidates_from_faces(dual_faces, mesh, candidate_options);
  timer.done("sites");
  const MesherStats unextracted = out.stats;
  extract_from_candidates(mesh, candidates, surface, options, out.stats);
  if (options.keep_manifold_dual && changes_topology(mesh, dual_faces)) {
    std::vector<MeshFace> faces(static_cast<std::size_t>(dual_faces.rows()));
    for (Eigen::Index f = 0; f < dual_faces.rows(); ++f)
      faces[static_cast<std::size_t>(f)] = {dual_faces(f, 0), dual_faces(f, 1), dual_faces(f, 2)};
    const std::vector<std::pair<std::string, double>> seconds = std::move(out.stats.stage_seconds);
    out.stats = unextracted;
    out.stats.stage_seconds = seconds;
    out.stats.candidate_triangles = static_cast<int>(faces.size());
    mesh.set_faces(std::move(faces));
  }
  polish_extracted(mesh, surface, options, out.stats);
  out.mesh = finish_mesh(mesh, surface, options, out.stats);
  StageTimer finish_timer(out.stats, options.cancelled);
  ValidationOptions vo;
  vo.require_closed = false;
  out.validation = validate_triangle_mesh(out.mesh.V, out.mesh.F, vo);
  finish_timer.done("validate");
  return out;
}

}  // namespace heatcvt
