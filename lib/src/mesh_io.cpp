// Mesh readers/writers: OBJ, OFF, PLY (ascii / binary LE / binary BE), STL (ascii / binary).
// Parsing works on the whole file held in memory; every count from a header is checked against
// the bytes actually present before anything is allocated.
#include "heatcvt/mesh_io.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>
#include <string_view>

#include "heatcvt/atomic_file.h"
#include "heatcvt/errors.h"
#include "heatcvt/input_file.h"
#include "ply_format.h"
#include "text_tokens.h"

namespace heatcvt {

namespace {

namespace fs = std::filesystem;

// ------------------------------------------------------------------------------------------
// Small utilities

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string extension_of(const std::string& path) { return lower(fs::path(path).extension().string()); }

std::string read_whole_file(const std::string& path) {
  require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open file: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "cannot determine file size");
  in.seekg(0, std::ios::beg);
  std::string data(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(data.data(), size)) fail(path, "read error");
  return data;
}

std::string quote(std::string_view s) { return quote_excerpt(s); }

using detail::is_space;
using detail::parse_double;
using detail::parse_int;
using detail::split;

// Iterates over the lines of a buffer.
class LineReader {
 public:
  explicit LineReader(std::string_view data, size_t start = 0) : data_(data), pos_(start) {}
  bool next(std::string_view& line) {
    if (pos_ >= data_.size()) return false;
    const size_t end = data_.find('\n', pos_);
    const size_t stop = end == std::string_view::npos ? data_.size() : end;
    line = data_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = stop + 1;
    ++line_no_;
    return true;
  }
  long line_no() const { return line_no_; }
  size_t pos() const { return std::min(pos_, data_.size()); }

 private:
  std::string_view data_;
  size_t pos_;
  long line_no_ = 0;
};

void push_polygon(PolygonSoup& soup, const std::vector<int>& poly) {
  soup.polygon_index.insert(soup.polygon_index.end(), poly.begin(), poly.end());
  soup.polygon_start.push_back(static_cast<int>(soup.polygon_index.size()));
}

constexpr long long kMaxCount = 2000000000LL;  // counts beyond int range are rejected

// ------------------------------------------------------------------------------------------
// OBJ

PolygonSoup read_obj(const std::string& path, const std::string& data, MeshReadReport& rep) {
  PolygonSoup soup;
  std::vector<Eigen::Vector3d> verts;
  verts.reserve(std::min<size_t>(data.size() / 24 + 16, 1u << 24));
  LineReader lines(data);
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<int> poly;
  const std::string where = path + ": line ";
  while (lines.next(line)) {
    size_t i = 0;
    while (i < line.size() && is_space(line[i])) ++i;
    if (i == line.size() || line[i] == '#') continue;
    split(line, tok);
    const std::string_view key = tok[0];
    if (key == "v") {
      if (tok.size() < 4) throw IOError(where + std::to_string(lines.line_no()) + ": vertex needs 3 coordinates");
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k)
        if (!parse_double(tok[k + 1], p[k]))
          throw IOError(where + std::to_string(lines.line_no()) + ": malformed number " + quote(tok[k + 1]));
      verts.push_back(p);
    } else if (key == "f") {
      poly.clear();
      for (size_t k = 1; k < tok.size(); ++k) {
        std::string_view t = tok[k];
        const size_t slash = t.find('/');
        if (slash != std::string_view::npos) t = t.substr(0, slash);
        long long idx = 0;
        if (!parse_int(t, idx) || idx == 0)
          throw IOError(where + std::to_string(lines.line_no()) + ": malformed face index " + quote(tok[k]));
        const long long nv = static_cast<long long>(verts.size());
        const long long resolved = idx > 0 ? idx - 1 : nv + idx;
        if (resolved < 0 || resolved >= nv)
          throw IOError(where + std::to_string(lines.line_no()) + ": face index " + std::to_string(idx) +
                        " out of range (" + std::to_string(nv) + " vertices defined so far)");
        poly.push_back(static_cast<int>(resolved));
      }
      push_polygon(soup, poly);
    } else if (key == "vn") {
      rep.has_vertex_normals = true;
    }
    // vt, vp, l, p, g, o, s, usemtl, mtllib, ... are ignored.
  }
  soup.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t k = 0; k < verts.size(); ++k) soup.V.row(static_cast<Eigen::Index>(k)) = verts[k].transpose();
  rep.format = "obj";
  return soup;
}

// ------------------------------------------------------------------------------------------
// OFF

