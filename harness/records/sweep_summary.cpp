#include "harness/records/sweep_summary.hpp"

#include "harness/records/json_numbers.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace lexdyn::records {

using nlohmann::json;

double SweepComparisonSummary::diffQuantile(double q) const {
  if (diffs.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = static_cast<size_t>(std::ceil(q * static_cast<double>(diffs.size())));
  return diffs[std::min(diffs.size() - 1, k == 0 ? 0 : k - 1)];
}

namespace {

json overridesJson(const std::vector<std::pair<std::string, std::string>>& overrides) {
  json out = json::array();
  for (const auto& [path, value] : overrides) out.push_back({{"path", path}, {"value", value}});
  return out;
}

json toJson(const SweepParameterRecord& p) {
  json j = {{"name", p.name}, {"paths", p.paths}, {"simplest", p.simplest}};
  switch (p.kind) {
    case SweepParameterRecord::Kind::Range:
      j["range"] = {p.lo, p.hi};
      break;
    case SweepParameterRecord::Kind::LogRange:
      j["range"] = {p.lo, p.hi};
      j["scale"] = "log";
      break;
    case SweepParameterRecord::Kind::Integers:
      j["integers"] = {static_cast<long>(p.lo), static_cast<long>(p.hi)};
      break;
    case SweepParameterRecord::Kind::Values:
      j["values"] = p.values;
      break;
    case SweepParameterRecord::Kind::Choices:
      j["choices"] = p.values;
      break;
  }
  return j;
}

json toJson(const SweepCheckSummary& c) {
  return {{"check", c.check},
          {"method", c.method},
          {"runs", c.runs},
          {"passed", c.passed},
          {"pass_rate", c.passRate()},
          {"worst_margin", finiteOrNull(c.worst_margin)},
          {"worst_point", c.worst_point},
          {"unit", c.unit}};
}

json toJson(const SweepWinCount& w) { return {{"points", w.points}, {"wins", w.wins}, {"win_rate", w.winRate()}}; }

json toJson(const SweepComparisonSummary& c) {
  json by = json::object();
  for (const auto& [pn, cells] : c.by_parameter) {
    for (const auto& [v, w] : cells) by[pn][v] = toJson(w);
  }
  return {{"name", c.name},
          {"better", c.better},
          {"worse", c.worse},
          {"statistic", c.statistic},
          {"tasks", c.tasks},
          {"from_s", c.from_s},
          {"to_s", finiteOrNull(c.to_s)},
          {"margin", c.margin},
          {"points", c.overall.points},
          {"better_stopped_early", c.better_stopped_early},
          {"worse_stopped_early", c.worse_stopped_early},
          {"wins", c.overall.wins},
          {"win_rate", c.overall.winRate()},
          {"diff",
           {{"min", finiteOrNull(c.diffQuantile(0.0))},
            {"p10", finiteOrNull(c.diffQuantile(0.1))},
            {"median", finiteOrNull(c.diffQuantile(0.5))},
            {"p90", finiteOrNull(c.diffQuantile(0.9))},
            {"max", finiteOrNull(c.diffs.empty() ? std::numeric_limits<double>::quiet_NaN() : c.diffs.back())}}},
          {"by_parameter", by}};
}

json toJson(const SweepMapRecord::Axis& a) { return {{"name", a.name}, {"path", a.path}, {"values", a.values}}; }

json toJson(const SweepMapRecord& m) {
  json j = {{"x", toJson(m.x)}, {"y", toJson(m.y)}, {"property", m.property}, {"method", m.method}, {"csv", m.csv}};
  if (!m.png.empty()) j["png"] = m.png;
  return j;
}

}  // namespace

json toJson(const SweepFailureRecord& f) {
  json j = {{"check", f.check},
            {"method", f.method},
            {"point", f.point},
            {"points_failing", f.points_failing},
            {"values", f.values},
            {"overrides", overridesJson(f.overrides)},
            {"duration_s", f.duration_s},
            {"command", f.command},
            {"status", toString(f.status)},
            {"shrunk", f.shrunk}};
  if (f.outcome) {
    j["value"] = finiteOrNull(f.outcome->value);
    j["limit"] = finiteOrNull(f.outcome->limit);
    j["margin"] = finiteOrNull(f.outcome->margin);
    j["unit"] = f.outcome->unit;
  }
  if (f.shrunk) {
    j["case_file"] = f.case_file;
    j["runs"] = f.runs;
    j["budget_exhausted"] = f.budget_exhausted;
  }
  return j;
}

json toJson(const SweepSummary& s) {
  json params = json::array(), checks = json::array(), comps = json::array(), maps = json::array(), failures = json::array();
  for (const auto& p : s.parameters) params.push_back(toJson(p));
  for (const auto& c : s.checks) checks.push_back(toJson(c));
  for (const auto& c : s.comparisons) comps.push_back(toJson(c));
  for (const auto& m : s.maps) maps.push_back(toJson(m));
  for (const auto& f : s.failures) failures.push_back(toJson(f));
  return {{"format", kSweepSummaryFormat},
          {"name", s.name},
          {"description", s.description},
          {"sweep_file", s.sweep_file},
          {"base_case", s.base_case},
          {"methods", s.methods},
          {"seed", s.seed},
          {"sampling", s.grid ? "grid" : "random"},
          {"duration_s", s.duration_s ? json(*s.duration_s) : json(nullptr)},
          {"parameters", params},
          {"points", s.points},
          {"completed", s.completed},
          {"failed_points", s.failed_points},
          {"checks", checks},
          {"comparisons", comps},
          {"maps", maps},
          {"failures", failures}};
}

}  // namespace lexdyn::records
