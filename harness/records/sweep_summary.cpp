#include "harness/records/sweep_summary.hpp"

#include "harness/records/json_numbers.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace lexdyn::records {

using nlohmann::json;

json finiteOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double numberOrNaN(const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

std::string jsonSyntaxProblem(const std::string& text, std::size_t byte, const std::string& message) {
  const std::size_t at = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  // The literal being read: the letters (and a sign) around the offset.
  std::size_t from = at;
  while (from > line_start && (std::isalpha(static_cast<unsigned char>(text[from - 1])) || text[from - 1] == '-')) --from;
  std::size_t to = from;
  while (to < text.size() && (std::isalpha(static_cast<unsigned char>(text[to])) || text[to] == '-')) ++to;
  const std::string literal = text.substr(from, to - from);
  if (literal == "NaN" || literal == "Infinity" || literal == "-Infinity" || literal == "nan" || literal == "-nan" || literal == "inf" ||
      literal == "-inf") {
    // The key: the last quoted string followed by ':' before the literal.
    std::string key;
    const std::size_t colon = text.rfind(':', from);
    if (colon != std::string::npos) {
      const std::size_t close = text.rfind('"', colon);
      const std::size_t open = close == std::string::npos || close == 0 ? std::string::npos : text.rfind('"', close - 1);
      if (open != std::string::npos) key = text.substr(open + 1, close - open - 1);
    }
    return "line " + std::to_string(line) + ": " + (key.empty() ? "" : key + ": ") + "expected a finite number or null, found " + literal;
  }
  // nlohmann's message without its own position ("[json.exception.parse_error.101] parse error at
  // line 1, column 10: syntax error ...": the part after the position).
  std::string what = message;
  const size_t column = what.find("column ");
  const size_t colon = column == std::string::npos ? std::string::npos : what.find(": ", column);
  if (colon != std::string::npos) what = what.substr(colon + 2);
  return "line " + std::to_string(line) + ", column " + std::to_string(at - line_start + 1) + ": not JSON (" + what + ")";
}

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
