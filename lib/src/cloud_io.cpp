// Point-cloud readers (PCD through PCL, PLY through the mesh PLY parser, XYZ-like text), clean-up
// and normalisation frames.
#include "heatcvt/cloud_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string_view>
#include <vector>

#include "heatcvt/errors.h"
#include "heatcvt/input_file.h"
#include "heatcvt/mesh_io.h"
#include "pcd_format.h"
#include "text_tokens.h"
#include "xyz_lines.h"

namespace heatcvt {

namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

void require_readable_file(const std::string& path) {
  std::error_code ec;
  require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file for reading");
  if (fs::file_size(path, ec) == 0) fail(path, "file is empty");
}

using detail::for_each_token;
using detail::parse_double;

// ------------------------------------------------------------------------------------------
// XYZ / PWN / TXT

PointCloud read_xyz(const std::string& path, CloudReadReport& rep) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string data = ss.str();
  std::vector<double> xyz, nrm;
  xyz.reserve(data.size() / 8);
  bool all_have_normals = true;
  bool first_data_line = true;
  long line_no = 0;
  size_t pos = 0;
  double vals[6];
  while (pos < data.size()) {
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    std::string_view line(data.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    int cols = 0;
    const detail::XyzLineKind kind = detail::read_xyz_line(line, first_data_line, path, line_no, vals, cols);
    if (kind == detail::XyzLineKind::blank) continue;
    first_data_line = false;
    if (kind != detail::XyzLineKind::values) continue;  // a column-name line or a point count
    if (cols < 3)
      fail(path, "line " + std::to_string(line_no) + ": expected at least 3 numbers (x y z), found " + std::to_string(cols));
    xyz.insert(xyz.end(), vals, vals + 3);
    if (cols >= 6) nrm.insert(nrm.end(), vals + 3, vals + 6);
    else all_have_normals = false;
  }
  PointCloud cloud;
  const Eigen::Index n = static_cast<Eigen::Index>(xyz.size() / 3);
  cloud.P = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), n, 3);
  if (all_have_normals && n > 0)
    cloud.N = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(nrm.data(), n, 3);
  rep.format = "xyz";
  rep.points_in_file = n;
  rep.width = static_cast<int>(n);
  rep.height = 1;
  return cloud;
}

// ------------------------------------------------------------------------------------------
// PCD

// Checks every line of an ASCII PCD body: the first `points` non-blank lines must hold exactly
// `values_per_point` numbers each (read_pcd_ascii_line), and nothing but blank lines may follow
// them (check_pcd_ascii_tail). `line_no` is the number of header lines.
void check_ascii_pcd_body(const std::string& path, std::istream& in, long long points, long long values_per_point,
                          int line_no) {
  std::string line;
  long long seen = 0;
  while (seen < points && std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (detail::read_pcd_ascii_line(path, line_no, line, values_per_point, [](std::string_view) {}) == 0) continue;
    ++seen;
  }
  if (seen < points)
    fail(path, "truncated: header announces " + std::to_string(points) + " points, file holds " + std::to_string(seen));
  detail::check_pcd_ascii_tail(path, line_no, points, [&](std::string& l) { return static_cast<bool>(std::getline(in, l)); });
}

// Checks the PCD header and the data size before handing the file to PCL, so that corrupt or
// truncated files give a clear error rather than relying on PCL's own checks.
void precheck_pcd(const std::string& path, std::string& data_kind, long long& header_points) {
  std::ifstream in(path, std::ios::binary);
  const auto file_size = static_cast<long long>(fs::file_size(path));
  const detail::PcdHeader h =
      detail::read_pcd_header(path, [&](std::string& line) { return static_cast<bool>(std::getline(in, line)); });
  data_kind = h.data_kind;
  header_points = h.points;
  const long long header_bytes = static_cast<long long>(in.tellg());
  const long long body = in ? file_size - header_bytes : 0;
  std::uint32_t compressed[2];
  detail::check_pcd_body_size(
      path, h, body, [&](char* dst, std::size_t n) { return static_cast<bool>(in.read(dst, static_cast<std::streamsize>(n))); },
      compressed);
  if (data_kind == "ascii") check_ascii_pcd_body(path, in, h.points, h.values_per_point(), h.lines);
}

