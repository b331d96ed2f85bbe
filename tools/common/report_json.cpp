#include "report_json.h"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "heatcvt/atomic_file.h"

namespace heatcvt::cli {

namespace {
std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}
std::string number(double v) { return std::isfinite(v) ? format_double(v) : "null"; }
}  // namespace

JsonObject& JsonObject::add(const std::string& key, double value) {
  entries_.emplace_back(key, number(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, long value) {
  entries_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, bool value) {
  entries_.emplace_back(key, value ? "true" : "false");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  entries_.emplace_back(key, quote(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::vector<double>& values) {
  std::string s = "[";
  for (size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + number(values[i]);
  entries_.emplace_back(key, s + "]");
  return *this;
}
JsonObject& JsonObject::add_object(const std::string& key, const JsonObject& object) {
  entries_.emplace_back(key, "\x01" + object.str());  // marker: nested, re-indented in str()
  return *this;
}
JsonObject& JsonObject::add_array(const std::string& key, const std::vector<JsonObject>& objects) {
  std::string s = "[";
  for (size_t i = 0; i < objects.size(); ++i) s += (i ? ", " : "") + objects[i].str();
  entries_.emplace_back(key, s + "]");
  return *this;
}

std::string JsonObject::str(int indent) const {
  const std::string pad(indent + 2, ' '), end_pad(indent, ' ');
  std::string out = "{\n";
  for (size_t i = 0; i < entries_.size(); ++i) {
    const auto& [k, v] = entries_[i];
    std::string value = v;
    if (!value.empty() && value[0] == '\x01') {
      // nested object: indent its lines
      value = value.substr(1);
      std::string shifted;
      for (char c : value) {
        shifted += c;
        if (c == '\n') shifted += pad;
      }
      value = shifted;
    }
    out += pad + quote(k) + ": " + value + (i + 1 < entries_.size() ? ",\n" : "\n");
  }
  return out + end_pad + "}";
}

void write_json(const std::string& path, const JsonObject& object) {
  write_atomically(path, [&](std::ostream& os) { os << object.str() << "\n"; });
}

}  // namespace heatcvt::cli
