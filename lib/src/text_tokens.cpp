// Text helpers of the readers (text_tokens.h).
#include "text_tokens.h"

#include <charconv>

namespace heatcvt::detail {

namespace {
// std::from_chars over the whole token after an optional '+' (from_chars rejects a '+').
template <typename T>
bool parse_whole(std::string_view tok, T& out) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return res.ec == std::errc() && res.ptr == tok.data() + tok.size();
}
}  // namespace

bool parse_double(std::string_view tok, double& out) { return parse_whole(tok, out); }

bool parse_int(std::string_view tok, long long& out) { return parse_whole(tok, out); }

void split(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  for_each_token(line, [&](std::string_view tok) { tokens.push_back(tok); });
}

}  // namespace heatcvt::detail