double load_field(const uint8_t* p, uint8_t datatype) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8: return get(int8_t());
    case pcl::PCLPointField::UINT8: return get(uint8_t());
    case pcl::PCLPointField::INT16: return get(int16_t());
    case pcl::PCLPointField::UINT16: return get(uint16_t());
    case pcl::PCLPointField::INT32: return get(int32_t());
    case pcl::PCLPointField::UINT32: return get(uint32_t());
    case pcl::PCLPointField::FLOAT32: return get(float());
    case pcl::PCLPointField::FLOAT64: return get(double());
    case pcl::PCLPointField::INT64: return get(int64_t());
    case pcl::PCLPointField::UINT64: return get(uint64_t());
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

size_t field_size(uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: case pcl::PCLPointField::UINT8: return 1;
    case pcl::PCLPointField::INT16: case pcl::PCLPointField::UINT16: return 2;
    case pcl::PCLPointField::INT32: case pcl::PCLPointField::UINT32: case pcl::PCLPointField::FLOAT32: return 4;
    case pcl::PCLPointField::FLOAT64: case pcl::PCLPointField::INT64: case pcl::PCLPointField::UINT64: return 8;
    default: return 0;
  }
}

// Colour of a PCD point: PCL packs it into one 4-byte field, `rgb` (declared float) or `rgba`
// (declared uint32), whose bytes read as a little-endian uint32 are 0xAARRGGBB; some writers use
// separate r, g, b fields (uint8 in 0..255, or float in [0,1]).
void read_pcd_colours(const std::string& path, const pcl::PCLPointCloud2& blob, PointCloud& cloud) {
  const pcl::PCLPointField* packed = nullptr;
  const pcl::PCLPointField* sep[3] = {nullptr, nullptr, nullptr};
  for (const auto& field : blob.fields) {
    if (field.name == "rgb" || field.name == "rgba") packed = &field;
    if (field.name == "r") sep[0] = &field;
    if (field.name == "g") sep[1] = &field;
    if (field.name == "b") sep[2] = &field;
  }
  const Eigen::Index n = cloud.P.rows();
  if (packed) {
    if (field_size(packed->datatype) != 4 || packed->offset + 4 > blob.point_step)
      fail(path, "PCD field '" + packed->name + "' is not a packed 4-byte colour");
    cloud.C.resize(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
      const uint8_t* p = blob.data.data() + static_cast<size_t>(i) * blob.point_step + packed->offset;
      // Bytes in file order: blue, green, red, alpha.
      for (int k = 0; k < 3; ++k) cloud.C(i, k) = p[2 - k] / 255.0;
    }
    return;
  }
  if (!(sep[0] && sep[1] && sep[2])) return;
  for (const auto* field : sep)
    if (field_size(field->datatype) == 0 || field->offset + field_size(field->datatype) > blob.point_step)
      fail(path, "PCD colour field '" + field->name + "' has an unsupported type or lies outside the point");
  const bool integer = sep[0]->datatype != pcl::PCLPointField::FLOAT32 && sep[0]->datatype != pcl::PCLPointField::FLOAT64;
  cloud.C.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const uint8_t* base = blob.data.data() + static_cast<size_t>(i) * blob.point_step;
    for (int k = 0; k < 3; ++k) {
      const double v = load_field(base + sep[k]->offset, sep[k]->datatype);
      cloud.C(i, k) = std::clamp(integer ? v / 255.0 : v, 0.0, 1.0);
    }
  }
}