PolygonSoup read_off(const std::string& path, const std::string& data, MeshReadReport& rep) {
  LineReader lines(data);
  std::string_view line;
  std::vector<std::string_view> tok;
  // next non-empty line with '#' comments removed
  auto next_tokens = [&]() -> bool {
    while (lines.next(line)) {
      const size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      split(line, tok);
      if (!tok.empty()) return true;
    }
    return false;
  };
  auto at = [&](const std::string& problem) {
    // A short last line means the file was cut off.
    const bool last = lines.pos() >= data.size();
    return IOError(path + ": line " + std::to_string(lines.line_no()) + ": " + (last ? "truncated: " : "") + problem);
  };
  if (!next_tokens()) fail(path, "empty OFF file");
  const std::string head(tok[0]);
  size_t first_count = 1;
  if (head.size() < 3 || head.compare(head.size() - 3, 3, "OFF") != 0) fail(path, "missing OFF header (found " + quote(head) + ")");
  if (head.find('4') != std::string::npos || (head.size() > 3 && head[head.size() - 4] == 'n'))
    fail(path, "unsupported OFF variant " + quote(head) + " (only 3D OFF/COFF/NOFF/STOFF)");
  if (tok.size() > 1 && tok[1] == "BINARY") fail(path, "binary OFF is not supported");
  std::vector<std::string_view> counts(tok.begin() + static_cast<long>(first_count), tok.end());
  if (counts.empty()) {
    if (!next_tokens()) fail(path, "truncated: missing vertex/face counts");
    counts = tok;
  }
  long long nv = -1, nf = -1;
  if (counts.size() < 2 || !parse_int(counts[0], nv) || !parse_int(counts[1], nf) || nv < 0 || nf < 0 || nv > kMaxCount ||
      nf > kMaxCount)
    throw at("malformed vertex/face counts");
  // Every vertex line needs at least 6 bytes ("0 0 0\n"), every face line at least 2 ("0\n").
  const long long remaining = static_cast<long long>(data.size() - lines.pos());
  if (nv * 6 + nf * 2 > remaining + 1)
    fail(path, "truncated: header announces " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                   " faces but only " + std::to_string(remaining) + " bytes follow");
  PolygonSoup soup;
  soup.V.resize(nv, 3);
  for (long long i = 0; i < nv; ++i) {
    if (!next_tokens())
      fail(path, "truncated: header announces " + std::to_string(nv) + " vertices, file ends after " + std::to_string(i));
    if (tok.size() < 3) throw at("vertex needs 3 coordinates");
    for (int k = 0; k < 3; ++k)
      if (!parse_double(tok[k], soup.V(i, k))) throw at("malformed number " + quote(tok[k]));
  }
  soup.polygon_index.reserve(static_cast<size_t>(std::min<long long>(nf * 3, remaining)));
  std::vector<int> poly;
  for (long long f = 0; f < nf; ++f) {
    if (!next_tokens())
      fail(path, "truncated: header announces " + std::to_string(nf) + " faces, file ends after " + std::to_string(f));
    long long n = 0;
    if (!parse_int(tok[0], n) || n < 0) throw at("malformed face size " + quote(tok[0]));
    if (static_cast<long long>(tok.size()) < n + 1)
      throw at("face announces " + std::to_string(n) + " corners but lists " + std::to_string(tok.size() - 1));
    poly.clear();
    for (long long k = 1; k <= n; ++k) {
      long long idx = 0;
      if (!parse_int(tok[static_cast<size_t>(k)], idx)) throw at("malformed face index " + quote(tok[static_cast<size_t>(k)]));
      if (idx < 0 || idx >= nv)
        throw at("face index " + std::to_string(idx) + " out of range (" + std::to_string(nv) + " vertices)");
      poly.push_back(static_cast<int>(idx));
    }
    push_polygon(soup, poly);  // trailing colour columns ignored
  }
  rep.format = "off";
  if (head.find('N') != std::string::npos) rep.has_vertex_normals = true;
  return soup;
}

// ------------------------------------------------------------------------------------------
// PLY

using detail::host_is_little_endian;
using detail::load_raw;
using detail::load_value;
using detail::ply_is_integer;
using detail::ply_size;
using detail::PlyElement;
using detail::PlyProperty;
using detail::PlyType;

