// Edge flips of the working mesh.
#include "heatcvt/mesher/edge_flips.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace heatcvt {
namespace {

// The flip rule of flip_edges() for the edge (a, b) of face f1 = (a, b, c) and its twin
// f2 = (b, a, d). Reads only the positions, valences and edges of a, b, c, d. `d` receives
// the opposite vertex (-1 on a border).
class FlipRule {
 public:
  FlipRule(const WorkingMesh& mesh, const FlipOptions& options, const std::vector<char>* only_at,
           const std::vector<int>* target_valence)
      : mesh_(mesh), o_(options), only_at_(only_at), target_(target_valence),
        flat_cos_(std::cos(options.flat_dihedral_deg * M_PI / 180.0)),
        valence_angle_(options.valence_min_angle_deg * M_PI / 180.0),
        cos_limit_(std::cos(options.max_normal_deviation_deg * M_PI / 180.0)) {}

  bool wants(int a, int b, int c, int* f2_out, int* d_out) const {
    const int f2 = mesh_.half_edge_face(b, a);
    *f2_out = f2;
    *d_out = -1;
    if (f2 < 0) return false;
    int d = -1;
    for (int v : mesh_.face(f2))
      if (v != a && v != b) d = v;
    *d_out = d;
    if (d < 0 || d == c) return false;
    if (only_at_ && !(*only_at_)[a] && !(*only_at_)[b]) return false;
    if (mesh_.valence(a) <= 3 || mesh_.valence(b) <= 3) return false;
    // The valence test needs no geometry and no edge search: it goes first.
    if (o_.valence_mode && !valence_gain(a, b, c, d)) return false;
    if (mesh_.edge_face_count(c, d) > 0) return false;
    const double before = std::min(min_angle(a, b, c), min_angle(b, a, d));
    const double after = std::min(min_angle(c, a, d), min_angle(d, b, c));
    if (o_.valence_mode) {
      // Never across creases or thin parts, where a valence flip can fold the surface
      // through itself.
      if (!(normal(a, b, c).normalized().dot(normal(b, a, d).normalized()) > flat_cos_)) return false;
      if (!(after > before || after > valence_angle_)) return false;
    } else if (!(after > before + 1e-9)) {
      return false;
    }
    const Eigen::Vector3d avg = (normal(a, b, c).normalized() + normal(b, a, d).normalized()).normalized();
    const Eigen::Vector3d m1 = normal(c, a, d), m2 = normal(d, b, c);
    if (!(m1.norm() > 0) || !(m2.norm() > 0) || !avg.allFinite()) return false;
    return !(m1.normalized().dot(avg) < cos_limit_ || m2.normalized().dot(avg) < cos_limit_);
  }

 private:
  Eigen::Vector3d normal(int a, int b, int c) const {
    const Eigen::MatrixX3d& V = mesh_.V;
    return (V.row(b) - V.row(a)).cross(V.row(c) - V.row(a)).transpose();
  }
  double min_angle(int a, int b, int c) const { return face_min_angle(mesh_, {a, b, c}); }
  bool valence_gain(int a, int b, int c, int d) const {
    auto dev = [&](int v, int x) {
      const int t = target_ ? (*target_)[v] : 6;
      return (x - t) * (x - t);
    };
    const int va = mesh_.valence(a), vb = mesh_.valence(b), vc = mesh_.valence(c), vd = mesh_.valence(d);
    return dev(a, va - 1) + dev(b, vb - 1) + dev(c, vc + 1) + dev(d, vd + 1) <
           dev(a, va) + dev(b, vb) + dev(c, vc) + dev(d, vd);
  }

  const WorkingMesh& mesh_;
  const FlipOptions& o_;
  const std::vector<char>* only_at_;
  const std::vector<int>* target_;
  double flat_cos_, valence_angle_, cos_limit_;
};

}  // namespace

std::vector<char> moved_vertex_rings(const WorkingMesh& mesh, const WorkingMesh::Checkpoint& before) {
  const int nv = mesh.num_vertices();
  const std::vector<char> moved = changes_since(before, mesh).moved;
  std::vector<char> dirty(nv, 0);
  for (const MeshFace& f : mesh.faces())
    if (moved[f[0]] || moved[f[1]] || moved[f[2]]) dirty[f[0]] = dirty[f[1]] = dirty[f[2]] = 1;
  for (int v = 0; v < nv; ++v) dirty[v] = dirty[v] || moved[v];
  return dirty;
}

