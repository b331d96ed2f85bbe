// Surface checks of a triangle mesh. Combinatorial checks (edges, vertices, orientation, borders,
// genus) are computed directly so that failures can name the offending elements; the polygon-mesh
// structure, closedness, components and self-intersections are checked with CGAL
// (Surface_mesh + Polygon_mesh_processing).
#include "heatcvt/validate.h"

#include "heatcvt/disjoint_sets.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <unordered_map>

#include "heatcvt/errors.h"

namespace heatcvt {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

struct Topology {
  int vertices = 0, edges = 0, faces = 0, components = 0, boundary_loops = 0;
  std::vector<std::vector<int>> nonmanifold_edges, border_edges, inconsistent_edges, nonmanifold_vertices,
      unused_vertices;
  long n_nonmanifold_edges = 0, n_border = 0, n_inconsistent = 0, n_nonmanifold_vertices = 0, n_unused = 0;
  std::vector<int> component_of_vertex;  // −1 for unreferenced
  std::vector<int> chi, loops;           // per component
  int orientable = -1;                   // 1 / 0 / −1 (non-manifold edges: not determined)
  std::vector<char> non_orientable;      // per component
};

Topology analyse(const Eigen::MatrixX3i& F, int nv, int max_listed) {
  Topology t;
  const int nf = static_cast<int>(F.rows());
  t.faces = nf;
  auto list = [&](std::vector<std::vector<int>>& where, long& count, std::vector<int> item) {
    if (static_cast<int>(where.size()) < max_listed) where.push_back(std::move(item));
    ++count;
  };
  std::vector<char> used(nv, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) used[F(f, k)] = 1;
  for (int v = 0; v < nv; ++v) {
    if (used[v]) ++t.vertices;
    else list(t.unused_vertices, t.n_unused, {v});
  }
  // edges: (min, max, face, +1 if stored a→b with a < b)
  std::vector<std::array<int, 4>> half;
  half.reserve(3 * static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      half.push_back({std::min(a, b), std::max(a, b), f, a < b ? 1 : 0});
    }
  std::sort(half.begin(), half.end());
  DisjointSets comps(nv), border(nv);
  std::vector<char> on_border(nv, 0);
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    ++t.edges;
    const int a = half[i][0], b = half[i][1];
    comps.unite(a, b);
    const size_t count = j - i;
    if (count > 2) list(t.nonmanifold_edges, t.n_nonmanifold_edges, {a, b});
    if (count == 1) {
      list(t.border_edges, t.n_border, {a, b});
      border.unite(a, b);
      on_border[a] = on_border[b] = 1;
    }
    if (count == 2 && half[i][3] == half[i + 1][3]) list(t.inconsistent_edges, t.n_inconsistent, {a, b});
    i = j;
  }
  // vertex links: the opposite edges of the incident faces must form one path or cycle
  std::vector<int> off(nv + 1, 0), link;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++off[F(f, k) + 1];
  for (int v = 0; v < nv; ++v) off[v + 1] += off[v];
  link.resize(2 * static_cast<size_t>(off[nv]));
  {
    std::vector<int> fill(off.begin(), off.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = F(f, k), i = fill[v]++;
        link[2 * i] = F(f, (k + 1) % 3);
        link[2 * i + 1] = F(f, (k + 2) % 3);
      }
  }
  // A vertex is manifold when the edges of its link (opposite edges of its faces) form one piece.
  std::unordered_map<int, int> local;  // link vertex -> index in the link
  for (int v = 0; v < nv; ++v) {
    if (off[v + 1] == off[v]) continue;
    local.clear();
    for (int i = off[v]; i < off[v + 1]; ++i)
      for (int q = 0; q < 2; ++q) local.emplace(link[2 * i + q], static_cast<int>(local.size()));
    DisjointSets link_sets(static_cast<int>(local.size()));
    for (int i = off[v]; i < off[v + 1]; ++i) link_sets.unite(local[link[2 * i]], local[link[2 * i + 1]]);
    int nroots = 0;
    for (int i = 0; i < static_cast<int>(local.size()); ++i) nroots += link_sets.find(i) == i;
    if (nroots > 1) list(t.nonmanifold_vertices, t.n_nonmanifold_vertices, {v});
  }
  // components and boundary loops
  t.component_of_vertex.assign(nv, -1);
  std::unordered_map<int, int> comp_id;
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    const int r = comps.find(v);
    auto it = comp_id.find(r);
    if (it == comp_id.end()) it = comp_id.emplace(r, static_cast<int>(comp_id.size())).first;
    t.component_of_vertex[v] = it->second;
  }
  t.components = static_cast<int>(comp_id.size());
  t.chi.assign(t.components, 0);
  t.loops.assign(t.components, 0);
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    t.chi[t.component_of_vertex[v]] += 1;
    if (on_border[v] && border.find(v) == v) {
      t.loops[t.component_of_vertex[v]] += 1;
      ++t.boundary_loops;
    }
  }
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    t.chi[t.component_of_vertex[half[i][0]]] -= 1;
    i = j;
  }
  for (int f = 0; f < nf; ++f) t.chi[t.component_of_vertex[F(f, 0)]] += 1;

  // Orientability: propagate face flips across the edges with exactly two faces (an edge stored
  // twice in the same direction asks its faces for opposite flips); a contradiction means no
  // consistent orientation exists.
  t.non_orientable.assign(t.components, 0);
  if (t.n_nonmanifold_edges == 0) {
    std::vector<std::vector<std::pair<int, int>>> adj(nf);  // (neighbour face, 1 if same direction)
    for (size_t i = 0; i + 1 < half.size(); ++i)
      if (half[i][0] == half[i + 1][0] && half[i][1] == half[i + 1][1] && half[i][2] != half[i + 1][2]) {
        const int same = half[i][3] == half[i + 1][3] ? 1 : 0;
        adj[half[i][2]].push_back({half[i + 1][2], same});
        adj[half[i + 1][2]].push_back({half[i][2], same});
      }
    std::vector<int> flip(nf, -1), stack;
    for (int f0 = 0; f0 < nf; ++f0) {
      if (flip[f0] >= 0) continue;
      flip[f0] = 0;
      stack.assign(1, f0);
      bool ok = true;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        for (const auto& [g, same] : adj[f]) {
          const int want = flip[f] ^ same;
          if (flip[g] < 0) {
            flip[g] = want;
            stack.push_back(g);
          } else if (flip[g] != want) {
            ok = false;
          }
        }
      }
      if (!ok) t.non_orientable[t.component_of_vertex[F(f0, 0)]] = 1;
    }
    t.orientable = 1;
    for (char c : t.non_orientable)
      if (c) t.orientable = 0;
  }
  return t;
}