// Sequential value source over the PLY body: binary (with optional byte swap) or ascii tokens.
class PlyBody {
 public:
  PlyBody(const std::string& path, std::string_view data, size_t start, bool ascii, bool swap)
      : path_(path), data_(data), pos_(start), ascii_(ascii), swap_(swap) {}
  size_t remaining() const { return data_.size() - std::min(pos_, data_.size()); }
  bool ascii() const { return ascii_; }
  // Whether only whitespace is left (ascii).
  bool only_space_left() const {
    for (size_t i = pos_; i < data_.size(); ++i)
      if (!is_space(data_[i])) return false;
    return true;
  }

  // Reads one value; `context` describes the position for error messages.
  template <typename Context>
  double read(PlyType t, const Context& context) {
    if (ascii_) {
      while (pos_ < data_.size() && is_space(data_[pos_])) ++pos_;
      if (pos_ >= data_.size()) fail(path_, "truncated: data ends in " + context());
      size_t end = pos_;
      while (end < data_.size() && !is_space(data_[end])) ++end;
      const std::string_view tok = data_.substr(pos_, end - pos_);
      pos_ = end;
      return detail::ply_ascii_value(path_, tok, t, context);
    }
    const size_t n = ply_size(t);
    if (remaining() < n) fail(path_, "truncated: binary data ends in " + context());
    const double v = load_value(data_.data() + pos_, t, swap_);
    pos_ += n;
    return v;
  }

 private:
  const std::string& path_;
  std::string_view data_;
  size_t pos_;
  bool ascii_;
  bool swap_;
};

PolygonSoup read_ply(const std::string& path, const std::string& data, MeshReadReport& rep) {
  LineReader lines(data);
  const detail::PlyHeader header =
      detail::read_ply_header(path, [&](std::string_view& line) { return lines.next(line); });
  const std::string& format = header.format;
  const std::vector<PlyElement>& elements = header.elements;
  const bool ascii = header.ascii;
  const bool swap = header.swap;
  PlyBody body(path, data, lines.pos(), ascii, swap);
  rep.format = "ply-" + format;

  PolygonSoup soup;
  bool have_vertices = false;
  long long num_vertices = -1;
  for (const auto& el : elements) {
    if (el.name == "vertex" && num_vertices < 0) num_vertices = el.count;
  }
  for (const auto& el : elements) {
    // Minimal bytes per instance, checked before any allocation.
    const size_t min_bytes = detail::ply_min_bytes(el, ascii);
    detail::check_ply_element_fits(path, el, min_bytes, static_cast<std::int64_t>(body.remaining()));
    const bool is_vertex = el.name == "vertex" && !have_vertices;
    const bool is_face = el.name == "face";
    int col[9] = {-1, -1, -1, -1, -1, -1, -1, -1, -1};
    double colour_scale = 1.0;  // uchar/ushort colours are scaled to [0,1]; float colours are taken as [0,1]
    int face_list = -1;
    if (is_vertex) {
      detail::ply_vertex_columns(path, el.props, col);
      have_vertices = true;
      soup.V.resize(el.count, 3);
      if (col[3] >= 0 && col[4] >= 0 && col[5] >= 0) {
        soup.N.resize(el.count, 3);
        rep.has_vertex_normals = true;
      }
      if (col[6] >= 0 && col[7] >= 0 && col[8] >= 0) {
        soup.C.resize(el.count, 3);
        colour_scale = detail::ply_colour_scale(el.props[static_cast<size_t>(col[6])].type);
      }
    }
    if (is_face) {
      for (size_t j = 0; j < el.props.size(); ++j)
        if (el.props[j].is_list && (el.props[j].name == "vertex_indices" || el.props[j].name == "vertex_index"))
          face_list = static_cast<int>(j);
      if (face_list < 0) fail(path, "PLY face element has no vertex_indices/vertex_index list");
      soup.polygon_index.reserve(static_cast<size_t>(std::min<long long>(el.count * 3, 1 << 26)));
    }
    std::vector<int> poly;
    if (el.props.empty()) continue;  // occupies no bytes, whatever its count
    for (long long i = 0; i < el.count; ++i) {
      for (size_t j = 0; j < el.props.size(); ++j) {
        const auto& p = el.props[j];
        auto context = [&]() { return el.name + " " + std::to_string(i) + " of " + std::to_string(el.count) + " (property " + p.name + ")"; };
        if (!p.is_list) {
          const double v = body.read(p.type, context);
          if (is_vertex) {
            for (int k = 0; k < 9; ++k)
              if (col[k] == static_cast<int>(j)) {
                if (k < 3) soup.V(i, k) = v;
                else if (k < 6 && soup.N.rows() > 0) soup.N(i, k - 3) = v;
                else if (k >= 6 && soup.C.rows() > 0) soup.C(i, k - 6) = std::clamp(v * colour_scale, 0.0, 1.0);
              }
          }
          continue;
        }
        const double cnt = body.read(p.count_type, context);
        if (!(cnt >= 0)) fail(path, "negative or invalid list length in " + context());
        if (!(cnt <= static_cast<double>(body.remaining())))
          fail(path, "truncated: list longer than the remaining data in " + context());
        const size_t n = static_cast<size_t>(cnt);
        if (!ascii && n * ply_size(p.type) > body.remaining())
          fail(path, "truncated: binary data ends in " + context());
        if (is_face && static_cast<int>(j) == face_list) {
          poly.clear();
          for (size_t k = 0; k < n; ++k) {
            const double idx = body.read(p.type, context);
            // Negated comparisons so that a NaN index (float-typed lists) is rejected too.
            if (!(idx >= 0 && idx < static_cast<double>(std::max<long long>(num_vertices, 0))) || idx != std::floor(idx))
              fail(path, "face " + std::to_string(i) + ": vertex index " + format_double(idx) + " out of range (" +
                             std::to_string(std::max<long long>(num_vertices, 0)) + " vertices)");
            poly.push_back(static_cast<int>(idx));
          }
          push_polygon(soup, poly);
        } else {
          for (size_t k = 0; k < n; ++k) body.read(p.type, context);
        }
      }
      if (!ascii && body.remaining() == 0 && i + 1 < el.count && min_bytes > 0)
        fail(path, "truncated: binary data ends after " + std::to_string(i + 1) + " of " + std::to_string(el.count) + " " +
                       el.name + " elements");
    }
  }
  if (!have_vertices) fail(path, "PLY file has no vertex element");
  // Values left after the last element: the header declares fewer than the file holds (a wrong
  // count); refused rather than read in part.
  if (ascii && !body.only_space_left()) fail(path, "more values than the header declares (a wrong element count?)");
  return soup;
}

