#pragma once
// Internal text helpers shared by the whole-file and the streaming readers (mesh_io, cloud_io,
// cloud_stream): whitespace, whole-token numbers and token splitting. Not installed.
#include <string_view>
#include <vector>

namespace heatcvt::detail {

/// The whitespace of the text formats: space, \t, \r, \n, \f, \v.
inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

/// Parses a whole token as a double ('+' prefix allowed); false if it is not exactly a number.
bool parse_double(std::string_view tok, double& out);
/// Parses a whole token as a signed integer ('+' prefix allowed); false if it is not exactly one.
bool parse_int(std::string_view tok, long long& out);
/// Splits a line into whitespace-separated tokens (reuses `tokens`).
void split(std::string_view line, std::vector<std::string_view>& tokens);

/// Calls f(token) for each whitespace-separated token of `line`, in order.
template <typename F>
void for_each_token(std::string_view line, F&& f) {
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i >= line.size()) break;
    std::size_t j = i;
    while (j < line.size() && !is_space(line[j])) ++j;
    f(line.substr(i, j - i));
    i = j;
  }
}

}  // namespace heatcvt::detail
