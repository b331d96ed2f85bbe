#pragma once
// A tiny ordered JSON object writer for the tools' --report files (no dependency needed).
#include <string>
#include <utility>
#include <vector>

namespace heatcvt::cli {

/// Ordered JSON object. Values are stored pre-serialised; nested objects via add_object.
class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, long value);
  JsonObject& add(const std::string& key, int value) { return add(key, static_cast<long>(value)); }
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  JsonObject& add(const std::string& key, const std::vector<double>& values);
  JsonObject& add_object(const std::string& key, const JsonObject& object);
  JsonObject& add_array(const std::string& key, const std::vector<JsonObject>& objects);
  std::string str(int indent = 0) const;

 private:
  std::vector<std::pair<std::string, std::string>> entries_;
};

/// Writes the object to `path` atomically (temporary file + rename).
void write_json(const std::string& path, const JsonObject& object);

}  // namespace heatcvt::cli
