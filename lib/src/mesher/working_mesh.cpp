// The working mesh of the surface mesher: faces with an incrementally maintained edge index.
#include "heatcvt/mesher/working_mesh.h"


#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <utility>

namespace heatcvt {

WorkingMesh::WorkingMesh(Eigen::MatrixX3d positions, Eigen::MatrixX3d normals, std::vector<int> anchors)
    : V(std::move(positions)), N(std::move(normals)), anchor(std::move(anchors)), valence_(V.rows(), 0) {
  anchor.resize(V.rows(), -1);
}

int WorkingMesh::add_vertex(const Eigen::Vector3d& position, const Eigen::Vector3d& normal, int anchor_hint) {
  const int m = num_vertices();
  V.conservativeResize(m + 1, 3);
  N.conservativeResize(m + 1, 3);
  V.row(m) = position.transpose();
  N.row(m) = normal.transpose();
  anchor.push_back(anchor_hint);
  valence_.push_back(0);
  return m;
}

void WorkingMesh::add_vertices(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& normals,
                               const std::vector<int>& anchor_hints) {
  const Eigen::Index m = V.rows(), k = positions.rows();
  V.conservativeResize(m + k, 3);
  N.conservativeResize(m + k, 3);
  V.bottomRows(k) = positions;
  N.bottomRows(k) = normals;
  anchor.insert(anchor.end(), anchor_hints.begin(), anchor_hints.end());
  valence_.resize(V.rows(), 0);
}

WorkingMesh::StarEntry* WorkingMesh::find(Star& star, int to) {
  for (StarEntry& e : star)
    if (e.to == to) return &e;
  return nullptr;
}

const WorkingMesh::StarEntry* WorkingMesh::find(const Star& star, int to) {
  for (const StarEntry& e : star)
    if (e.to == to) return &e;
  return nullptr;
}

void WorkingMesh::grow_stars() {
  const size_t n = static_cast<size_t>(V.rows());
  if (valence_.size() < n) valence_.resize(n, 0);
  if (out_.size() < n) out_.resize(n);
  if (edges_.size() < n) edges_.resize(n);
}

void WorkingMesh::index_face(int f) {
  grow_stars();
  const MeshFace& t = faces_[f];
  for (int k = 0; k < 3; ++k) {
    const int a = t[k], b = t[(k + 1) % 3];
    if (StarEntry* e = find(out_[a], b)) e->value = f;
    else out_[a].push_back({b, f});
    Star& star = edges_[std::min(a, b)];
    if (StarEntry* e = find(star, std::max(a, b))) {
      ++e->value;
    } else {
      star.push_back({std::max(a, b), 1});
      ++valence_[a], ++valence_[b];
    }
  }
}

void WorkingMesh::unindex_face(int f) {
  const MeshFace& t = faces_[f];
  auto erase = [](Star& star, StarEntry* e) {
    *e = star.back();
    star.pop_back();
  };
  for (int k = 0; k < 3; ++k) {
    const int a = t[k], b = t[(k + 1) % 3];
    if (StarEntry* e = find(out_[a], b); e && e->value == f) erase(out_[a], e);
    Star& star = edges_[std::min(a, b)];
    if (StarEntry* e = find(star, std::max(a, b)); e && --e->value == 0) {
      erase(star, e);
      --valence_[a], --valence_[b];
    }
  }
}

int WorkingMesh::add_face(const MeshFace& f) {
  faces_.push_back(f);
  index_face(num_faces() - 1);
  return num_faces() - 1;
}

void WorkingMesh::pop_face() {
  unindex_face(num_faces() - 1);
  faces_.pop_back();
}

void WorkingMesh::pop_vertex() {
  const Eigen::Index m = V.rows() - 1;
  V.conservativeResize(m, 3);
  N.conservativeResize(m, 3);
  anchor.pop_back();
  const auto shrink = [m](auto& per_vertex) {
    if (static_cast<Eigen::Index>(per_vertex.size()) > m) per_vertex.resize(static_cast<std::size_t>(m));
  };
  shrink(valence_);
  shrink(out_);
  shrink(edges_);
}

void WorkingMesh::replace_face(int f, const MeshFace& g) {
  unindex_face(f);
  faces_[f] = g;
  index_face(f);
}

int WorkingMesh::remove_faces(const std::vector<char>& drop) {
  int removed = 0;
  for (int f = 0; f < num_faces(); ++f)
    if (drop[f]) unindex_face(f), ++removed;
  if (removed == 0) return 0;
  int next = 0;
  for (int f = 0; f < num_faces(); ++f) {
    if (drop[f]) continue;
    if (next != f) {
      faces_[next] = faces_[f];
      for (int k = 0; k < 3; ++k) {  // re-point the half-edges the moved face holds
        StarEntry* e = find(out_[faces_[next][k]], faces_[next][(k + 1) % 3]);
        if (e && e->value == f) e->value = next;
      }
    }
    ++next;
  }
  faces_.resize(next);
  return removed;
}

void WorkingMesh::set_faces(std::vector<MeshFace> faces) {
  faces_ = std::move(faces);
  out_.assign(V.rows(), {});
  edges_.assign(V.rows(), {});
  valence_.assign(V.rows(), 0);
  for (int f = 0; f < num_faces(); ++f) index_face(f);
}

void WorkingMesh::flip(int f1, int k, int f2) {
  const int a = faces_[f1][k], b = faces_[f1][(k + 1) % 3], c = faces_[f1][(k + 2) % 3];
  int d = -1;
  for (int v : faces_[f2])
    if (v != a && v != b) d = v;
  replace_face(f1, {c, a, d});
  replace_face(f2, {d, b, c});
}

int WorkingMesh::half_edge_face(int a, int b) const {
  if (a < 0 || a >= static_cast<int>(out_.size())) return -1;
  const StarEntry* e = find(out_[a], b);
  return e ? e->value : -1;
}

int WorkingMesh::edge_face_count(int a, int b) const {
  const int lo = std::min(a, b);
  if (lo < 0 || lo >= static_cast<int>(edges_.size())) return 0;
  const StarEntry* e = find(edges_[lo], std::max(a, b));
  return e ? e->value : 0;
}

std::vector<std::vector<int>> WorkingMesh::vertex_faces() const {
  std::vector<std::vector<int>> vf(num_vertices());
  for (int f = 0; f < num_faces(); ++f)
    for (int v : faces_[f]) vf[v].push_back(f);
  return vf;
}

std::vector<char> WorkingMesh::boundary_vertices() const {
  std::vector<char> on(num_vertices(), 0);
  for (const MeshFace& f : faces_)
    for (int q = 0; q < 3; ++q)
      if (!has_half_edge(f[(q + 1) % 3], f[q])) on[f[q]] = on[f[(q + 1) % 3]] = 1;
  return on;
}

void WorkingMesh::rollback(const Checkpoint& c, bool keep_anchors) {
  if (!keep_anchors || anchor.size() != c.anchor.size()) anchor = c.anchor;
  V = c.V;
  N = c.N;
  set_faces(c.faces);
}

MeshChanges changes_since(const WorkingMesh::Checkpoint& before, const WorkingMesh& mesh) {
  const int nv = mesh.num_vertices();
  MeshChanges c;
  c.moved.assign(nv, 0);
  c.rehinted.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    c.moved[v] = v >= before.V.rows() || mesh.V.row(v) != before.V.row(v);
    c.rehinted[v] = !c.moved[v] && (mesh.N.row(v) != before.N.row(v) || mesh.anchor[v] != before.anchor[v]);
  }
  c.new_face.assign(mesh.num_faces(), 0);
  if (mesh.faces() == before.faces) return c;
  const std::unordered_set<MeshFace, MeshFaceHash> then(before.faces.begin(), before.faces.end());
  const std::unordered_set<MeshFace, MeshFaceHash> now(mesh.faces().begin(), mesh.faces().end());
  for (int f = 0; f < mesh.num_faces(); ++f) c.new_face[f] = !then.count(mesh.face(f));
  for (const MeshFace& f : before.faces)
    if (!now.count(f)) c.removed.push_back(f);
  return c;
}