std::string join_items(const std::vector<std::vector<int>>& where) {
  std::ostringstream s;
  for (size_t i = 0; i < where.size(); ++i) {
    s << (i ? " " : "") << '(';
    for (size_t k = 0; k < where[i].size(); ++k) s << (k ? "," : "") << where[i][k];
    s << ')';
  }
  return s.str();
}

MeshCheck make_check(const std::string& name, long failures, const std::string& what,
                     std::vector<std::vector<int>> where) {
  MeshCheck c;
  c.name = name;
  c.passed = failures == 0;
  c.detail = c.passed ? "ok" : std::to_string(failures) + " " + what + ": " + join_items(where);
  c.where = std::move(where);
  return c;
}

}  // namespace

bool ValidationReport::ok() const {
  for (const auto& c : checks)
    if (!c.ran || !c.passed) return false;
  return !checks.empty();
}

const MeshCheck* ValidationReport::find(const std::string& name) const {
  for (const auto& c : checks)
    if (c.name == name) return &c;
  return nullptr;
}

std::string ValidationReport::summary() const {
  std::ostringstream s;
  for (const auto& c : checks) s << (c.ran ? (c.passed ? "PASS " : "FAIL ") : "SKIP ") << c.name << ": " << c.detail << '\n';
  s << "V=" << vertices << " E=" << edges << " F=" << faces << " components=" << components
    << " boundary_loops=" << boundary_loops << " euler=" << euler_characteristic << " genus=" << genus;
  if (orientable == 0) s << " non-orientable (cross-caps=" << crosscaps << ")";
  s << '\n';
  return s.str();
}

