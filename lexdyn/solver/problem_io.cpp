#include "lexdyn/solver/problem_io.hpp"

#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_set>

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_text.hpp"

namespace lexdyn::solver {

using nlohmann::json;

namespace {

std::string typeName(const json& j) { return j.type_name(); }

// Builds the DOM like json::parse, but keeps the path of the value being parsed so that a
// number overflow (e.g. 1e999) or a syntax error is reported with its location.
class PathTrackingSax {
 public:
  explicit PathTrackingSax(json& root) : dom_(root, true) {}

  bool null() { return value() && dom_.null(); }
  bool boolean(bool b) { return value() && dom_.boolean(b); }
  bool number_integer(json::number_integer_t v) { return value() && dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value() && dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const std::string& s) { return value() && dom_.number_float(v, s); }
  bool string(std::string& v) { return value() && dom_.string(v); }
  bool binary(json::binary_t& v) { return value() && dom_.binary(v); }
  bool start_object(std::size_t n) {
    value();
    stack_.push_back({false, -1, {}, {}});
    return dom_.start_object(n);
  }
  bool key(std::string& k) {
    stack_.back().key = k;
    // JSON leaves duplicate keys undefined and the DOM would keep the last one silently.
    if (!stack_.back().keys.insert(k).second) {
      errorPath_ = path();
      errorMessage_ = "duplicate key \"" + k + "\"";
      return false;
    }
    return dom_.key(k);
  }
  bool end_object() {
    stack_.pop_back();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    value();
    stack_.push_back({true, -1, {}, {}});
    return dom_.start_array(n);
  }
  bool end_array() {
    stack_.pop_back();
    return dom_.end_array();
  }
  bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception& ex) {
    std::string msg = ex.what();
    const auto p = msg.find("] ");
    if (p != std::string::npos) msg = msg.substr(p + 2);
    // The failing value has not been reported: it is the next element of the innermost array.
    if (!stack_.empty() && stack_.back().array) ++stack_.back().index;
    errorPath_ = path();
    errorMessage_ = msg + " (byte " + std::to_string(position) + ", near '" + token + "')";
    return false;
  }

  const std::string& errorPath() const { return errorPath_; }
  const std::string& errorMessage() const { return errorMessage_; }