double triangle_min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // One acos instead of three: the smallest angle is the one opposite the shortest edge.
  const Eigen::Vector3d p[3] = {a, b, c};
  int k = 0;
  double shortest = std::numeric_limits<double>::infinity();
  for (int q = 0; q < 3; ++q) {
    const double len = (p[(q + 1) % 3] - p[(q + 2) % 3]).squaredNorm();
    if (len < shortest) shortest = len, k = q;
  }
  const Eigen::Vector3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
  const double n1 = e1.norm(), n2 = e2.norm();
  if (n1 == 0 || n2 == 0 || shortest == 0) return 0;
  return std::acos(std::clamp(e1.dot(e2) / (n1 * n2), -1.0, 1.0));
}

double face_min_angle(const WorkingMesh& mesh, const MeshFace& f) {
  return triangle_min_angle(mesh.V.row(f[0]).transpose(), mesh.V.row(f[1]).transpose(), mesh.V.row(f[2]).transpose());
}

double mean_min_angle(const WorkingMesh& mesh) {
  double sum = 0;
  for (const MeshFace& f : mesh.faces()) sum += face_min_angle(mesh, f);
  return mesh.num_faces() > 0 ? sum / mesh.num_faces() : 0.0;
}

double mean_edge_length(const WorkingMesh& mesh) {
  double sum = 0;
  long count = 0;
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k, ++count) sum += (mesh.V.row(f[k]) - mesh.V.row(f[(k + 1) % 3])).norm();
  return count > 0 ? sum / count : 0.0;
}