int mesh_genus(const Eigen::MatrixX3i& F, int num_vertices) {
  Topology t = analyse(F, num_vertices, 0);
  if (t.n_nonmanifold_edges || t.n_nonmanifold_vertices || t.n_inconsistent) return -1;
  int genus = 0;
  for (int c = 0; c < t.components; ++c) {
    const int twice = 2 - t.chi[c] - t.loops[c];
    if (twice < 0 || twice % 2) return -1;
    genus += twice / 2;
  }
  return genus;
}

namespace {

bool is_oriented_manifold(const Topology& t) {
  return t.n_nonmanifold_edges == 0 && t.n_nonmanifold_vertices == 0 && t.n_inconsistent == 0;
}

// Counts, orientability, cross-caps and genus (per component: 2 − χ − loops = 2g, or the number
// of cross-caps of a non-orientable one) from the combinatorial analysis.
void fill_topology(ValidationReport& rep, const Topology& t) {
  const bool manifold = is_oriented_manifold(t);
  rep.vertices = t.vertices;
  rep.edges = t.edges;
  rep.faces = t.faces;
  rep.components = t.components;
  rep.boundary_loops = t.boundary_loops;
  rep.euler_characteristic = t.vertices - t.edges + t.faces;
  rep.orientable = t.orientable;
  if (t.n_nonmanifold_edges == 0 && t.n_nonmanifold_vertices == 0) {
    rep.crosscaps = 0;
    for (int c = 0; c < t.components; ++c)
      if (t.non_orientable[c]) rep.crosscaps += 2 - t.chi[c] - t.loops[c];
  }
  if (manifold) {
    rep.genus = 0;
    for (int c = 0; c < t.components; ++c) {
      const int twice = 2 - t.chi[c] - t.loops[c];
      if (twice < 0 || twice % 2) {
        rep.genus = -1;
        break;
      }
      rep.genus += twice / 2;
    }
  }
}

// The combinatorial checks: manifold edges and vertices, orientation, closedness, unused
// vertices, and the expected components / genus when asked for.
void add_topology_checks(ValidationReport& rep, const Topology& t, const ValidationOptions& options,
                         bool accepted_non_orientable) {
  const bool manifold = is_oriented_manifold(t);
  rep.checks.push_back(make_check("manifold_edges", t.n_nonmanifold_edges, "edges with more than two faces",
                                  t.nonmanifold_edges));
  rep.checks.push_back(make_check("manifold_vertices", t.n_nonmanifold_vertices,
                                  "vertices whose faces do not form one fan", t.nonmanifold_vertices));
  if (accepted_non_orientable) {
    MeshCheck c;
    c.name = "consistent_orientation";
    c.passed = true;
    c.detail = "non-orientable surface (" + std::to_string(rep.crosscaps) +
               " cross-caps): no consistent orientation exists; " + std::to_string(t.n_inconsistent) +
               " edges are traversed twice in the same direction (accepted: allow_non_orientable)";
    c.where = t.inconsistent_edges;
    rep.checks.push_back(c);
  } else {
    rep.checks.push_back(make_check("consistent_orientation", t.n_inconsistent,
                                    "edges traversed twice in the same direction", t.inconsistent_edges));
  }
  if (options.require_closed) rep.checks.push_back(make_check("closed", t.n_border, "border edges", t.border_edges));
  rep.checks.push_back(make_check("all_vertices_used", t.n_unused, "vertices in no triangle", t.unused_vertices));
  if (options.expected_components >= 0) {
    MeshCheck c;
    c.name = "components";
    c.passed = t.components == options.expected_components;
    c.detail = std::to_string(t.components) + " components, expected " + std::to_string(options.expected_components);
    rep.checks.push_back(c);
  }
  if (options.expected_boundary_loops >= 0) {
    MeshCheck c;
    c.name = "boundary_loops";
    c.passed = t.boundary_loops == options.expected_boundary_loops;
    c.detail = std::to_string(t.boundary_loops) + " boundary loops, expected " +
               std::to_string(options.expected_boundary_loops);
    rep.checks.push_back(c);
  }
  if (options.expected_genus >= 0) {
    MeshCheck c;
    c.name = "genus";
    c.ran = manifold;
    c.passed = manifold && rep.genus == options.expected_genus;
    c.detail = manifold ? "genus " + std::to_string(rep.genus) + " (euler " + std::to_string(rep.euler_characteristic) +
                              ", " + std::to_string(t.components) + " components, " +
                              std::to_string(t.boundary_loops) + " boundary loops), expected " +
                              std::to_string(options.expected_genus)
                        : "not computed: the mesh is not an oriented 2-manifold";
    rep.checks.push_back(c);
  }
}

// (V, F) as a CGAL polygon soup over the vertices in use. A non-orientable surface is cut open
// along an orientation seam (vertices duplicated) so that CGAL can build a polygon mesh;
// `original` maps every point back to its vertex of (V, F).
struct CgalSoup {
  std::vector<Kernel::Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  std::vector<int> original;
};

CgalSoup cgal_soup(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, bool accepted_non_orientable) {
  const int nv = static_cast<int>(V.rows());
  CgalSoup soup;
  std::vector<Kernel::Point_3>& points = soup.points;
  std::vector<std::vector<std::size_t>>& polygons = soup.polygons;
  std::vector<int> remap(nv, -1);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      if (remap[v] < 0) {
        remap[v] = static_cast<int>(points.size());
        points.emplace_back(V(v, 0), V(v, 1), V(v, 2));
      }
    }
  std::vector<int> back(points.size());
  for (int v = 0; v < nv; ++v)
    if (remap[v] >= 0) back[remap[v]] = v;
  polygons.resize(static_cast<std::size_t>(F.rows()));
  for (int f = 0; f < F.rows(); ++f)
    polygons[f] = {static_cast<std::size_t>(remap[F(f, 0)]), static_cast<std::size_t>(remap[F(f, 1)]),
                   static_cast<std::size_t>(remap[F(f, 2)])};
  std::vector<int>& original = soup.original;
  original = back;
  if (accepted_non_orientable) {
    PMP::orient_polygon_soup(points, polygons);
    std::map<std::array<double, 3>, int> by_position;
    for (size_t i = 0; i < back.size(); ++i)
      by_position.emplace(std::array<double, 3>{points[i].x(), points[i].y(), points[i].z()}, back[i]);
    for (size_t i = back.size(); i < points.size(); ++i)
      original.push_back(by_position.at({points[i].x(), points[i].y(), points[i].z()}));
  }
  return soup;
}

