#include "harness/sweep/sweep_file.hpp"

#include "harness/cases/case_document.hpp"
#include "harness/cases/task_registry.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/control/method.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>

namespace lexdyn::sweep {

namespace fs = std::filesystem;

std::string numberText(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

namespace {

// A YAML value as one line of YAML text (flow style, quoted where needed).
std::string flowText(const YAML::Node& n) {
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e << n;
  return e.c_str();
}

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// u in [0, 1) from (seed, point, parameter) alone.
double uniform01(std::uint64_t seed, long point, size_t parameter) {
  const std::uint64_t h = mix64(mix64(mix64(seed) ^ static_cast<std::uint64_t>(point)) ^ static_cast<std::uint64_t>(parameter));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

cases::Override makeOverride(const std::string& path, const std::string& value) { return {path, value, "--set " + path + "=" + value}; }

void readSets(const yaml::Node& n, std::vector<cases::Override>& out) {
  for (const auto& [path, value] : n.entries()) {
    if (value.isNull()) value.fail("expected a value");
    out.push_back(makeOverride(path, flowText(value.raw())));
  }
}

Parameter readParameter(const yaml::Node& node) {
  yaml::StrictMap m(node);
  Parameter p;
  p.where = node.where();
  auto path = m.optional("path");
  auto choices = m.optional("choices");
  if (path) p.paths.push_back(path->asString());
  if (auto also = m.optional("also")) {
    if (!path) also->fail("also needs path");
    for (const yaml::Node& a : also->elements()) p.paths.push_back(a.asString());
  }
  if (auto nm = m.optional("name"))
    p.name = nm->asString();
  else if (path)
    p.name = p.paths.front();
  else
    node.fail("a parameter with choices needs a name");
  int kinds = 0;
  if (auto r = m.optional("range")) {
    ++kinds;
    const Eigen::VectorXd v = r->asVector(2);
    p.lo = v[0];
    p.hi = v[1];
    if (!(p.lo < p.hi))
      r->fail("expected [lo, hi] with lo < hi (an empty range), found [" + numberText(p.lo) + ", " + numberText(p.hi) + "]");
    p.distribution = Distribution::Uniform;
    if (auto sc = m.optional("scale")) {
      if (sc->asEnum({"linear", "log"}) == "log") {
        if (!(p.lo > 0.0)) r->fail("a log scale needs lo > 0");
        p.distribution = Distribution::LogUniform;
      }
    }
  }
  if (auto r = m.optional("integers")) {
    ++kinds;
    if (r->size() != 2) r->fail("expected [lo, hi]");
    p.lo = (*r)[0].asInt();
    p.hi = (*r)[1].asInt();
    if (!(p.lo <= p.hi)) r->fail("expected [lo, hi] with lo <= hi");
    p.distribution = Distribution::Integers;
  }
  if (auto v = m.optional("values")) {
    ++kinds;
    if (v->size() < 1) v->fail("expected at least one value (an empty set)");
    for (const yaml::Node& e : v->elements()) p.values.push_back(flowText(e.raw()));
    p.distribution = Distribution::Values;
  }
  if (choices) {
    ++kinds;
    if (path) choices->fail("give either path (with range, integers or values) or choices, not both");
    if (choices->size() < 1) choices->fail("expected at least one choice");
    for (const yaml::Node& c : choices->elements()) {
      yaml::StrictMap cm(c);
      Choice ch;
      ch.label = cm.required("label").asString();
      for (const auto& o : p.choices) {
        if (o.label == ch.label) cm.required("label").fail("duplicate label '" + ch.label + "'");
      }
      const yaml::Node sets = cm.required("set");
      readSets(sets, ch.sets);
      if (ch.sets.empty()) sets.fail("expected at least one PATH: VALUE");
      cm.finish();
      p.choices.push_back(ch);
    }
    p.distribution = Distribution::Choices;
  }
  if (!path && !choices) node.fail("a parameter needs path (and range, integers or values) or choices");
  if (kinds != 1) node.fail("a parameter needs exactly one of range, integers, values, choices");
  if (m.has("scale") && p.distribution != Distribution::Uniform && p.distribution != Distribution::LogUniform) {
    m.optional("scale")->fail("scale applies to range only");
  }
  if (auto st = m.optional("steps")) {
    p.steps = st->asInt();
    if (p.steps < 2) st->fail("expected an integer >= 2");
    if (p.distribution == Distribution::Values || p.distribution == Distribution::Choices) st->fail("steps applies to range and integers");
  }
  if (auto s = m.optional("simplest")) p.simplest = s->isScalar() ? s->raw().Scalar() : flowText(s->raw());
  m.finish();
  return p;
}

cases::CaseSpec loadWith(const SweepSpec& s, const std::vector<cases::Override>& o) { return cases::loadCase(s.base_case, o); }

// The base case's value at `path` as text, or "" when the base leaves it out.
std::string baseValue(const SweepSpec& s, const std::string& path) {
  const YAML::Node root = YAML::Load(s.base.document);
  try {
    const cases::doc::Resolved r = cases::doc::resolve(root, path, {}, "");
    if (r.exists && r.node.IsScalar()) return r.node.Scalar();
    if (r.exists) return flowText(r.node);
  } catch (const InputError&) {}
  return "";
}

bool parsesAsNumber(const std::string& t, double& v) {
  const char* b = t.c_str();
  char* end = nullptr;
  v = std::strtod(b, &end);
  return !t.empty() && end == b + t.size() && std::isfinite(v);
}

void validateParameter(SweepSpec& s, Parameter& p, const yaml::Node& node, bool probe) {
  for (const auto& o : s.parameters) {
    if (o.name == p.name) node.fail("duplicate parameter name '" + p.name + "'");
  }
  // Every value the parameter can take must give a case that loads: each end of a range, each
  // value, each choice (with the other parameters at the base case's values).
  std::vector<std::string> probes;
  if (p.numeric()) {
    probes = {p.distribution == Distribution::Integers ? std::to_string(static_cast<long>(p.lo)) : numberText(p.lo),
              p.distribution == Distribution::Integers ? std::to_string(static_cast<long>(p.hi)) : numberText(p.hi)};
  } else if (p.distribution == Distribution::Values) {
    probes = p.values;
  } else {
    for (const auto& c : p.choices) probes.push_back(c.label);
  }
  const size_t k = s.parameters.size();
  s.parameters.push_back(p);
  if (!probe) probes.clear();
  for (const std::string& v : probes) {
    std::vector<std::string> values(s.parameters.size());
    values[k] = v;
    try {
      loadWith(s, overridesOf(s, values));
    } catch (const InputError& e) {
      s.parameters.pop_back();
      throw InputError(p.where, "parameter '" + p.name + "' = " + v + ": " + e.what());
    }
  }
  Parameter& q = s.parameters.back();
  // The simplest value: given, or the base case's.
  if (q.simplest.empty()) {
    const std::string base = q.distribution == Distribution::Choices ? "" : baseValue(s, q.paths.front());
    double v = 0.0;
    if (q.distribution == Distribution::Choices) {
      q.simplest = q.choices.front().label;
    } else if (q.numeric()) {
      if (!parsesAsNumber(base, v)) node.fail("the base case has no number at " + q.paths.front() + "; give simplest");
      q.simplest = base;
    } else {
      q.simplest = std::find(q.values.begin(), q.values.end(), base) != q.values.end() ? base : q.values.front();
    }
  } else if (q.distribution == Distribution::Choices) {
    bool found = false;
    for (const auto& c : q.choices) found = found || c.label == q.simplest;
    if (!found) node.fail("simplest '" + q.simplest + "' is not a choice label");
  } else if (q.numeric()) {
    double v = 0.0;
    if (!parsesAsNumber(q.simplest, v)) node.fail("simplest must be a number, found '" + q.simplest + "'");
  }
  // A simplest value outside what the case accepts fails here rather than while shrinking.
  if (!probe) return;
  std::vector<std::string> values(s.parameters.size());
  values[k] = q.simplest;
  try {
    loadWith(s, overridesOf(s, values));
  } catch (const InputError& e) {
    throw InputError(q.where + ".simplest", e.what());
  }
}

}  // namespace

std::vector<std::string> gridValues(const Parameter& p) {
  std::vector<std::string> out;
  switch (p.distribution) {
    case Distribution::Values:
      return p.values;
    case Distribution::Choices:
      for (const auto& c : p.choices) out.push_back(c.label);
      return out;
    case Distribution::Integers: {
      const long lo = static_cast<long>(p.lo), hi = static_cast<long>(p.hi);
      if (p.steps == 0) {
        for (long i = lo; i <= hi; ++i) out.push_back(std::to_string(i));
      } else {
        for (int i = 0; i < p.steps; ++i) {
          const long v = lo + std::lround(static_cast<double>(hi - lo) * i / (p.steps - 1));
          if (out.empty() || out.back() != std::to_string(v)) out.push_back(std::to_string(v));
        }
      }
      return out;
    }
    case Distribution::Uniform:
    case Distribution::LogUniform:
      for (int i = 0; i < p.steps; ++i) {
        const double f = static_cast<double>(i) / (p.steps - 1);
        const double v = p.distribution == Distribution::Uniform ? p.lo + (p.hi - p.lo) * f
                                                                 : std::exp(std::log(p.lo) + (std::log(p.hi) - std::log(p.lo)) * f);
        out.push_back(numberText(i == p.steps - 1 ? p.hi : (i == 0 ? p.lo : v)));
      }
      return out;
  }
  return out;
}

Point pointAt(const SweepSpec& s, long index) {
  Point pt;
  pt.index = index;
  if (s.grid) {
    long rest = index;
    std::vector<std::string> values(s.parameters.size());
    for (size_t k = s.parameters.size(); k-- > 0;) {  // the last parameter varies fastest
      const std::vector<std::string> g = gridValues(s.parameters[k]);
      const long n = static_cast<long>(g.size());
      values[k] = g[static_cast<size_t>(rest % n)];
      rest /= n;
    }
    pt.values = values;
    return pt;
  }
  for (size_t k = 0; k < s.parameters.size(); ++k) {
    const Parameter& p = s.parameters[k];
    const double u = uniform01(s.seed, index, k);
    switch (p.distribution) {
      case Distribution::Uniform:
        pt.values.push_back(numberText(p.lo + (p.hi - p.lo) * u));
        break;
      case Distribution::LogUniform:
        pt.values.push_back(numberText(std::exp(std::log(p.lo) + (std::log(p.hi) - std::log(p.lo)) * u)));
        break;
      case Distribution::Integers: {
        const long lo = static_cast<long>(p.lo), hi = static_cast<long>(p.hi);
        pt.values.push_back(std::to_string(std::min(hi, lo + static_cast<long>(std::floor(u * static_cast<double>(hi - lo + 1))))));
        break;
      }
      case Distribution::Values:
        pt.values.push_back(p.values[std::min(p.values.size() - 1, static_cast<size_t>(u * p.values.size()))]);
        break;
      case Distribution::Choices:
        pt.values.push_back(p.choices[std::min(p.choices.size() - 1, static_cast<size_t>(u * p.choices.size()))].label);
        break;
    }
  }
  return pt;
}

std::vector<cases::Override> overridesOf(const SweepSpec& s, const std::vector<std::string>& values) {
  std::vector<cases::Override> out = s.sets;
  for (size_t k = 0; k < s.parameters.size() && k < values.size(); ++k) {
    if (values[k].empty()) continue;
    const Parameter& p = s.parameters[k];
    if (p.distribution == Distribution::Choices) {
      for (const auto& c : p.choices) {
        if (c.label == values[k]) out.insert(out.end(), c.sets.begin(), c.sets.end());
      }
      continue;
    }
    for (const std::string& path : p.paths) out.push_back(makeOverride(path, values[k]));
  }
  return out;
}

std::vector<std::string> propertyChecks(const SweepSpec& s, const std::string& method) {
  std::vector<std::string> out;
  for (const std::string& name : s.checks) {
    for (const auto& c : s.base.checks) {
      if (c.name == name && checks::appliesTo(c, method)) out.push_back(name);
    }
  }
  return out;
}

SweepSpec loadSweep(const std::string& path, bool validate) {
  const yaml::Node root = yaml::loadFile(path);
  yaml::StrictMap top(root);
  SweepSpec s;
  s.path = path;
  if (auto f = top.optional("format")) {
    if (f->asString() != "lexdyn-sweep/1") f->fail("expected lexdyn-sweep/1");
  }
  s.name = top.required("name").asString();
  if (s.name.find_first_of("/ \t\n\\\"'") != std::string::npos)
    top.required("name").fail("names may not contain slashes, whitespace or quotes");
  if (auto d = top.optional("description")) s.description = d->asString();
  const yaml::Node base = top.required("base");
  s.base_case_text = base.asString();
  {
    const fs::path rel(s.base_case_text);
    s.base_case = (rel.is_absolute() ? rel : fs::path(path).parent_path() / rel).lexically_normal().string();
    std::error_code ec;
    if (!fs::is_regular_file(s.base_case, ec)) base.fail("file not found: " + s.base_case);
  }
  if (auto sets = top.optional("set")) readSets(*sets, s.sets);
  try {
    s.base = cases::loadCase(s.base_case, s.sets);
  } catch (const InputError& e) {
    base.fail(std::string("the base case does not load: ") + e.what());
  }
  if (!cases::isLexdyn(s.base))
    base.fail(std::string("sweeps run lexdyn cases (the base case's controller is ") + records::toString(s.base.controller.type) + ")");
  const yaml::Node methods = top.required("methods");
  if (methods.size() < 1) methods.fail("expected at least one method");
  for (const yaml::Node& mn : methods.elements()) {
    const std::string m = mn.asEnum(control::methodNames());
    if (std::find(s.methods.begin(), s.methods.end(), m) != s.methods.end()) mn.fail("method " + m + " listed twice");
    try {
      cases::CaseSpec c = s.base;
      cases::overrideMethod(c, m, mn.where());
    } catch (const InputError& e) {
      mn.fail(e.detail());
    }
    s.methods.push_back(m);
  }
  const yaml::Node seed = top.required("seed");
  const int sv = seed.asInt();
  if (sv < 0) seed.fail("expected an integer >= 0");
  s.seed = static_cast<std::uint64_t>(sv);
  if (auto d = top.optional("duration_s")) {
    s.duration_s = d->asPositiveDouble();
    if (*s.duration_s < s.base.control_period_s) d->fail("expected at least one control period");
  }
  if (auto t = top.optional("timeout_s")) s.timeout_s = t->asPositiveDouble();
  if (auto t = top.optional("trace_every_n_ticks")) {
    s.trace_every_n_ticks = t->asInt();
    if (s.trace_every_n_ticks < 1) t->fail("expected an integer >= 1");
  }
  const yaml::Node params = top.required("parameters");
  if (params.size() < 1) params.fail("expected at least one parameter");
  for (const yaml::Node& pn : params.elements()) {
    Parameter p = readParameter(pn);
    validateParameter(s, p, pn, validate);
  }
  const yaml::Node sampling = top.required("sampling");
  {
    yaml::StrictMap sm(sampling);
    auto points = sm.optional("points");
    auto grid = sm.optional("grid");
    if ((points ? 1 : 0) + (grid ? 1 : 0) != 1) sampling.fail("expected either points: N (random sampling) or grid: true");
    if (points) {
      const int n = points->asInt();
      if (n < 1 || n > 1000000) points->fail("expected 1 to 1000000 points");
      s.points = n;
    } else {
      if (!grid->asBool()) grid->fail("expected grid: true (or points: N)");
      s.grid = true;
      s.points = 1;
      for (size_t k = 0; k < s.parameters.size(); ++k) {
        const Parameter& p = s.parameters[k];
        if ((p.distribution == Distribution::Uniform || p.distribution == Distribution::LogUniform) && p.steps == 0) {
          params[static_cast<int>(k)].fail("a grid needs steps for a range");
        }
        s.points *= static_cast<long>(gridValues(p).size());
        if (s.points > 1000000) sampling.fail("the grid has more than 1000000 points");
      }
    }
    sm.finish();
  }
  if (auto props = top.optional("properties")) {
    yaml::StrictMap pm(*props);
    if (auto c = pm.optional("checks")) {
      if (c->isScalar()) {
        if (c->asString() != "all") c->fail("expected all or a list of check names");
      } else {
        for (const yaml::Node& cn : c->elements()) {
          const std::string name = cn.asString();
          std::vector<std::string> names;
          bool found = false, wall_clock = false;
          for (const auto& ck : s.base.checks) {
            names.push_back(ck.name);
            if (ck.name != name) continue;
            found = true;
            wall_clock = wall_clock || checks::machineDependent(ck);
          }
          if (!found) cn.fail("the base case has no check '" + name + "' (checks: " + cases::joinNames(names) + ")");
          if (wall_clock)
            cn.fail("check '" + name + "' is a wall-clock check (machine-dependent): a sweep's verdicts may not depend on the machine");
          bool any = false;
          for (const auto& m : s.methods) {
            for (const auto& ck : s.base.checks) any = any || (ck.name == name && checks::appliesTo(ck, m));
          }
          if (!any) cn.fail("check '" + name + "' applies to none of the sweep's methods");
          s.checks.push_back(name);
        }
        if (s.checks.empty()) c->fail("expected at least one check (or leave checks out: all of them)");
      }
    }
    if (!pm.has("checks")) {
      for (const auto& ck : s.base.checks) {
        if (!checks::machineDependent(ck)) s.checks.push_back(ck.name);  // wall-clock checks are not verdicts here
      }
    }
    if (auto cs = pm.optional("comparisons")) {
      for (const yaml::Node& cn : cs->elements()) {
        Comparison c;
        if (cn.isScalar()) {
          const std::string name = cn.asString();
          bool found = false;
          for (const auto& bc : s.base.comparisons) {
            if (bc.name == name) {
              c = bc;
              found = true;
            }
          }
          if (!found) cn.fail("the base case has no comparison '" + name + "'");
        } else {
          c = cases::readComparison(cn, s.base);
        }
        for (const std::string* m : {&c.better, &c.worse}) {
          if (std::find(s.methods.begin(), s.methods.end(), *m) == s.methods.end()) {
            cn.fail("comparison '" + c.name + "' needs method " + *m + ", which the sweep does not run");
          }
        }
        for (const auto& o : s.comparisons) {
          if (o.name == c.name) cn.fail("duplicate comparison '" + c.name + "'");
        }
        s.comparisons.push_back(c);
      }
    }
    pm.finish();
  } else {
    for (const auto& ck : s.base.checks) {
      if (!checks::machineDependent(ck)) s.checks.push_back(ck.name);
    }
  }
  if (auto sh = top.optional("shrink")) {
    yaml::StrictMap sm(*sh);
    if (auto v = sm.optional("enabled")) s.shrink.enabled = v->asBool();
    if (auto v = sm.optional("max_runs")) {
      s.shrink.max_runs = v->asInt();
      if (s.shrink.max_runs < 1) v->fail("expected an integer >= 1");
    }
    if (auto v = sm.optional("max_total_runs")) {
      s.shrink.max_total_runs = v->asInt();
      if (s.shrink.max_total_runs < 1) v->fail("expected an integer >= 1");
    }
    if (auto v = sm.optional("bisection_steps")) {
      s.shrink.bisection_steps = v->asInt();
      if (s.shrink.bisection_steps < 0 || s.shrink.bisection_steps > 30) v->fail("expected an integer in 0..30");
    }
    if (auto v = sm.optional("min_duration_s")) s.shrink.min_duration_s = v->asPositiveDouble();
    sm.finish();
  }
  top.finish();
  return s;
}

}  // namespace lexdyn::sweep
