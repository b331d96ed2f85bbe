// Line rules of text point clouds (xyz_lines.h).
#include "xyz_lines.h"

#include <algorithm>
#include <cmath>

#include "heatcvt/errors.h"
#include "text_tokens.h"

namespace heatcvt::detail {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

// The separator of a line: ';' where it holds one (a decimal-comma export: "1,5;2,5;3,5"), else ','
// where it holds one, else none (white space).
char separator_of(std::string_view line) {
  if (line.find(';') != std::string_view::npos) return ';';
  if (line.find(',') != std::string_view::npos) return ',';
  return 0;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Calls f(field) for each field of `line`: white-space tokens, or the trimmed text between two
// separators (an empty field is passed as empty; one trailing separator ends the line).
template <typename F>
void for_each_field(std::string_view line, F&& f) {
  const char sep = separator_of(line);
  if (sep == 0) {
    for_each_token(line, f);
    return;
  }
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(line.find(sep, start), line.size());
    const std::string_view field = trimmed(line.substr(start, end - start));
    if (!(end >= line.size() && field.empty() && start > 0)) f(field);
    if (end >= line.size()) break;
    start = end + 1;
  }
}

}  // namespace

XyzLineKind read_xyz_line(std::string_view line, bool first, const std::string& path, long line_no, double vals[6],
                          int& cols) {
  if (first && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // a UTF-8 byte-order mark
  line = line.substr(0, std::min(line.find('#'), line.find("//")));
  cols = 0;
  int fields = 0;
  std::string_view other;  // the first field that is not a number
  bool have_other = false;
  for_each_field(line, [&](std::string_view field) {
    ++fields;
    double v = 0;
    if (parse_double(field, v)) {
      if (cols < 6) vals[cols] = v;
      ++cols;
    } else if (!have_other) {
      other = field;
      have_other = true;
    }
  });
  if (fields == 0) return XyzLineKind::blank;
  if (have_other) {
    // Column names ("x y z", "X coord;Y coord;Z coord", "x (m), y (m), z (m)"): no number at all.
    if (first && cols == 0) return XyzLineKind::header;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    if (other.empty()) fail(path, where + "empty field between two separators");
    double v = 0;
    bool numbers = true;  // a field of several numbers: a decimal comma between white-space columns
    for_each_token(other, [&](std::string_view tok) { numbers = numbers && parse_double(tok, v); });
    if (numbers && other.find_first_of(" \t") != std::string_view::npos)
      fail(path, where + "a field holds more than one number " + quote_excerpt(other));
    fail(path, where + "malformed number " + quote_excerpt(other));
  }
  if (first && cols == 1 && vals[0] >= 0 && vals[0] == std::floor(vals[0])) return XyzLineKind::count;
  return XyzLineKind::values;
}

}  // namespace heatcvt::detail