// ------------------------------------------------------------------------------------------
// STL

struct Vec3Less {
  bool operator()(const std::array<double, 3>& a, const std::array<double, 3>& b) const {
    return a < b;  // -0.0 == 0.0 under operator<, so signed zeros weld
  }
};

PolygonSoup read_stl(const std::string& path, const std::string& data, MeshReadReport& rep) {
  std::vector<std::array<double, 3>> corners;
  std::vector<int> loop_sizes;
  bool binary = false;
  if (data.size() >= 84) {
    const uint32_t n = load_raw<uint32_t>(data.data() + 80, !host_is_little_endian());
    if (84 + 50ull * n == data.size()) binary = true;
  }
  const bool starts_solid = data.size() >= 5 && lower(data.substr(0, 5)) == "solid";
  if (binary) {
    const uint32_t n = load_raw<uint32_t>(data.data() + 80, !host_is_little_endian());
    corners.reserve(3ull * n);
    for (uint32_t t = 0; t < n; ++t) {
      const char* rec = data.data() + 84 + 50ull * t + 12;
      for (int c = 0; c < 3; ++c) {
        std::array<double, 3> p;
        for (int k = 0; k < 3; ++k) p[k] = load_raw<float>(rec + 12 * c + 4 * k, !host_is_little_endian());
        corners.push_back(p);
      }
      loop_sizes.push_back(3);
    }
    rep.format = "stl-binary";
  } else if (starts_solid) {
    LineReader lines(data);
    std::string_view line;
    std::vector<std::string_view> tok;
    int in_loop = -1;
    while (lines.next(line)) {
      split(line, tok);
      if (tok.empty()) continue;
      const std::string key = lower(std::string(tok[0]));
      auto at = [&](const std::string& problem) {
        return IOError(path + ": line " + std::to_string(lines.line_no()) + ": " + problem);
      };
      if (key == "vertex") {
        if (in_loop < 0) throw at("vertex outside 'outer loop'");
        if (tok.size() < 4) throw at("vertex needs 3 coordinates");
        std::array<double, 3> p;
        for (int k = 0; k < 3; ++k)
          if (!parse_double(tok[k + 1], p[k])) throw at("malformed number " + quote(tok[k + 1]));
        corners.push_back(p);
        ++in_loop;
      } else if (key == "outer") {
        in_loop = 0;
      } else if (key == "endloop") {
        if (in_loop < 0) throw at("endloop without outer loop");
        loop_sizes.push_back(in_loop);
        in_loop = -1;
      }
    }
    if (in_loop >= 0) fail(path, "truncated: file ends inside a facet");
    rep.format = "stl-ascii";
  } else {
    if (data.size() < 84) fail(path, "truncated: binary STL shorter than its 84-byte header");
    const uint32_t n = load_raw<uint32_t>(data.data() + 80, !host_is_little_endian());
    fail(path, "truncated or corrupt binary STL: header announces " + std::to_string(n) + " triangles (" +
                   std::to_string(84 + 50ull * n) + " bytes) but the file has " + std::to_string(data.size()) + " bytes");
  }
  PolygonSoup soup;
  std::map<std::array<double, 3>, int, Vec3Less> weld;
  std::vector<std::array<double, 3>> unique;
  soup.polygon_index.reserve(corners.size());
  for (const auto& p : corners) {
    auto [it, inserted] = weld.emplace(p, static_cast<int>(unique.size()));
    if (inserted) unique.push_back(p);
    else ++rep.welded_vertices;
    soup.polygon_index.push_back(it->second);
  }
  int offset = 0;
  for (int s : loop_sizes) {
    offset += s;
    soup.polygon_start.push_back(offset);
  }
  soup.V.resize(static_cast<Eigen::Index>(unique.size()), 3);
  for (size_t i = 0; i < unique.size(); ++i)
    for (int k = 0; k < 3; ++k) soup.V(static_cast<Eigen::Index>(i), k) = unique[i][k];
  rep.vertices_in_file = static_cast<int>(corners.size());
  return soup;
}

