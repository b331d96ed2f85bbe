// Polish stages of the surface mesher.
#include "heatcvt/mesher/polish.h"

#include "heatcvt/mesher/mesh_checks.h"
#include "heatcvt/mesher/tangential_relaxation.h"

namespace heatcvt {
namespace {

int delaunay_flips(WorkingMesh& mesh, const PolishOptions& o, int passes, const std::vector<char>* only = nullptr) {
  FlipOptions f = o.flips;
  f.max_passes = passes;
  f.valence_mode = false;
  return flip_edges(mesh, f, only);
}

void relax(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& o, bool use_valence,
           MesherStats& stats) {
  RelaxationBorder border;
  border.follow_sample_border = o.follow_sample_border;
  for (int it = 0; it < o.relaxation_iterations; ++it) {
    tangential_relaxation(mesh, surface, o.threads, border);
    // Valence-equalising flips first, max-min-angle flips in the last two iterations so that no
    // flip that hurts the smallest angle survives.
    FlipOptions f = o.flips;
    f.max_passes = o.flip_passes;
    f.valence_mode = use_valence && it + 2 < o.relaxation_iterations;
    stats.flipped_edges += flip_edges(mesh, f);
  }
}

}  // namespace

void relaxation_polish(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& options,
                       const UntangleOptions& untangling, const HoleFillingOptions& holes,
                       const ManifoldOptions& manifold, MesherStats& stats) {
  remove_valence3(mesh, options.valence3);
  stats.flipped_edges = delaunay_flips(mesh, options, options.initial_flip_passes);
  if (options.relaxation_iterations <= 0) return;
  const WorkingMesh::Checkpoint unpolished = mesh.checkpoint();
  const int flips_unpolished = stats.flipped_edges;
  relax(mesh, surface, options, true, stats);
  // Where the valence polish folded a thin part through itself, untangle locally first.
  if (self_intersecting_pairs(mesh) > 0) {
    untangle(mesh, surface, untangling, holes, manifold, stats);
    stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
  }
  if (self_intersecting_pairs(mesh) > 0) {
    mesh.rollback(unpolished);
    stats.flipped_edges = flips_unpolished;
    stats.polish_fallback = true;
    relax(mesh, surface, options, false, stats);
    if (self_intersecting_pairs(mesh) > 0) {
      untangle(mesh, surface, untangling, holes, manifold, stats);
      stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
    }
  }
}

void angle_polish_stage(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& options,
                        MesherStats& stats) {
  if (options.relaxation_iterations <= 0) return;
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const int flips_before = stats.flipped_edges;
  std::vector<char> frozen(mesh.num_vertices(), 0);
  for (int attempt = 0; attempt < options.angle_attempts; ++attempt) {
    if (remove_valence3(mesh, options.valence3) > 0) stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
    std::vector<char> settled;  // vertices whose search would find no move (angle_polish())
    for (int r = 0; r < options.angle_cycles; ++r) {
      angle_polish(mesh, surface, options.angle_rounds, frozen, options.angle, options.threads, &settled);
      const std::vector<MeshFace> unflipped = mesh.faces();
      stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
      unsettle_changed_faces(unflipped, mesh, settled);
    }
    const std::vector<int> bad = self_intersecting_faces(mesh);
    if (bad.empty()) break;
    std::vector<char> vbad(mesh.num_vertices(), 0);
    for (int f : bad)
      for (int v : mesh.face(f)) vbad[v] = 1;
    for (const MeshFace& f : mesh.faces())
      if (vbad[f[0]] || vbad[f[1]] || vbad[f[2]])
        for (int v : f) frozen[v] = 1;
    mesh.rollback(before, true);
    stats.flipped_edges = flips_before;
    if (attempt == options.angle_attempts - 1) stats.angle_polish_undone = true;
  }
}

}  // namespace heatcvt