int flip_edges(WorkingMesh& mesh, const FlipOptions& options, const std::vector<char>* only_at,
               const std::vector<int>* target_valence, const std::vector<char>* dirty, bool* converged,
               const std::vector<int>* faces) {
  const FlipRule rule(mesh, options, only_at, target_valence);
  // The faces visited, in ascending order: every face, or those of `faces`.
  std::vector<int> visit;
  if (faces) {
    visit = *faces;
    std::sort(visit.begin(), visit.end());
    visit.erase(std::unique(visit.begin(), visit.end()), visit.end());
  } else {
    visit.resize(static_cast<std::size_t>(mesh.num_faces()));
    for (int f = 0; f < mesh.num_faces(); ++f) visit[static_cast<std::size_t>(f)] = f;
  }
  // A rejected edge stays rejected while none of a, b, c, d is in a flip: the rule reads only
  // their valences and edges (positions do not move here). `changed` stamps the vertices of
  // every flip (by their rank in `stamped`: every vertex, or the corners of the visited faces),
  // `checked` the last rejection of each visited face corner (with its d), so passes after the
  // first look only at edges next to a flip. Same flips in the same order as a full scan.
  std::vector<int> stamped;
  if (faces)
    for (int f : visit)
      for (int v : mesh.face(f)) stamped.push_back(v);
  std::sort(stamped.begin(), stamped.end());
  stamped.erase(std::unique(stamped.begin(), stamped.end()), stamped.end());
  const int nv = mesh.num_vertices();
  const auto rank = [&](int v) -> long {
    if (v < 0 || v >= nv) return -1;
    if (!faces) return v;
    const auto it = std::lower_bound(stamped.begin(), stamped.end(), v);
    return it != stamped.end() && *it == v ? it - stamped.begin() : -1;
  };
  std::vector<long> changed(faces ? stamped.size() : static_cast<std::size_t>(nv), 0);
  std::vector<long> checked(3 * visit.size(), -1);
  std::vector<int> checked_d(checked.size(), -1);
  long clock = 0;
  // A vertex outside `stamped` (a corner of a twin face the caller did not list) counts as changed.
  auto still = [&](int v, long when) {
    if (v < 0 || v >= nv) return true;
    const long r = rank(v);
    return r >= 0 && changed[static_cast<std::size_t>(r)] <= when;
  };
  const auto tracked_vertex = [&](int v) { return v >= 0 && v < nv; };
  // With `dirty`, an edge with neither end dirty still has the verdict of the converged call
  // before: recorded as rejected at clock 0. A change of its twin face stamps a or b.
  if (dirty)
    for (std::size_t slot = 0; slot < visit.size(); ++slot)
      for (int k = 0; k < 3; ++k) {
        const MeshFace& t = mesh.face(visit[slot]);
        const int a = t[k], b = t[(k + 1) % 3];
        if (tracked_vertex(a) && tracked_vertex(b) && !(*dirty)[a] && !(*dirty)[b]) checked[3 * slot + k] = 0;
      }
  int flips = 0;
  if (converged) *converged = false;
  for (int pass = 0; pass < options.max_passes; ++pass) {
    int pass_flips = 0;
    for (std::size_t slot = 0; slot < visit.size(); ++slot) {
      const int f1 = visit[slot];
      for (int k = 0; k < 3; ++k) {
        const MeshFace& t = mesh.face(f1);
        const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        const size_t corner = 3 * slot + k;
        const bool tracked = tracked_vertex(a) && tracked_vertex(b) && tracked_vertex(c);
        if (tracked && checked[corner] >= 0) {
          const long when = checked[corner];
          if (still(a, when) && still(b, when) && still(c, when) && still(checked_d[corner], when)) continue;
        }
        int f2 = -1, d = -1;
        if (!rule.wants(a, b, c, &f2, &d)) {
          if (tracked) {
            checked[corner] = clock;
            checked_d[corner] = d;
          }
          continue;
        }
        mesh.flip(f1, k, f2);
        ++clock;
        for (int v : {a, b, c, d})
          if (const long r = rank(v); r >= 0) changed[static_cast<std::size_t>(r)] = clock;
        ++pass_flips;
        break;  // face f1 changed: move on to the next face
      }
    }
    flips += pass_flips;
    if (pass_flips == 0) {
      if (converged) *converged = true;
      break;
    }
  }
  return flips;
}

}  // namespace heatcvt