PointCloud read_pcd(const std::string& path, CloudReadReport& rep, const FlyingPixelOptions& flying) {
  std::string kind;
  long long header_points = 0;
  precheck_pcd(path, kind, header_points);
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int status = -1;
  // PCL prints its own diagnostics; we report one line ourselves, so silence it while loading.
  const pcl::console::VERBOSITY_LEVEL verbosity = pcl::console::getVerbosityLevel();
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  try {
    status = pcl::io::loadPCDFile(path, blob, origin, orientation);
  } catch (const std::exception& e) {
    pcl::console::setVerbosityLevel(verbosity);
    fail(path, std::string("PCL could not read the PCD file: ") + e.what());
  }
  pcl::console::setVerbosityLevel(verbosity);
  if (status < 0) fail(path, "PCL could not read the PCD file (malformed or truncated)");
  const long long n = static_cast<long long>(blob.width) * blob.height;
  if (n < header_points)  // PCL's ascii reader accepts short files with a warning
    fail(path, "truncated: header announces " + std::to_string(header_points) + " points, file holds " + std::to_string(n));
  if (static_cast<long long>(blob.data.size()) < n * static_cast<long long>(blob.point_step))
    fail(path, "truncated: PCD data holds fewer than " + std::to_string(n) + " points");
  const pcl::PCLPointField* f[6] = {nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
  static const char* names[6] = {"x", "y", "z", "normal_x", "normal_y", "normal_z"};
  for (const auto& field : blob.fields)
    for (int k = 0; k < 6; ++k)
      if (field.name == names[k]) f[k] = &field;
  for (int k = 0; k < 3; ++k) {
    if (!f[k]) fail(path, std::string("PCD file has no '") + names[k] + "' field");
  }
  const bool normals = f[3] && f[4] && f[5];
  for (int k = 0; k < (normals ? 6 : 3); ++k)
    if (field_size(f[k]->datatype) == 0 || f[k]->offset + field_size(f[k]->datatype) > blob.point_step)
      fail(path, std::string("PCD field '") + names[k] + "' has an unsupported type or lies outside the point");
  PointCloud cloud;
  cloud.P.resize(n, 3);
  if (normals) cloud.N.resize(n, 3);
  for (long long i = 0; i < n; ++i) {
    const uint8_t* base = blob.data.data() + i * blob.point_step;
    for (int k = 0; k < 3; ++k) cloud.P(i, k) = load_field(base + f[k]->offset, f[k]->datatype);
    if (normals)
      for (int k = 0; k < 3; ++k) cloud.N(i, k) = load_field(base + f[k + 3]->offset, f[k + 3]->datatype);
  }
  read_pcd_colours(path, blob, cloud);
  rep.format = "pcd-" + kind;
  rep.points_in_file = n;
  rep.width = static_cast<int>(blob.width);
  rep.height = static_cast<int>(blob.height);
  rep.sensor = origin.head<3>().cast<double>();
  if (blob.height > 1)
    rep.flying_pixels_removed = remove_flying_pixels(cloud.P, static_cast<int>(blob.width), static_cast<int>(blob.height),
                                                     origin.head<3>().cast<double>(), flying);
  return cloud;
}

// ------------------------------------------------------------------------------------------
// PLY (vertices of the mesh PLY parser)

PointCloud read_ply_cloud(const std::string& path, CloudReadReport& rep) {
  MeshReadReport mrep;
  PolygonSoup soup = read_polygon_soup(path, &mrep);
  PointCloud cloud;
  cloud.P = std::move(soup.V);
  cloud.N = std::move(soup.N);
  cloud.C = std::move(soup.C);
  rep.format = mrep.format;
  rep.points_in_file = cloud.P.rows();
  rep.width = static_cast<int>(cloud.P.rows());
  rep.height = 1;
  return cloud;
}

}  // namespace