// ------------------------------------------------------------------------------------------
// Triangulation

// Ear clipping of one polygon (distinct consecutive corners) in its Newell plane; fan fallback.
void triangulate_polygon(const Eigen::MatrixX3d& V, const std::vector<int>& poly, std::vector<Eigen::Vector3i>& out) {
  const size_t n = poly.size();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = V.row(poly[i]).transpose();
    const Eigen::Vector3d b = V.row(poly[(i + 1) % n]).transpose();
    normal += a.cross(b);
  }
  auto fan = [&](const std::vector<int>& p) {
    for (size_t i = 1; i + 1 < p.size(); ++i) out.emplace_back(p[0], p[i], p[i + 1]);
  };
  // Ear clipping costs O(n^3) in the worst case: very large polygons (never seen in real meshes,
  // easily produced by corrupt files) are fanned so that no input can make the reader hang.
  constexpr size_t kMaxEarClippingCorners = 256;
  if (n > kMaxEarClippingCorners || !(normal.norm() > 0) || !std::isfinite(normal.norm())) {
    fan(poly);
    return;
  }
  normal.normalize();
  Eigen::Vector3d u = std::abs(normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  u = (u - u.dot(normal) * normal).normalized();
  const Eigen::Vector3d w = normal.cross(u);
  std::vector<Eigen::Vector2d> q(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = V.row(poly[i]).transpose();
    q[i] = Eigen::Vector2d(p.dot(u), p.dot(w));
  }
  auto cross2 = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
  };
  std::vector<size_t> rem(n);
  for (size_t i = 0; i < n; ++i) rem[i] = i;
  while (rem.size() > 3) {
    bool clipped = false;
    const size_t m = rem.size();
    for (size_t s = 0; s < m && !clipped; ++s) {
      const size_t i = (s + 1) % m;  // start at the second corner: convex polygons give the fan
      const size_t a = rem[(i + m - 1) % m], b = rem[i], c = rem[(i + 1) % m];
      if (cross2(q[a], q[b], q[c]) <= 0) continue;  // reflex or flat corner
      bool empty = true;
      for (size_t j = 0; j < m && empty; ++j) {
        const size_t d = rem[j];
        if (d == a || d == b || d == c) continue;
        if (cross2(q[a], q[b], q[d]) >= 0 && cross2(q[b], q[c], q[d]) >= 0 && cross2(q[c], q[a], q[d]) >= 0) empty = false;
      }
      if (!empty) continue;
      out.emplace_back(poly[a], poly[b], poly[c]);
      rem.erase(rem.begin() + static_cast<long>(i));
      clipped = true;
    }
    if (!clipped) break;
  }
  std::vector<int> rest;
  for (size_t r : rem) rest.push_back(poly[r]);
  fan(rest);
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Public readers