double corner_angle(const WorkingMesh& mesh, const MeshFace& f, int k) {
  const Eigen::Vector3d e1 = (mesh.V.row(f[(k + 1) % 3]) - mesh.V.row(f[k])).transpose();
  const Eigen::Vector3d e2 = (mesh.V.row(f[(k + 2) % 3]) - mesh.V.row(f[k])).transpose();
  if (!(e1.norm() > 0 && e2.norm() > 0)) return 0;
  return std::acos(std::clamp(e1.normalized().dot(e2.normalized()), -1.0, 1.0));
}

std::vector<double> vertex_angle_sums(const WorkingMesh& mesh) {
  std::vector<double> sum(mesh.num_vertices(), 0.0);
  for (const MeshFace& f : mesh.faces())
    for (int k = 0; k < 3; ++k) sum[f[k]] += corner_angle(mesh, f, k);
  return sum;
}

int vertices_in_faces(const WorkingMesh& mesh) {
  std::vector<char> used(mesh.num_vertices(), 0);
  for (const MeshFace& f : mesh.faces())
    for (int v : f) used[v] = 1;
  return static_cast<int>(std::count(used.begin(), used.end(), 1));
}

BorderLinks border_links(const WorkingMesh& mesh) {
  BorderLinks b;
  b.next.assign(mesh.num_vertices(), -1);
  b.prev.assign(mesh.num_vertices(), -1);
  for (const MeshFace& f : mesh.faces())
    for (int q = 0; q < 3; ++q) {
      const int a = f[q], c = f[(q + 1) % 3];
      if (mesh.has_half_edge(c, a)) continue;
      b.next[a] = b.next[a] == -1 ? c : -2;
      b.prev[c] = b.prev[c] == -1 ? a : -2;
    }
  return b;
}

double border_turn(const WorkingMesh& mesh, const BorderLinks& border, int v) {
  if (!border.simple(v)) return M_PI;
  const Eigen::Vector3d in = mesh.V.row(v) - mesh.V.row(border.prev[v]), out = mesh.V.row(border.next[v]) - mesh.V.row(v);
  if (!(in.norm() > 0) || !(out.norm() > 0)) return M_PI;
  return std::acos(std::clamp(in.normalized().dot(out.normalized()), -1.0, 1.0));
}

FaceComponents face_components(const WorkingMesh& mesh, bool by_vertex) {
  const int nf = mesh.num_faces();
  FaceComponents out;
  out.of_face.assign(nf, -1);
  if (by_vertex) {
    DisjointSets sets(mesh.num_vertices());
    for (const MeshFace& f : mesh.faces()) sets.unite(f[0], f[1]), sets.unite(f[1], f[2]);
    std::vector<int> id(mesh.num_vertices(), -1);
    for (int f = 0; f < nf; ++f) {
      int& c = id[sets.find(mesh.face(f)[0])];
      if (c < 0) c = static_cast<int>(out.size.size()), out.size.push_back(0);
      out.of_face[f] = c;
      ++out.size[c];
    }
    return out;
  }
  DisjointSets sets(nf);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.face(f)[k], b = mesh.face(f)[(k + 1) % 3];
      for (int g : {mesh.half_edge_face(a, b), mesh.half_edge_face(b, a)})
        if (g >= 0) sets.unite(f, g);
    }
  std::vector<int> id(nf, -1);
  for (int f = 0; f < nf; ++f) {
    int& c = id[sets.find(f)];
    if (c < 0) c = static_cast<int>(out.size.size()), out.size.push_back(0);
    out.of_face[f] = c;
    ++out.size[c];
  }
  return out;
}

std::vector<char> open_pieces(const WorkingMesh& mesh, const FaceComponents& pieces) {
  const BorderLinks border = border_links(mesh);
  std::vector<char> open(pieces.size.size(), 0);
  for (int id = 0; id < mesh.num_faces(); ++id)
    for (int v : mesh.face(id))
      if (border.on(v)) open[pieces.of_face[id]] = 1;
  return open;
}

}  // namespace heatcvt
