#pragma once
// Internal PCD format pieces shared by the whole-file cloud reader (cloud_io.cpp, which hands the
// file to PCL after these checks) and the streaming reader (cloud_stream_pcd.cpp): the header
// parser with its consistency checks, the check of the body size against the header, and the
// strict reading of one ascii body line. Not installed.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "text_tokens.h"

namespace heatcvt::detail {

struct PcdHeader {
  std::vector<std::string> field_names;  // FIELDS (or COLUMNS), each name once but '_' (padding)
  std::vector<long long> sizes;          // SIZE, one per field
  std::vector<long long> counts;         // COUNT, one per field, or empty (1 each)
  std::vector<char> kinds;               // TYPE entries ('?' for one that is not a single letter)
  long long width = -1, height = 1;
  double viewpoint[3] = {0, 0, 0};  // VIEWPOINT translation: the sensor position (origin if absent)
  long long points = 0;   // POINTS, = width * height
  std::string data_kind;  // DATA: "ascii", "binary", "binary_compressed" or another (rejected later)
  int lines = 0;          // header lines read, the DATA line included

  long long count(std::size_t k) const { return counts.empty() ? 1 : counts[k]; }
  /// Bytes of one point record (fields packed in header order, SIZE × COUNT bytes each).
  long long point_step() const;
  /// Numbers on one ascii body line (sum of COUNT).
  long long values_per_point() const;
};

/// Reads and checks a PCD header up to its DATA line. `getline(line)` yields the next line
/// without its '\n' (false at the end of the file); afterwards the source is at the body.
/// Throws IOError "path: ..." when the header is malformed, inconsistent or missing.
PcdHeader read_pcd_header(const std::string& path, const std::function<bool(std::string&)>& getline);

/// Checks that `body` bytes after the header can hold the announced points: the exact size for
/// binary, a plausible size for ascii, and for binary_compressed the two sizes that open the
/// body, read through `read(dst, 8)` and returned in `compressed` (packed, unpacked bytes).
/// Fails for an unknown DATA kind.
void check_pcd_body_size(const std::string& path, const PcdHeader& h, long long body,
                         const std::function<bool(char*, std::size_t)>& read, std::uint32_t compressed[2]);

/// Fails at `line_no`: `tok` is not a number (with a hint for decimal commas).
[[noreturn]] void pcd_ascii_number_error(const std::string& path, long line_no, std::string_view tok);
/// Fails at `line_no`: the line holds `cols` numbers, not `values_per_point`.
[[noreturn]] void pcd_ascii_columns_error(const std::string& path, long line_no, long long cols, long long values_per_point);

/// Checks that an ascii body ends after its `points` points: every line `getline` still yields
/// (numbered on from `line_no`, the last line read) must be blank. A count in the header smaller
/// than the data (POINTS or WIDTH × HEIGHT not updated after an edit) would otherwise drop the
/// rest of the cloud silently, as PCL's reader does. Fails "path: line N: data beyond ...".
void check_pcd_ascii_tail(const std::string& path, long line_no, long long points,
                          const std::function<bool(std::string&)>& getline);

/// Parses one ascii body line strictly (PCL accepts non-numeric tokens and short lines silently):
/// calls on_value(token) for each number ("nan" allowed, as PCL writes it) and returns how many
/// there are; fails at `line_no` on a token that is not a number, or when a non-blank line does
/// not hold exactly `values_per_point` numbers. A blank line gives 0.
template <typename OnValue>
long long read_pcd_ascii_line(const std::string& path, long line_no, std::string_view line, long long values_per_point,
                              OnValue&& on_value) {
  long long cols = 0;
  for_each_token(line, [&](std::string_view tok) {
    double v = 0;
    if (!parse_double(tok, v)) pcd_ascii_number_error(path, line_no, tok);
    on_value(tok);
    ++cols;
  });
  if (cols != 0 && cols != values_per_point) pcd_ascii_columns_error(path, line_no, cols, values_per_point);
  return cols;
}

}  // namespace heatcvt::detail
