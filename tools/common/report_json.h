#pragma once
// The JSON --report of every tool, one schema (nlohmann-json, insertion-ordered keys):
//   "tool", "input", "outputs": [paths], tool-specific figures (angles as "phi_min_deg",
//   "phi_mean_deg"; times in seconds with the suffix "_s"), "stages": [{"name", "seconds"}],
//   "checks": [{"name", "passed", "detail"}] ("passed": null for a check that could not run),
//   "all_checks_passed", "exit_status" (see cli_common.h).
#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

#include "heatcvt/validate.h"

namespace heatcvt::cli {

using Json = nlohmann::ordered_json;

/// One entry of the "checks" list.
struct CheckRecord {
  std::string name;
  bool passed = false;
  bool ran = true;
  std::string detail;
};

/// The checks of a ValidationReport as records.
std::vector<CheckRecord> check_records(const ValidationReport& report);

/// True when every record ran and passed.
bool all_passed(const std::vector<CheckRecord>& checks);

/// Prints the checks on stdout, one "  PASS|FAIL|SKIP name: detail" line each.
void print_checks(const std::vector<CheckRecord>& checks);

/// Prints the stage times on stdout as one line "  stages: <name> <seconds> s; ...".
void print_stages(const std::vector<std::pair<std::string, double>>& stages);

/// A report with the common head: "tool", "input", "outputs" (non-empty paths only).
Json report_head(const std::string& tool, const std::string& input, const std::vector<std::string>& outputs);

/// Adds the common tail: "stages", "checks", "all_checks_passed", "exit_status"; returns the status.
int finish_report(Json& report, const std::vector<std::pair<std::string, double>>& stages,
                  const std::vector<CheckRecord>& checks);

/// Writes the report to `path` (with the run's other outputs, see atomic_file.h).
void write_json(const std::string& path, const Json& report);

}  // namespace heatcvt::cli