 private:
  struct Frame {
    bool array;
    int index;
    std::string key;
    std::unordered_set<std::string> keys;  ///< objects: the keys seen so far
  };
  bool value() {
    if (!stack_.empty() && stack_.back().array) ++stack_.back().index;
    return true;
  }
  std::string path() const {
    std::string s;
    for (const Frame& f : stack_) {
      if (f.array) {
        s += "[" + std::to_string(std::max(f.index, 0)) + "]";
      } else if (!f.key.empty()) {
        s += (s.empty() ? "" : ".") + f.key;
      }
    }
    return s;
  }
  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::vector<Frame> stack_;
  std::string errorPath_, errorMessage_;
};

std::string fmt(double v) { return formatNumber(v); }

// A number (null: nullValue, when allowed) of magnitude at most kMaxProblemMagnitude.
double readNumber(const json& j, const std::string& where, bool allowNull, double nullValue) {
  if (j.is_null()) {
    if (allowNull) return nullValue;
    throw InputError(where, "expected a number, found null");
  }
  if (!j.is_number()) throw InputError(where, std::string("expected a number, found ") + typeName(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw InputError(where, "expected a finite number, found " + fmt(v));
  if (std::abs(v) > kMaxProblemMagnitude) {
    throw InputError(where, "expected a magnitude of at most " + fmt(kMaxProblemMagnitude) +
                                " (beyond, the solver's arithmetic "
                                "overflows), found " +
                                fmt(v));
  }
  return v;
}

}  // namespace

namespace {

// Options as the file writes them: every field but `trace` (a debugging switch).
json optionsValue(const Options& o) {
  json j;
  j["rank_tolerance"] = o.rank_tolerance;
  j["feasibility_tolerance"] = o.feasibility_tolerance;
  j["zero_tolerance"] = o.zero_tolerance;
  j["dual_tolerance"] = o.dual_tolerance;
  j["eliminate_first_level"] = o.eliminate_first_level;
  j["elimination_tolerance"] = o.elimination_tolerance;
  j["split_from_variable"] = o.split_from_variable;
  j["last_level_projection"] = o.last_level_projection == Options::LastLevel::Auto
                                   ? "auto"
                                   : (o.last_level_projection == Options::LastLevel::Never ? "never" : "always");
  j["spanning_stages"] = o.spanning_stages;
  j["spanning_any_rows"] = o.spanning_any_rows;
  j["spanning_structured"] = o.spanning_structured;
  j["lazy_snapshots"] = o.lazy_snapshots;
  j["project_unit_suffix"] = o.project_unit_suffix;
  j["restart_after_bound_change"] = o.restart_after_bound_change;
  j["swap_reflectors"] = o.swap_reflectors;
  j["max_iterations"] = o.max_iterations;
  j["bland_after_degenerate_steps"] = o.bland_after_degenerate_steps;
  j["cycle_tolerance_factor"] = o.cycle_tolerance_factor;
  j["stop_slack_norm"] = o.stop_slack_norm;
  j["stop_optimality_iterations"] = o.stop_optimality_iterations;
  j["stop_total_iterations"] = o.stop_total_iterations;
  j["stop_after_level"] = o.stop_after_level;
  j["compute_multipliers"] = o.compute_multipliers;
  return j;
}

// The file's solver_options: every key optional (the solver's default), none unknown, each of
// its type, then Options::validate's ranges; errors name the file and the key.
Options readOptions(const json& j, const std::string& where) {
  if (!j.is_object()) throw InputError(where, "expected an object, found " + typeName(j));
  Options o;
  const json known = optionsValue(o);
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!known.contains(it.key())) {
      std::string names;
      for (auto k = known.begin(); k != known.end(); ++k) names += (names.empty() ? "" : ", ") + k.key();
      throw InputError(where + "." + it.key(), "unknown key (expected " + names + ")");
    }
  }
  auto number = [&](const char* key, double& v) {
    if (j.contains(key)) v = readNumber(j[key], where + "." + key, false, 0.0);
  };
  auto integer = [&](const char* key, int& v) {
    if (!j.contains(key)) return;
    const json& x = j[key];
    if (!x.is_number_integer() || x.get<long long>() < -1000000000LL || x.get<long long>() > 1000000000LL)
      throw InputError(where + "." + key, "expected an integer, found " + x.dump());
    v = static_cast<int>(x.get<long long>());
  };
  auto boolean = [&](const char* key, bool& v) {
    if (!j.contains(key)) return;
    if (!j[key].is_boolean()) throw InputError(where + "." + key, "expected true or false, found " + j[key].dump());
    v = j[key].get<bool>();
  };
  number("rank_tolerance", o.rank_tolerance);
  number("feasibility_tolerance", o.feasibility_tolerance);
  number("zero_tolerance", o.zero_tolerance);
  number("dual_tolerance", o.dual_tolerance);
  boolean("eliminate_first_level", o.eliminate_first_level);
  number("elimination_tolerance", o.elimination_tolerance);
  integer("split_from_variable", o.split_from_variable);
  if (j.contains("last_level_projection")) {
    const json& x = j["last_level_projection"];
    const std::string v = x.is_string() ? x.get<std::string>() : "";
    if (v == "auto")
      o.last_level_projection = Options::LastLevel::Auto;
    else if (v == "never")
      o.last_level_projection = Options::LastLevel::Never;
    else if (v == "always")
      o.last_level_projection = Options::LastLevel::Always;
    else
      throw InputError(where + ".last_level_projection", "expected \"auto\", \"never\" or \"always\", found " + x.dump());
  }
  boolean("spanning_stages", o.spanning_stages);
  boolean("spanning_any_rows", o.spanning_any_rows);
  boolean("spanning_structured", o.spanning_structured);
  boolean("lazy_snapshots", o.lazy_snapshots);
  boolean("project_unit_suffix", o.project_unit_suffix);
  boolean("restart_after_bound_change", o.restart_after_bound_change);
  boolean("swap_reflectors", o.swap_reflectors);
  integer("max_iterations", o.max_iterations);
  integer("bland_after_degenerate_steps", o.bland_after_degenerate_steps);
  number("cycle_tolerance_factor", o.cycle_tolerance_factor);
  number("stop_slack_norm", o.stop_slack_norm);
  integer("stop_optimality_iterations", o.stop_optimality_iterations);
  integer("stop_total_iterations", o.stop_total_iterations);
  integer("stop_after_level", o.stop_after_level);
  boolean("compute_multipliers", o.compute_multipliers);
  try {
    o.validate();
  } catch (const InputError& e) {
    // "FIELD: what" names the key as a type error does: WHERE.FIELD: what.
    const std::string& d = e.detail();
    const size_t colon = d.find(": ");
    if (colon == std::string::npos) throw InputError(where, d);
    throw InputError(where + "." + d.substr(0, colon), d.substr(colon + 2));
  }
  return o;
}

}  // namespace