PolygonSoup read_polygon_soup(const std::string& path, MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& rep = report ? *report : local;
  rep = MeshReadReport();
  require_regular_file(path);  // before the extension: a directory is not "an unknown format"
  const std::string ext = extension_of(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(path, "unknown mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  const std::string data = read_whole_file(path);
  if (data.empty()) fail(path, "file is empty");
  PolygonSoup soup;
  if (ext == ".obj") soup = read_obj(path, data, rep);
  else if (ext == ".off") soup = read_off(path, data, rep);
  else if (ext == ".ply") soup = read_ply(path, data, rep);
  else soup = read_stl(path, data, rep);
  if (ext != ".stl") rep.vertices_in_file = static_cast<int>(soup.V.rows());
  rep.polygons_in_file = soup.num_polygons();
  return soup;
}

TriangleMesh read_mesh(const std::string& path, MeshReadReport* report) {
  MeshReadReport local;
  MeshReadReport& rep = report ? *report : local;
  const PolygonSoup soup = read_polygon_soup(path, &rep);
  const Eigen::MatrixX3d& V = soup.V;
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (!V.row(i).allFinite())
      throw InvalidInputError(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate (" +
                              format_double(V(i, 0)) + " " + format_double(V(i, 1)) + " " + format_double(V(i, 2)) + ")");
  std::vector<Eigen::Vector3i> tris;
  tris.reserve(soup.polygon_index.size() / 3 + 1);
  std::vector<int> poly;
  for (int f = 0; f < soup.num_polygons(); ++f) {
    poly.clear();
    for (int k = soup.polygon_start[f]; k < soup.polygon_start[f + 1]; ++k) {
      const int v = soup.polygon_index[k];
      if (poly.empty() || poly.back() != v) poly.push_back(v);
    }
    while (poly.size() > 1 && poly.front() == poly.back()) poly.pop_back();
    std::vector<int> sorted = poly;
    std::sort(sorted.begin(), sorted.end());
    const bool repeated = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
    if (poly.size() < 3 || (poly.size() == 3 && repeated)) {
      ++rep.degenerate_faces_dropped;
      continue;
    }
    if (poly.size() == 3) {
      tris.emplace_back(poly[0], poly[1], poly[2]);
      continue;
    }
    const size_t before = tris.size();
    triangulate_polygon(V, poly, tris);
    ++rep.polygons_triangulated;
    // A polygon that revisits a vertex can yield triangles with a repeated corner: drop them.
    size_t kept = before;
    for (size_t t = before; t < tris.size(); ++t) {
      const auto& tri = tris[t];
      if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) tris[kept++] = tri;
      else ++rep.degenerate_faces_dropped;
    }
    tris.resize(kept);
    rep.triangles_from_polygons += static_cast<int>(kept - before);
  }
  if (tris.empty()) throw InvalidInputError(path + ": no faces (the file contains no usable triangles or polygons)");
  // Drop unreferenced vertices, keeping the order of the others.
  std::vector<int> remap(static_cast<size_t>(V.rows()), -1);
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) remap[static_cast<size_t>(t[k])] = 0;
  int next = 0;
  for (auto& r : remap)
    if (r == 0) r = next++;
  rep.unreferenced_vertices_dropped = static_cast<int>(V.rows()) - next;
  TriangleMesh mesh;
  mesh.V.resize(next, 3);
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (remap[static_cast<size_t>(i)] >= 0) mesh.V.row(remap[static_cast<size_t>(i)]) = V.row(i);
  mesh.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t) {
    for (int k = 0; k < 3; ++k) mesh.F(static_cast<Eigen::Index>(t), k) = remap[static_cast<size_t>(tris[t][k])];
    const Eigen::Vector3d a = mesh.V.row(mesh.F(static_cast<Eigen::Index>(t), 0));
    const Eigen::Vector3d b = mesh.V.row(mesh.F(static_cast<Eigen::Index>(t), 1));
    const Eigen::Vector3d c = mesh.V.row(mesh.F(static_cast<Eigen::Index>(t), 2));
    if ((b - a).cross(c - a).squaredNorm() == 0.0) ++rep.zero_area_triangles;
  }
  return mesh;
}

// ------------------------------------------------------------------------------------------
// Writers

