// Line rules of text point clouds (xyz_lines.h).
#include "xyz_lines.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "heatcvt/errors.h"
#include "text_tokens.h"

namespace heatcvt::detail {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw IOError(path + ": " + problem); }

bool is_separator(char c) { return c == ',' || c == ';'; }

// A column name of a header line: a letter or '_' first, then letters, digits, '_' or '.'.
bool is_name(std::string_view tok) {
  if (tok.empty() || !(std::isalpha(static_cast<unsigned char>(tok[0])) || tok[0] == '_')) return false;
  for (char c : tok)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.')) return false;
  return true;
}

// Calls f(field) for each field of `line`: white-space tokens, or, where the line holds a comma or
// semicolon, the trimmed text between separators (an empty field is passed as empty).
template <typename F>
void for_each_field(std::string_view line, F&& f) {
  bool csv = false;
  for (char c : line) csv = csv || is_separator(c);
  if (!csv) {
    for_each_token(line, f);
    return;
  }
  std::size_t start = 0;
  while (true) {
    std::size_t end = start;
    while (end < line.size() && !is_separator(line[end])) ++end;
    std::string_view field = line.substr(start, end - start);
    while (!field.empty() && is_space(field.front())) field.remove_prefix(1);
    while (!field.empty() && is_space(field.back())) field.remove_suffix(1);
    // A trailing separator ("1,2,3,") ends the line without an empty last field.
    if (!(end >= line.size() && field.empty() && start > 0)) f(field);
    if (end >= line.size()) break;
    start = end + 1;
  }
}

}  // namespace

XyzLineKind read_xyz_line(std::string_view line, bool first, const std::string& path, long line_no, double vals[6],
                          int& cols) {
  const std::size_t hash = line.find('#'), slashes = line.find("//");
  line = line.substr(0, std::min(hash, slashes));
  cols = 0;
  int fields = 0;
  bool only_names = true;       // every field that is not a number is a column name
  std::string_view other;       // the first field that is not a number
  bool have_other = false;
  for_each_field(line, [&](std::string_view field) {
    ++fields;
    double v = 0;
    if (parse_double(field, v)) {
      if (cols < 6) vals[cols] = v;
      ++cols;
      return;
    }
    if (!have_other) other = field, have_other = true;
    only_names = only_names && is_name(field);
  });
  if (fields == 0) return XyzLineKind::blank;
  if (have_other) {
    if (first && cols == 0 && only_names) return XyzLineKind::header;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    if (other.empty()) fail(path, where + "empty field between two separators");
    if (other.find_first_of(" \t") != std::string_view::npos)
      fail(path, where + "a field holds more than one number " + quote_excerpt(other));
    fail(path, where + "malformed number " + quote_excerpt(other));
  }
  if (first && cols == 1 && vals[0] >= 0 && vals[0] == std::floor(vals[0])) return XyzLineKind::count;
  return XyzLineKind::values;
}

}  // namespace heatcvt::detail