// CGAL's checks: polygon-mesh structure, closedness and components against the combinatorial
// ones, self-intersections (faces touching at a vertex of the uncut surface do not count).
void add_cgal_checks(ValidationReport& rep, const CgalSoup& soup, const Topology& t, const ValidationOptions& options,
                     bool accepted_non_orientable, int listed) {
  const std::vector<Kernel::Point_3>& points = soup.points;
  const std::vector<std::vector<std::size_t>>& polygons = soup.polygons;
  const std::vector<int>& original = soup.original;
  MeshCheck structure;
  structure.name = "cgal_polygon_mesh";
  structure.passed = PMP::is_polygon_soup_a_polygon_mesh(polygons);
  structure.detail = structure.passed ? "ok"
                                      : "CGAL rejects the triangles as a polygon mesh (non-manifold or "
                                        "inconsistently oriented)";
  rep.checks.push_back(structure);
  MeshCheck si;
  si.name = "no_self_intersections";
  if (!structure.passed) {
    si.ran = false;
    si.detail = "not run: needs a valid polygon mesh";
  } else {
    CgalMesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
    // Faces of the Surface_mesh are created in polygon order: face index i = row i of F.
    const bool cgal_closed = CGAL::is_closed(mesh);
    if (options.require_closed && !accepted_non_orientable && cgal_closed != (t.n_border == 0)) {
      MeshCheck c;
      c.name = "cgal_closed";
      c.passed = false;
      c.detail = "CGAL::is_closed disagrees with the border-edge count";
      rep.checks.push_back(c);
    }
    std::vector<std::size_t> comp_of_face(num_faces(mesh));
    auto fmap = boost::make_iterator_property_map(comp_of_face.begin(), get(boost::face_index, mesh));
    const std::size_t ncc = PMP::connected_components(mesh, fmap);
    if (static_cast<int>(ncc) != t.components && !accepted_non_orientable) {
      MeshCheck c;
      c.name = "cgal_components";
      c.passed = false;
      c.detail = "CGAL finds " + std::to_string(ncc) + " components, edge graph " + std::to_string(t.components);
      rep.checks.push_back(c);
    }
    if (!options.check_self_intersections) {
      si.name.clear();  // disabled by the caller: not reported
    } else if (!PMP::does_self_intersect<CGAL::Sequential_tag>(mesh) && !accepted_non_orientable) {
      si.passed = true;
      si.detail = "ok";
      rep.self_intersecting_pairs = 0;
    } else {
      std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> pairs;
      PMP::self_intersections<CGAL::Sequential_tag>(mesh, std::back_inserter(pairs));
      if (accepted_non_orientable) {
        // faces that share a vertex of the uncut surface touch there: not an intersection
        auto shares_vertex = [&](std::size_t a, std::size_t b) {
          for (std::size_t x : polygons[a])
            for (std::size_t y : polygons[b])
              if (original[x] == original[y]) return true;
          return false;
        };
        pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                                   [&](const auto& p) { return shares_vertex(p.first.idx(), p.second.idx()); }),
                    pairs.end());
      }
      rep.self_intersecting_pairs = static_cast<long>(pairs.size());
      si.passed = pairs.empty();
      for (const auto& [a, b] : pairs) {
        if (static_cast<int>(si.where.size()) >= listed) break;
        si.where.push_back({static_cast<int>(a.idx()), static_cast<int>(b.idx())});
      }
      si.detail = pairs.empty() ? "ok" : std::to_string(pairs.size()) + " intersecting face pairs: " + join_items(si.where);
    }
  }
  if (!si.name.empty()) rep.checks.push_back(si);
}

}  // namespace

ValidationReport validate_triangle_mesh(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                                        const ValidationOptions& options) {
  const int nv = static_cast<int>(V.rows());
  if (F.rows() == 0) throw InvalidInputError("validate_triangle_mesh: the mesh has no faces");
  if (!V.allFinite()) throw InvalidInputError("validate_triangle_mesh: non-finite vertex coordinates");
  if (F.minCoeff() < 0 || F.maxCoeff() >= nv)
    throw InvalidInputError("validate_triangle_mesh: face index out of range [0, " + std::to_string(nv) + ")");
  const int listed = std::max(0, options.max_listed);
  ValidationReport rep;
  const Topology t = analyse(F, nv, listed);
  fill_topology(rep, t);
  const bool accepted_non_orientable = options.allow_non_orientable && t.orientable == 0;
  add_topology_checks(rep, t, options, accepted_non_orientable);
  add_cgal_checks(rep, cgal_soup(V, F, accepted_non_orientable), t, options, accepted_non_orientable, listed);
  return rep;
}

}  // namespace heatcvt