namespace {

void check_mesh_for_writing(const std::string& path, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F,
                            const MeshAttributes& attr) {
  if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows()))
    throw InvalidInputError(path + ": cannot write, face index out of range (" + std::to_string(V.rows()) + " vertices)");
  if (attr.face_int.size() > 0 && attr.face_int.size() != F.rows())
    throw InvalidInputError(path + ": cannot write, face_int has " + std::to_string(attr.face_int.size()) + " entries for " +
                            std::to_string(F.rows()) + " faces");
  if (attr.face_color.rows() > 0 && attr.face_color.rows() != F.rows())
    throw InvalidInputError(path + ": cannot write, face_color has " + std::to_string(attr.face_color.rows()) +
                            " rows for " + std::to_string(F.rows()) + " faces");
  if (attr.vertex_color.rows() > 0 && attr.vertex_color.rows() != V.rows())
    throw InvalidInputError(path + ": cannot write, vertex_color has " + std::to_string(attr.vertex_color.rows()) +
                            " rows for " + std::to_string(V.rows()) + " vertices");
  if (attr.vertex_normal.rows() > 0 && attr.vertex_normal.rows() != V.rows())
    throw InvalidInputError(path + ": cannot write, vertex_normal has " + std::to_string(attr.vertex_normal.rows()) +
                            " rows for " + std::to_string(V.rows()) + " vertices");
}

unsigned char to_byte(double c) {
  if (!std::isfinite(c)) return 0;
  return static_cast<unsigned char>(std::lround(std::clamp(c, 0.0, 1.0) * 255.0));
}

class BinaryWriter {
 public:
  explicit BinaryWriter(bool big_endian) : swap_(big_endian == host_is_little_endian()) {}
  template <typename T>
  void put(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    buf_.append(reinterpret_cast<const char*>(b), sizeof(T));
  }
  std::string& buffer() { return buf_; }

 private:
  bool swap_;
  std::string buf_;
};

void write_ply(std::ostream& out, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const MeshAttributes& attr,
               PlyEncoding enc) {
  const bool vcol = attr.vertex_color.rows() > 0, fcol = attr.face_color.rows() > 0, fint = attr.face_int.size() > 0;
  const bool vnor = attr.vertex_normal.rows() > 0;
  std::ostringstream h;
  h << "ply\nformat "
    << (enc == PlyEncoding::ascii ? "ascii" : enc == PlyEncoding::binary_big_endian ? "binary_big_endian" : "binary_little_endian")
    << " 1.0\ncomment written by heatcvt\nelement vertex " << V.rows()
    << "\nproperty double x\nproperty double y\nproperty double z\n";
  if (vnor) h << "property float nx\nproperty float ny\nproperty float nz\n";
  if (vcol) h << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  h << "element face " << F.rows() << "\nproperty list uchar int vertex_indices\n";
  if (fint) h << "property int " << attr.face_int_name << "\n";
  if (fcol) h << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  h << "end_header\n";
  out << h.str();
  if (enc == PlyEncoding::ascii) {
    std::string s;
    for (Eigen::Index i = 0; i < V.rows(); ++i) {
      s = format_double(V(i, 0)) + " " + format_double(V(i, 1)) + " " + format_double(V(i, 2));
      if (vnor)
        for (int k = 0; k < 3; ++k) s += " " + format_double(static_cast<float>(attr.vertex_normal(i, k)));
      if (vcol)
        for (int k = 0; k < 3; ++k) s += " " + std::to_string(to_byte(attr.vertex_color(i, k)));
      out << s << '\n';
    }
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      out << "3 " << F(f, 0) << ' ' << F(f, 1) << ' ' << F(f, 2);
      if (fint) out << ' ' << attr.face_int[f];
      if (fcol)
        for (int k = 0; k < 3; ++k) out << ' ' << static_cast<int>(to_byte(attr.face_color(f, k)));
      out << '\n';
    }
    return;
  }
  BinaryWriter w(enc == PlyEncoding::binary_big_endian);
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    for (int k = 0; k < 3; ++k) w.put<double>(V(i, k));
    if (vnor)
      for (int k = 0; k < 3; ++k) w.put<float>(static_cast<float>(attr.vertex_normal(i, k)));
    if (vcol)
      for (int k = 0; k < 3; ++k) w.put<unsigned char>(to_byte(attr.vertex_color(i, k)));
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    w.put<unsigned char>(3);
    for (int k = 0; k < 3; ++k) w.put<int32_t>(F(f, k));
    if (fint) w.put<int32_t>(attr.face_int[f]);
    if (fcol)
      for (int k = 0; k < 3; ++k) w.put<unsigned char>(to_byte(attr.face_color(f, k)));
  }
  out.write(w.buffer().data(), static_cast<std::streamsize>(w.buffer().size()));
}