std::string solverOptionsToJson(const Options& options) { return optionsValue(options).dump(); }

Problem parseProblemJson(const std::string& text, const std::string& source) { return parseProblemFile(text, source).problem; }

ProblemFile parseProblemFile(const std::string& text, const std::string& source) {
  json doc;
  PathTrackingSax sax(doc);
  if (!json::sax_parse(text, &sax)) {
    const std::string where = sax.errorPath().empty() ? source : source + ": " + sax.errorPath();
    throw InputError(where, (sax.errorMessage().rfind("duplicate key", 0) == 0 ? "" : "malformed JSON: ") + sax.errorMessage());
  }
  if (!doc.is_object()) throw InputError(source, "expected a JSON object at the top level, found " + typeName(doc));
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    if (it.key() != "variables" && it.key() != "levels" && it.key() != "solver_options") {
      throw InputError(source + ": " + it.key(), "unknown key (expected \"variables\", \"levels\" and optionally \"solver_options\")");
    }
  }
  if (!doc.contains("variables")) throw InputError(source, "missing key \"variables\"");
  if (!doc.contains("levels")) throw InputError(source, "missing key \"levels\"");
  const json& jn = doc["variables"];
  if (!jn.is_number_integer() || (jn.is_number_unsigned() ? jn.get<unsigned long long>() == 0 : jn.get<long long>() <= 0)) {
    throw InputError(source + ": variables", "expected a positive integer, found " + jn.dump());
  }
  if (jn.is_number_unsigned() ? jn.get<unsigned long long>() > static_cast<unsigned long long>(kMaxProblemVariables)
                              : jn.get<long long>() > kMaxProblemVariables) {
    throw InputError(source + ": variables",
                     "expected at most " + std::to_string(kMaxProblemVariables) + " variables (size guard), found " + jn.dump());
  }
  const int n = static_cast<int>(jn.get<long long>());
  const json& jl = doc["levels"];
  if (!jl.is_array()) throw InputError(source + ": levels", "expected an array, found " + typeName(jl));
  if (jl.size() > static_cast<size_t>(kMaxProblemLevels)) {
    throw InputError(source + ": levels", "expected at most " + std::to_string(kMaxProblemLevels) +
                                              " levels (size guard: the solver's work grows with the cube of the level count), found " +
                                              std::to_string(jl.size()));
  }
  long total_rows = 0;

  Problem problem(n);
  for (size_t l = 0; l < jl.size(); ++l) {
    const std::string lw = source + ": levels[" + std::to_string(l) + "]";
    const json& lv = jl[l];
    if (!lv.is_object()) throw InputError(lw, "expected an object, found " + typeName(lv));
    for (auto it = lv.begin(); it != lv.end(); ++it) {
      const std::string& k = it.key();
      if (k != "name" && k != "A" && k != "lower" && k != "upper" && k != "columns") {
        throw InputError(lw + "." + k, "unknown key (expected name, A, lower, upper, columns)");
      }
    }
    std::string name;
    if (lv.contains("name")) {
      if (!lv["name"].is_string()) throw InputError(lw + ".name", "expected a string");
      name = lv["name"].get<std::string>();
    }
    for (const char* key : {"A", "lower", "upper"}) {
      if (!lv.contains(key)) throw InputError(lw, std::string("missing key \"") + key + "\"");
      if (!lv[key].is_array()) throw InputError(lw + "." + key, "expected an array, found " + typeName(lv[key]));
    }
    const json& jA = lv["A"];
    const json& jlo = lv["lower"];
    const json& jup = lv["upper"];
    total_rows += static_cast<long>(jA.size());
    if (total_rows > kMaxProblemRows || total_rows * n > kMaxProblemEntries) {
      throw InputError(lw + ".A",
                       "the problem has more than " +
                           (total_rows > kMaxProblemRows ? std::to_string(kMaxProblemRows) + " rows"
                                                         : std::to_string(kMaxProblemEntries) + " matrix entries (rows x variables)") +
                           " up to this level (size guard)");
    }
    const int m = static_cast<int>(jA.size());
    if (static_cast<int>(jlo.size()) != m) {
      throw InputError(lw + ".lower", "has " + std::to_string(jlo.size()) + " entries but A has " + std::to_string(m) + " rows");
    }
    if (static_cast<int>(jup.size()) != m) {
      throw InputError(lw + ".upper", "has " + std::to_string(jup.size()) + " entries but A has " + std::to_string(m) + " rows");
    }
    Eigen::MatrixXd A(m, n);
    Eigen::VectorXd lo(m), up(m);
    for (int r = 0; r < m; ++r) {
      const std::string rw = lw + ".A[" + std::to_string(r) + "]";
      const json& row = jA[static_cast<size_t>(r)];
      if (!row.is_array()) throw InputError(rw, "expected an array of " + std::to_string(n) + " numbers, found " + typeName(row));
      if (static_cast<int>(row.size()) != n) {
        throw InputError(rw, "expected " + std::to_string(n) + " numbers (the number of variables), found " + std::to_string(row.size()));
      }
      for (int c = 0; c < n; ++c) {
        const std::string cw = rw + "[" + std::to_string(c) + "]";
        A(r, c) = readNumber(row[static_cast<size_t>(c)], cw, false, 0.0);
      }
      lo(r) = readNumber(jlo[static_cast<size_t>(r)], lw + ".lower[" + std::to_string(r) + "]", true, -kInf);
      up(r) = readNumber(jup[static_cast<size_t>(r)], lw + ".upper[" + std::to_string(r) + "]", true, kInf);
      if (std::isnan(lo(r)) || std::isnan(up(r))) throw InputError(lw + ".row[" + std::to_string(r) + "]", "bound is NaN");
      if (lo(r) > up(r)) {
        std::ostringstream os;
        os << "lower bound " << lo(r) << " is greater than upper bound " << up(r);
        throw InputError(lw + ".row[" + std::to_string(r) + "]", os.str());
      }
    }
    problem.addLevel(name, std::move(A), std::move(lo), std::move(up));
    if (lv.contains("columns")) {
      // The declaration of the level's nonzero columns (Problem::setLevelColumns), checked against
      // A by validate() below.
      const json& jc = lv["columns"];
      if (!jc.is_number_integer() || jc.get<long long>() < 0 || jc.get<long long>() > n)
        throw InputError(lw + ".columns",
                         "expected an integer in 0 .. " + std::to_string(n) + " (the number of variables), found " + jc.dump());
      problem.setLevelColumns(static_cast<int>(l), static_cast<int>(jc.get<long long>()));
    }
  }
  problem.validate(source);
  ProblemFile file{std::move(problem), std::nullopt};
  if (doc.contains("solver_options")) file.options = readOptions(doc["solver_options"], source + ": solver_options");
  return file;
}