void clean_cloud(PointCloud& cloud, CloudReadReport* report) {
  CloudReadReport local;
  CloudReadReport& rep = report ? *report : local;
  const Eigen::Index n = cloud.P.rows();
  const bool normals = cloud.N.rows() == n && n > 0;
  if (!normals) cloud.N.resize(0, 3);
  const bool colours = cloud.C.rows() == n && n > 0;
  if (!colours) cloud.C.resize(0, 3);
  std::vector<Eigen::Index> order;
  order.reserve(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    if (cloud.P.row(i).allFinite()) order.push_back(i);
    else ++rep.non_finite_dropped;
  }
  // Exact duplicates: sort finite points lexicographically (index as tie-break), keep the first.
  std::vector<Eigen::Index> sorted = order;
  std::sort(sorted.begin(), sorted.end(), [&](Eigen::Index a, Eigen::Index b) {
    for (int k = 0; k < 3; ++k)
      if (cloud.P(a, k) != cloud.P(b, k)) return cloud.P(a, k) < cloud.P(b, k);
    return a < b;
  });
  std::vector<char> keep(static_cast<size_t>(n), 0);
  for (size_t s = 0; s < sorted.size(); ++s) {
    if (s > 0 && (cloud.P.row(sorted[s]).array() == cloud.P.row(sorted[s - 1]).array()).all()) {
      ++rep.duplicates_merged;
      continue;
    }
    keep[static_cast<size_t>(sorted[s])] = 1;
  }
  Eigen::Index m = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!keep[static_cast<size_t>(i)]) continue;
    if (m != i) {
      cloud.P.row(m) = cloud.P.row(i);
      if (normals) cloud.N.row(m) = cloud.N.row(i);
      if (colours) cloud.C.row(m) = cloud.C.row(i);
    }
    ++m;
  }
  cloud.P.conservativeResize(m, 3);
  if (colours) cloud.C.conservativeResize(m, 3);
  if (normals) {
    cloud.N.conservativeResize(m, 3);
    bool any_nonzero = false;
    for (Eigen::Index i = 0; i < m; ++i) {
      if (!cloud.N.row(i).allFinite()) {
        cloud.N.row(i).setZero();
        ++rep.invalid_normals_zeroed;
      }
      if (!cloud.N.row(i).isZero(0.0)) any_nonzero = true;
    }
    if (!any_nonzero) {
      cloud.N.resize(0, 3);
      rep.normals_all_zero = true;
    }
  }
  rep.has_normals = cloud.has_normals();
  rep.has_colours = cloud.has_colours();
}

PointCloud read_cloud(const std::string& path, CloudReadReport* report, const CloudReadOptions& options) {
  CloudReadReport local;
  CloudReadReport& rep = report ? *report : local;
  rep = CloudReadReport();
  require_readable_file(path);  // before the extension: a directory is not "an unknown format"
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext != ".pcd" && ext != ".ply" && ext != ".xyz" && ext != ".pwn" && ext != ".txt")
    fail(path, "unknown point-cloud format " + quote_excerpt(ext) + " (expected .pcd, .ply, .xyz, .pwn or .txt)");
  PointCloud cloud;
  if (ext == ".pcd") cloud = read_pcd(path, rep, options.flying_pixels);
  else if (ext == ".ply") cloud = read_ply_cloud(path, rep);
  else cloud = read_xyz(path, rep);
  if (rep.points_in_file == 0) throw InvalidInputError(path + ": no points in the file");
  clean_cloud(cloud, &rep);
  rep.non_finite_dropped -= rep.flying_pixels_removed;  // finite pixels the flying-pixel rule set to NaN
  if (cloud.P.rows() == 0 && rep.flying_pixels_removed > 0)
    throw InvalidInputError(path + ": no point left: " + std::to_string(rep.non_finite_dropped) + " of its " +
                            std::to_string(rep.points_in_file) + " points are NaN/inf and the flying-pixel rule removed " +
                            "the " + std::to_string(rep.flying_pixels_removed) +
                            " others (CloudReadOptions::flying_pixels off, cloud2mesh --flying-pixels 0, keeps them)");
  if (cloud.P.rows() == 0)
    throw InvalidInputError(path + ": no finite points (all " + std::to_string(rep.points_in_file) + " points are NaN/inf)");
  rep.depth_steps = smooth_depth_steps(cloud.P, rep.sensor, options.depth_steps);
  return cloud;
}

CloudFrame normalize_cloud(PointCloud& cloud) { return normalize_positions(cloud.P); }

void write_cloud_xyz(const std::string& path, const PointCloud& cloud) {
  write_points_xyz(path, cloud.P, cloud.has_normals() ? cloud.N : Eigen::MatrixX3d());
}

}  // namespace heatcvt