void write_obj(std::ostream& out, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const MeshAttributes& attr) {
  out << "# written by heatcvt\n";
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    out << "v " << format_double(V(i, 0)) << ' ' << format_double(V(i, 1)) << ' ' << format_double(V(i, 2));
    if (attr.vertex_color.rows() > 0)
      for (int k = 0; k < 3; ++k) out << ' ' << format_double(attr.vertex_color(i, k));
    out << '\n';
  }
  const bool vnor = attr.vertex_normal.rows() > 0;
  for (Eigen::Index i = 0; vnor && i < V.rows(); ++i)
    out << "vn " << format_double(attr.vertex_normal(i, 0)) << ' ' << format_double(attr.vertex_normal(i, 1)) << ' '
        << format_double(attr.vertex_normal(i, 2)) << '\n';
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    out << 'f';
    for (int k = 0; k < 3; ++k) {
      out << ' ' << F(f, k) + 1;
      if (vnor) out << "//" << F(f, k) + 1;
    }
    out << '\n';
  }
}

void write_off(std::ostream& out, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const MeshAttributes& attr) {
  out << "OFF\n" << V.rows() << ' ' << F.rows() << " 0\n";
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    out << format_double(V(i, 0)) << ' ' << format_double(V(i, 1)) << ' ' << format_double(V(i, 2)) << '\n';
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    out << "3 " << F(f, 0) << ' ' << F(f, 1) << ' ' << F(f, 2);
    if (attr.face_color.rows() > 0)
      for (int k = 0; k < 3; ++k) out << ' ' << format_double(std::clamp(attr.face_color(f, k), 0.0, 1.0));
    out << '\n';
  }
}

void write_stl(std::ostream& out, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F) {
  BinaryWriter w(false);
  std::string header = "binary STL written by heatcvt";
  header.resize(80, ' ');
  w.buffer() = header;
  w.put<uint32_t>(static_cast<uint32_t>(F.rows()));
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() > 0) n.normalize();
    for (int k = 0; k < 3; ++k) w.put<float>(static_cast<float>(n[k]));
    for (const Eigen::Vector3d* p : {&a, &b, &c})
      for (int k = 0; k < 3; ++k) w.put<float>(static_cast<float>((*p)[k]));
    w.put<uint16_t>(0);
  }
  out.write(w.buffer().data(), static_cast<std::streamsize>(w.buffer().size()));
}

}  // namespace

void write_mesh(const std::string& path, const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, const MeshAttributes& attr,
                const MeshWriteOptions& options) {
  const std::string ext = extension_of(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(path, "unknown mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  check_mesh_for_writing(path, V, F, attr);
  write_atomically(path, [&](std::ostream& out) {
    if (ext == ".ply") write_ply(out, V, F, attr, options.ply_encoding);
    else if (ext == ".obj") write_obj(out, V, F, attr);
    else if (ext == ".off") write_off(out, V, F, attr);
    else write_stl(out, V, F);
  });
}

void write_polylines_obj(const std::string& path, const Eigen::MatrixX3d& points,
                         const std::vector<std::vector<int>>& polylines) {
  for (size_t l = 0; l < polylines.size(); ++l)
    for (int i : polylines[l])
      if (i < 0 || i >= points.rows())
        throw InvalidInputError(path + ": cannot write, polyline " + std::to_string(l) + " references point " +
                                std::to_string(i) + " of " + std::to_string(points.rows()));
  write_atomically(path, [&](std::ostream& out) {
    out << "# written by heatcvt\n";
    for (Eigen::Index i = 0; i < points.rows(); ++i)
      out << "v " << format_double(points(i, 0)) << ' ' << format_double(points(i, 1)) << ' ' << format_double(points(i, 2)) << '\n';
    for (const auto& line : polylines) {
      if (line.size() < 2) continue;
      out << 'l';
      for (int i : line) out << ' ' << i + 1;
      out << '\n';
    }
  });
}

void write_points_xyz(const std::string& path, const Eigen::MatrixX3d& P, const Eigen::MatrixX3d& N) {
  if (N.rows() > 0 && N.rows() != P.rows())
    throw InvalidInputError(path + ": cannot write, " + std::to_string(N.rows()) + " normals for " +
                            std::to_string(P.rows()) + " points");
  write_atomically(path, [&](std::ostream& out) {
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      out << format_double(P(i, 0)) << ' ' << format_double(P(i, 1)) << ' ' << format_double(P(i, 2));
      if (N.rows() > 0) out << ' ' << format_double(N(i, 0)) << ' ' << format_double(N(i, 1)) << ' ' << format_double(N(i, 2));
      out << '\n';
    }
  });
}

}  // namespace heatcvt
