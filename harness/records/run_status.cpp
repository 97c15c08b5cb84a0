#include "harness/records/run_status.hpp"

#include <array>
#include <ostream>
#include <utility>

namespace lexdyn::records {

namespace {

constexpr std::array<std::pair<RunStatus, const char*>, 12> kSpellings = {{
    {RunStatus::Completed, "completed"},
    {RunStatus::IntegratorFailure, "integrator_failure"},
    {RunStatus::ControllerFailure, "controller_failure"},
    {RunStatus::Diverged, "diverged"},
    {RunStatus::InternalError, "internal_error"},
    {RunStatus::Interrupted, "interrupted"},
    {RunStatus::InputError, "input_error"},
    {RunStatus::OutputError, "output_error"},
    {RunStatus::Timeout, "timeout"},
    {RunStatus::Crashed, "crashed"},
    {RunStatus::BadInput, "bad_input"},
    {RunStatus::NoSummary, "no_summary"},
}};

}  // namespace

const char* toString(RunStatus s) {
  for (const auto& [status, text] : kSpellings) {
    if (status == s) return text;
  }
  return "unknown";
}

std::optional<RunStatus> parseRunStatus(std::string_view text) {
  for (const auto& [status, spelling] : kSpellings) {
    if (text == spelling) return status;
  }
  return std::nullopt;
}

const std::vector<RunStatus>& allRunStatuses() {
  static const std::vector<RunStatus> all = [] {
    std::vector<RunStatus> v;
    for (const auto& kv : kSpellings) v.push_back(kv.first);
    return v;
  }();
  return all;
}

bool isRunsOwn(RunStatus s) {
  switch (s) {
    case RunStatus::Timeout:
    case RunStatus::Crashed:
    case RunStatus::BadInput:
    case RunStatus::NoSummary:
      return false;
    default:
      return true;
  }
}

const std::vector<RunStatus>& runsOwnStatuses() {
  static const std::vector<RunStatus> own = [] {
    std::vector<RunStatus> v;
    for (RunStatus s : allRunStatuses()) {
      if (isRunsOwn(s)) v.push_back(s);
    }
    return v;
  }();
  return own;
}

bool isRecordedBySweeps(RunStatus s) {
  switch (s) {
    case RunStatus::Interrupted:
    case RunStatus::OutputError:
    case RunStatus::NoSummary:
      return false;
    default:
      return true;
  }
}

std::ostream& operator<<(std::ostream& os, RunStatus s) { return os << toString(s); }

std::string spellings(const std::vector<RunStatus>& statuses) {
  std::string out;
  for (RunStatus s : statuses) out += (out.empty() ? "" : " | ") + std::string(toString(s));
  return out;
}

}  // namespace lexdyn::records