Problem readProblemJson(const std::string& path) { return readProblemFile(path).problem; }

ProblemFile readProblemFile(const std::string& path) { return parseProblemFile(readTextFile(path, "problem"), path); }

namespace {

json boundValue(double v) {
  if (std::isinf(v)) return nullptr;
  return v;
}

}  // namespace

std::string problemToJson(const Problem& problem, const Options* options) {
  json doc;
  if (options) doc["solver_options"] = optionsValue(*options);
  doc["variables"] = problem.variables();
  json levels = json::array();
  const int n = problem.variables();
  for (int l = 0; l < problem.levelCount(); ++l) {
    const Level& lv = problem.level(l);
    json jl;
    jl["name"] = lv.name;
    json A = json::array(), lo = json::array(), up = json::array();
    for (int r = 0; r < lv.rows(); ++r) {
      json row = json::array();
      for (int c = 0; c < n; ++c) {
        double a = 0.0;
        if (lv.kind == LevelKind::General) {
          a = lv.A(r, c);
        } else if (lv.variable[static_cast<size_t>(r)] == c) {
          a = lv.coefficient(r);
        }
        row.push_back(a);
      }
      A.push_back(std::move(row));
      lo.push_back(boundValue(lv.lower(r)));
      up.push_back(boundValue(lv.upper(r)));
    }
    jl["A"] = std::move(A);
    jl["lower"] = std::move(lo);
    jl["upper"] = std::move(up);
    if (lv.kind == LevelKind::General && lv.columns >= 0) jl["columns"] = lv.columns;
    levels.push_back(std::move(jl));
  }
  doc["levels"] = std::move(levels);
  return doc.dump();
}

