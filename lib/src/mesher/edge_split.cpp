// Splits of the long edges of slivers.
#include "heatcvt/mesher/edge_split.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "heatcvt/mesher/mesh_checks.h"

namespace heatcvt {
namespace {

struct Split {
  std::array<int, 5> vertices;  // a, b, c, d and the new vertex
  long long edge;               // the split edge {min, max}
};

// One pass: splits the longest edge of each sliver where allowed. Returns the splits; marks the
// vertices of the edited faces in near_new (resized to the new vertex count).
std::vector<Split> split_pass(WorkingMesh& mesh, const SurfaceProjector& surface, const EdgeSplitOptions& o,
                              const std::set<long long>& excluded, std::vector<char>& near_new, int budget) {
  const double thr = o.sliver_angle_deg * M_PI / 180.0;
  double mean_edge = 0;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) mean_edge += (mesh.V.row(f[k]) - mesh.V.row(f[(k + 1) % 3])).norm();
  mean_edge /= 3.0 * static_cast<double>(mesh.num_faces());
  const int nf = mesh.num_faces();
  std::vector<char> touched(nf, 0);
  std::vector<MeshFace> added;
  std::vector<Split> made;
  near_new.assign(mesh.num_vertices(), 0);
  for (int id = 0; id < nf && (budget < 0 || static_cast<int>(made.size()) < budget); ++id) {
    const MeshFace f = mesh.face(id);
    if (touched[id] || face_min_angle(mesh, f) >= thr) continue;
    int k = 0;
    double longest = 0;
    for (int q = 0; q < 3; ++q) {
      const double len = (mesh.V.row(f[q]) - mesh.V.row(f[(q + 1) % 3])).norm();
      if (len > longest) longest = len, k = q;
    }
    if (!(longest > o.length_factor * mean_edge)) continue;
    const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
    const long long key = WorkingMesh::edge_key(std::min(a, b), std::max(a, b));
    if (excluded.count(key) || mesh.edge_face_count(a, b) != 2) continue;
    const int other = mesh.half_edge_face(b, a);
    if (other < 0 || other >= nf || touched[other]) continue;
    int d = -1;
    for (int v : mesh.face(other))
      if (v != a && v != b) d = v;
    if (d < 0 || d == c) continue;
    Eigen::Vector3d pos, nrm;
    surface.project(0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose(), mesh.anchor[a], pos, nrm);
    if (!pos.allFinite() || !nrm.allFinite()) continue;
    const int m = mesh.add_vertex(pos, nrm, mesh.anchor[a]);
    // (a, b, c) → (a, m, c), (m, b, c); the neighbour (b, a, d) → (b, m, d), (m, a, d).
    mesh.replace_face(id, {a, m, c});
    added.push_back({m, b, c});
    mesh.replace_face(other, {b, m, d});
    added.push_back({m, a, d});
    touched[id] = touched[other] = 1;
    near_new.resize(mesh.num_vertices(), 0);
    for (int v : {a, b, c, d, m}) near_new[v] = 1;
    made.push_back({{a, b, c, d, m}, key});
  }
  for (const MeshFace& t : added) mesh.add_face(t);
  return made;
}

}  // namespace

int split_long_edges(WorkingMesh& mesh, const SurfaceProjector& surface, const EdgeSplitOptions& options,
                     MesherStats& stats) {
  const WorkingMesh::Checkpoint before = mesh.checkpoint();
  const int flips_before = stats.flipped_edges;
  FlipOptions fo = options.flips;
  fo.valence_mode = false;
  std::set<long long> excluded;  // edges (of the original vertices) not to split
  for (int attempt = 0; attempt < options.attempts; ++attempt) {
    std::vector<Split> made;
    for (int pass = 0; pass < options.passes && !mesh.empty(); ++pass) {
      std::vector<char> near_new;
      int budget = -1;  // splits left before the mesh has options.max_vertices vertices in faces
      if (options.max_vertices > 0) {
        budget = std::max(0, options.max_vertices - vertices_in_faces(mesh));
      }
      const std::vector<Split> pass_made = split_pass(mesh, surface, options, excluded, near_new, budget);
      if (pass_made.empty()) break;
      made.insert(made.end(), pass_made.begin(), pass_made.end());
      stats.flipped_edges += flip_edges(mesh, fo, &near_new);
      std::vector<char> frozen(mesh.num_vertices(), 1);
      for (int v = 0; v < mesh.num_vertices(); ++v)
        if (near_new[v]) frozen[v] = 0;
      angle_polish(mesh, surface, options.polish_rounds, frozen, options.angle, options.threads);
      stats.flipped_edges += flip_edges(mesh, fo, &near_new);
    }
    if (made.empty()) break;
    const std::vector<int> bad = self_intersecting_faces(mesh);
    if (bad.empty()) return static_cast<int>(made.size());
    // Leave out the splits whose vertices are in or next to an intersecting face; redo.
    std::vector<char> in_bad(mesh.num_vertices(), 0), vbad(mesh.num_vertices(), 0);
    for (int f : bad)
      for (int v : mesh.face(f)) in_bad[v] = 1;
    for (const MeshFace& f : mesh.faces())
      if (in_bad[f[0]] || in_bad[f[1]] || in_bad[f[2]])
        for (int v : f) vbad[v] = 1;
    bool any = false;
    for (const Split& s : made)
      if (std::any_of(s.vertices.begin(), s.vertices.end(), [&](int v) { return vbad[v] != 0; }))
        excluded.insert(s.edge), any = true;
    mesh.rollback(before);
    stats.flipped_edges = flips_before;
    if (!any) break;  // the intersection is not the splits' doing: keep the mesh as it was
  }
  return 0;
}

}  // namespace heatcvt
