// Helpers for error messages shared by the readers and the tools.
#include "heatcvt/errors.h"

#include <cctype>

namespace heatcvt {

std::string quote_excerpt(std::string_view text, std::size_t max_chars) {
  std::string t(text.substr(0, max_chars));
  for (auto& c : t)
    if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
  return "'" + t + (text.size() > max_chars ? "...'" : "'");
}

std::string without_function_prefix(const std::string& message) {
  const std::size_t colon = message.find(": ");
  if (colon == std::string::npos || colon == 0) return message;
  // A function or class name: identifier characters only, with an '_' or an inner capital
  // ("cotan_laplacian", "HeatSolver", "HeatSolver::solve"); a file name has a '.' or a '/'.
  bool identifier = true, code_name = false;
  for (std::size_t i = 0; i < colon; ++i) {
    const unsigned char c = static_cast<unsigned char>(message[i]);
    if (c == '_' || (i > 0 && std::isupper(c))) code_name = true;
    if (!std::isalnum(c) && c != '_' && c != ':') identifier = false;
  }
  return identifier && code_name ? message.substr(colon + 2) : message;
}

}  // namespace heatcvt