void writeFileAtomic(const std::string& path, const std::string& text) {
  // An output that cannot be written is a run failure with the system's reason, not bad input.
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw OutputError(tmp, std::string("cannot open for writing: ") + std::strerror(errno));
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    std::remove(tmp.c_str());
    throw OutputError(tmp, std::string("cannot write: ") + std::strerror(written ? errno : err));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    throw OutputError(path, std::string("cannot rename into place: ") + std::strerror(e));
  }
}

void writeProblemJson(const Problem& problem, const std::string& path, const Options* options) {
  writeFileAtomic(path, problemToJson(problem, options));
}

std::string resultToJson(const Problem& problem, const Result& result, bool withDetails, const Options* options,
                         const std::string& options_from) {
  json doc;
  doc["status"] = toString(result.status);
  doc["reason"] = toString(result.reason);
  json x = json::array();
  for (int i = 0; i < result.x.size(); ++i) x.push_back(result.x(i));
  doc["x"] = std::move(x);
  json lv = json::array();
  for (int l = 0; l < result.violation_norm.size(); ++l) lv.push_back(result.violation_norm(l));
  doc["level_violation"] = std::move(lv);
  doc["iterations"] = result.iterations;
  if (withDetails) {
    doc["optimality_iterations"] = result.optimality_iterations;
    doc["factorizations"] = result.factorizations;
    json act = json::array();
    json rank = json::array();
    for (int l = 0; l < problem.levelCount(); ++l) {
      json a = json::array();
      for (RowState s : result.active.level[static_cast<size_t>(l)]) a.push_back(toString(s));
      act.push_back(std::move(a));
      rank.push_back(result.rank[static_cast<size_t>(l)]);
    }
    doc["active_set"] = std::move(act);
    doc["rank"] = std::move(rank);
    json viol = json::array();
    for (const auto& v : result.violation) {
      json a = json::array();
      for (int r = 0; r < v.size(); ++r) a.push_back(v(r));
      viol.push_back(std::move(a));
    }
    doc["violation"] = std::move(viol);
  }
  if (options) {
    doc["solver_options"] = optionsValue(*options);
    doc["solver_options_from"] = options_from;
  }
  return doc.dump();
}

}  // namespace lexdyn::solver
