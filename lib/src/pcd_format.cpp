// PCD format pieces shared by the readers (pcd_format.h).
#include "pcd_format.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "heatcvt/errors.h"

namespace heatcvt::detail {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

// A header should reach DATA well before this many lines; beyond it the file is taken for another format.
constexpr int kMaxPcdHeaderLines = 1000;

}  // namespace

long long PcdHeader::point_step() const {
  long long step = 0;
  for (std::size_t k = 0; k < field_names.size(); ++k) step += sizes[k] * count(k);
  return step;
}

long long PcdHeader::values_per_point() const {
  long long n = 0;
  for (std::size_t k = 0; k < field_names.size(); ++k) n += count(k);
  return n;
}

PcdHeader read_pcd_header(const std::string& path, const std::function<bool(std::string&)>& getline) {
  PcdHeader h;
  std::string line;
  long long points = -1;
  bool have_data = false;
  while (getline(line)) {
    if (++h.lines > kMaxPcdHeaderLines) fail(path, "not a PCD file (no DATA line in the first " + std::to_string(kMaxPcdHeaderLines) + " lines)");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key.empty() || key[0] == '#') continue;
    if (key == "FIELDS" || key == "COLUMNS") {
      std::string f;
      while (ls >> f) {
        // A repeated name (two 'x' fields) would silently read one of them for both. '_' is
        // PCL's padding field (bytes skipped, never read), which may appear any number of times.
        if (f != "_" && std::find(h.field_names.begin(), h.field_names.end(), f) != h.field_names.end())
          fail(path, "malformed PCD header: the field " + quote_excerpt(f) + " is listed twice");
        h.field_names.push_back(f);
      }
    } else if (key == "SIZE" || key == "COUNT") {
      auto& dst = key == "SIZE" ? h.sizes : h.counts;
      std::string t;
      while (ls >> t) {
        long long v = 0;
        const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
        if (r.ec != std::errc() || v <= 0 || v > 1 << 20) fail(path, "malformed PCD " + key + " entry " + quote_excerpt(t));
        dst.push_back(v);
      }
    } else if (key == "TYPE") {
      std::string t;
      while (ls >> t) h.kinds.push_back(t.size() == 1 ? t[0] : '?');
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      std::string t;
      ls >> t;
      long long v = -1;
      const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
      if (r.ec != std::errc() || v < 0 || v > 2000000000LL) fail(path, "malformed PCD " + key + " " + quote_excerpt(t));
      (key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : points) = v;
    } else if (key == "DATA") {
      ls >> h.data_kind;
      have_data = true;
      break;
    } else if (key == "VIEWPOINT") {
      // tx ty tz qw qx qy qz: only the sensor position is used (ranges of organised clouds).
      for (double& t : h.viewpoint) {
        std::string tok;
        if (!(ls >> tok) || !parse_double(tok, t) || !std::isfinite(t))
          fail(path, "malformed PCD VIEWPOINT " + quote_excerpt(line));
      }
    } else if (key != "VERSION") {
      fail(path, "not a PCD file (unexpected header line " + quote_excerpt(line) + ")");
    }
  }
  const std::size_t nfields = h.field_names.size();
  if (!have_data) fail(path, "not a PCD file or truncated header (no DATA line)");
  if (nfields == 0 || h.sizes.size() != nfields) fail(path, "malformed PCD header (FIELDS and SIZE disagree)");
  if (!h.counts.empty() && h.counts.size() != nfields) fail(path, "malformed PCD header (FIELDS and COUNT disagree)");
  if (h.width < 0) fail(path, "malformed PCD header (no WIDTH)");
  if (points < 0) points = h.width * h.height;
  if (points != h.width * h.height)
    fail(path, "malformed PCD header: POINTS " + std::to_string(points) + " != WIDTH*HEIGHT " + std::to_string(h.width * h.height));
  h.points = points;
  return h;
}

void check_pcd_body_size(const std::string& path, const PcdHeader& h, long long body,
                         const std::function<bool(char*, std::size_t)>& read, std::uint32_t compressed[2]) {
  const long long points = h.points, point_step = h.point_step();
  if (h.data_kind == "binary") {
    if (points * point_step > body)
      fail(path, "truncated: header announces " + std::to_string(points) + " points (" + std::to_string(points * point_step) +
                     " bytes) but only " + std::to_string(body) + " bytes of data follow");
  } else if (h.data_kind == "binary_compressed") {
    compressed[0] = compressed[1] = 0;
    if (body < 8 || !read(reinterpret_cast<char*>(compressed), 8)) fail(path, "truncated: compressed PCD data missing");
    if (static_cast<long long>(compressed[0]) > body - 8)
      fail(path, "truncated: compressed block of " + std::to_string(compressed[0]) + " bytes but only " +
                     std::to_string(body - 8) + " bytes follow");
    if (static_cast<long long>(compressed[1]) != points * point_step)
      fail(path, "corrupt compressed PCD: uncompressed size " + std::to_string(compressed[1]) + " != " +
                     std::to_string(points * point_step) + " expected from the header");
  } else if (h.data_kind == "ascii") {
    if (points * 2 * static_cast<long long>(h.field_names.size()) > body + 1)
      fail(path, "truncated: header announces " + std::to_string(points) + " points but only " + std::to_string(body) +
                     " bytes follow");
  } else {
    fail(path, "unknown PCD DATA type " + quote_excerpt(h.data_kind));
  }
}

void check_pcd_ascii_tail(const std::string& path, long line_no, long long points,
                          const std::function<bool(std::string&)>& getline) {
  std::string line;
  while (getline(line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") != std::string::npos)
      fail(path, "line " + std::to_string(line_no) + ": data beyond the " + std::to_string(points) +
                     " points the header announces (POINTS, WIDTH x HEIGHT)");
  }
}

void pcd_ascii_number_error(const std::string& path, long line_no, std::string_view tok) {
  fail(path, "line " + std::to_string(line_no) + ": malformed number " + quote_excerpt(tok) +
                 (tok.find(',') != std::string_view::npos ? " (decimal commas are not allowed)" : ""));
}

void pcd_ascii_columns_error(const std::string& path, long line_no, long long cols, long long values_per_point) {
  fail(path, "line " + std::to_string(line_no) + ": " + std::to_string(cols) + " values, the header announces " +
                 std::to_string(values_per_point) + " per point");
}

}  // namespace heatcvt::detail
