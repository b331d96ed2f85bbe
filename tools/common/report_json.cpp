#include "report_json.h"

#include <cstdio>
#include <ostream>

#include "cli_common.h"
#include "heatcvt/atomic_file.h"

namespace heatcvt::cli {

std::vector<CheckRecord> check_records(const ValidationReport& report) {
  std::vector<CheckRecord> out;
  for (const auto& c : report.checks) out.push_back({c.name, c.passed, c.ran, c.detail});
  return out;
}

bool all_passed(const std::vector<CheckRecord>& checks) {
  for (const auto& c : checks)
    if (!c.ran || !c.passed) return false;
  return true;
}

void print_checks(const std::vector<CheckRecord>& checks) {
  for (const auto& c : checks)
    std::printf("  %s %s: %s\n", !c.ran ? "SKIP" : (c.passed ? "PASS" : "FAIL"), c.name.c_str(), c.detail.c_str());
}

void print_stages(const std::vector<std::pair<std::string, double>>& stages) {
  std::printf("  stages:");
  for (const auto& [name, seconds] : stages) std::printf(" %s %.2f s;", name.c_str(), seconds);
  std::printf("\n");
}

Json report_head(const std::string& tool, const std::string& input, const std::vector<std::string>& outputs) {
  Json j;
  j["tool"] = tool;
  j["input"] = input;
  j["outputs"] = Json::array();
  for (const auto& o : outputs)
    if (!o.empty()) j["outputs"].push_back(o);
  return j;
}

int finish_report(Json& report, const std::vector<std::pair<std::string, double>>& stages,
                  const std::vector<CheckRecord>& checks) {
  Json st = Json::array();
  for (const auto& [name, seconds] : stages) st.push_back({{"name", name}, {"seconds", seconds}});
  Json ch = Json::array();
  for (const auto& c : checks) {
    Json r;
    r["name"] = c.name;
    r["passed"] = c.ran ? Json(c.passed) : Json(nullptr);
    r["detail"] = c.ran ? c.detail : "not run: " + c.detail;
    ch.push_back(std::move(r));
  }
  const int status = all_passed(checks) ? exit_ok : exit_checks_failed;
  report["stages"] = std::move(st);
  report["checks"] = std::move(ch);
  report["all_checks_passed"] = status == exit_ok;
  report["exit_status"] = status;
  return status;
}

void write_json(const std::string& path, const Json& report) {
  // Invalid UTF-8 in strings (e.g. a file name) is replaced instead of throwing.
  write_atomically(path, [&](std::ostream& os) {
    os << report.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
  });
}

}  // namespace heatcvt::cli
