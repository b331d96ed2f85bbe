// Polish stages of the surface mesher.
#include "heatcvt/mesher/polish.h"

#include <algorithm>
#include <memory>
#include <vector>

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

// The vertices that may go: all but `tips`, for remove_valence3(); null where there is no tip.
std::unique_ptr<std::vector<char>> removable(const std::vector<char>& tips) {
  if (std::none_of(tips.begin(), tips.end(), [](char t) { return t != 0; })) return nullptr;
  auto out = std::make_unique<std::vector<char>>(tips.size());
  for (std::size_t v = 0; v < tips.size(); ++v) (*out)[v] = !tips[v];
  return out;
}

void relax(WorkingMesh& mesh, const SurfaceProjector& surface, const PolishOptions& o, bool use_valence,
           const std::vector<char>& tips, MesherStats& stats) {
  RelaxationBorder border;
  border.follow_sample_border = o.follow_sample_border;
  border.spoiled_angle_deg = o.spoiled_border_angle_deg;
  std::vector<char> fixed = tips;
  fixed.resize(static_cast<std::size_t>(mesh.num_vertices()), 0);
  for (int it = 0; it < o.relaxation_iterations; ++it) {
    tangential_relaxation(mesh, surface, o.threads, border, &fixed);
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
  const std::vector<char> tips = tip_vertices(mesh, options.tips);
  remove_valence3(mesh, options.valence3, removable(tips).get());
  stats.flipped_edges = delaunay_flips(mesh, options, options.initial_flip_passes);
  if (options.relaxation_iterations <= 0) return;
  const WorkingMesh::Checkpoint unpolished = mesh.checkpoint();
  const int flips_unpolished = stats.flipped_edges;
  relax(mesh, surface, options, true, tips, stats);
  // Where the valence polish folded a thin part through itself, untangle locally first.
  if (self_intersecting_pairs(mesh) > 0) {
    untangle(mesh, surface, untangling, holes, manifold, stats);
    stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
  }
  if (self_intersecting_pairs(mesh) > 0) {
    mesh.rollback(unpolished);
    stats.flipped_edges = flips_unpolished;
    stats.polish_fallback = true;
    relax(mesh, surface, options, false, tips, stats);
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
  std::vector<char> frozen = tip_vertices(mesh, options.tips);
  const std::unique_ptr<std::vector<char>> may_go = removable(frozen);
  for (int attempt = 0; attempt < options.angle_attempts; ++attempt) {
    if (remove_valence3(mesh, options.valence3, may_go.get()) > 0) stats.flipped_edges += delaunay_flips(mesh, options, options.flip_passes);
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
