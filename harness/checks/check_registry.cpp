#include "harness/checks/check_registry.hpp"

#include "harness/checks/contact_checks.hpp"
#include "harness/checks/health_checks.hpp"
#include "harness/checks/joint_checks.hpp"
#include "harness/checks/sim_checks.hpp"
#include "harness/checks/task_checks.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"

#include <algorithm>

namespace lexdyn::checks {

const CheckRegistry& builtinChecks() {
  static const CheckRegistry registry = [] {
    CheckRegistry r;
    // One line per type; the order is that of the messages listing the types.
    r.add(frameDriftCheck());
    r.add(forceBalanceCheck());
    r.add(contactSlipCheck());
    r.add(frameHeightCheck());
    r.add(taskErrorCheck());
    r.add(torqueLimitsCheck());
    r.add(contactUnilateralCheck());
    r.add(contactFrictionCheck());
    r.add(contactCopCheck());
    r.add(contactWrenchMatchCheck());
    r.add(jointAccelerationSignChangesCheck());
    r.add(jointVelocityHfEnergyCheck());
    r.add(taskErrorRateSignChangesCheck());
    r.add(taskErrorClosedFormCheck());
    r.add(taskOvershootCheck());
    r.add(controllerStatusCheck());
    r.add(activeSetPeakCheck());
    r.add(factorizationPeakCheck());
    r.add(augmentedFractionCheck());
    r.add(tickTimeCheck());
    return r;
  }();
  return registry;
}

// ---------------------------------------------------------------------------------------------
// The registry.

void CheckRegistry::add(CheckType type) {
  LEXDYN_ALWAYS_ASSERT(!type.name.empty() && type.parse && type.make, "a check type needs a name, a parser and an evaluator");
  LEXDYN_ALWAYS_ASSERT(!find(type.name), "check type registered twice");
  names_.push_back(type.name);
  types_.push_back(std::move(type));
}

const CheckType* CheckRegistry::find(const std::string& name) const {
  for (const CheckType& t : types_) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

const CheckType& CheckRegistry::get(const std::string& name, const std::string& where) const {
  const CheckType* t = find(name);
  if (!t) throw InputError(where, "unknown check type '" + name + "' (known: " + joinNames(names_) + ")");
  return *t;
}

const std::vector<std::string>& checkTypes() { return builtinChecks().names(); }

std::unique_ptr<Check> makeCheck(const CheckSpec& spec, const CheckRegistry& registry) {
  const CheckType& t = registry.get(spec.type, spec.where);
  return t.make(spec, t);
}

std::unique_ptr<Check> makeCheck(const CheckSpec& spec) { return makeCheck(spec, builtinChecks()); }

bool machineDependent(const CheckSpec& spec) {
  const CheckType* t = builtinChecks().find(spec.type);
  return t && t->machineDependent();
}

CheckSpec readCheck(const yaml::Node& node, const CheckContext& context, const CheckRegistry& registry) {
  yaml::StrictMap m(node);
  CheckSpec c;
  c.where = node.where();
  const yaml::Node typeNode = m.required("type");
  c.type = typeNode.asEnum(registry.names());
  const CheckType& type = *registry.find(c.type);
  c.name = c.type;
  if (auto n = m.optional("name")) c.name = n->asString();
  if (auto f = m.optional("from_s")) c.from_s = f->asDoubleIn(0.0, ranges::kMaxTime_s, "s");
  if (auto v = m.optional("methods")) {
    if (!context.lexdyn()) v->fail("methods: applies to the lexdyn controller only");
    for (const yaml::Node& mn : v->elements()) c.methods.push_back(context.method(mn));
  }
  if (type.readsController()) {
    if (!context.lexdyn()) {
      typeNode.fail("check type " + c.type + " reads the lexdyn controller's channels; the controller is " +
                    records::toString(context.controller));
    }
    if (auto t = m.optional("to_s")) {
      c.to_s = t->asNonNegativeDouble();
      if (c.to_s < c.from_s) t->fail("to_s must not be before from_s");
    }
  }
  CheckReader reader{m, context, c, c.methods.empty() && context.lexdyn() ? context.caseMethods() : c.methods};
  type.parse(reader);
  m.finish();
  return c;
}

// ---------------------------------------------------------------------------------------------
// The parsers' helpers.

bool globMatch(const std::string& pattern, const std::string& text) {
  // Iterative matcher with backtracking to the last '*'.
  size_t p = 0, t = 0, star = std::string::npos, mark = 0;
  while (t < text.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = t;
    } else if (p < pattern.size() && pattern[p] == text[t]) {
      ++p;
      ++t;
    } else if (star != std::string::npos) {
      p = star + 1;
      t = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

std::string joinNames(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

namespace {

bool contains(const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); }

template <class T>
const T* byName(const std::vector<T>& v, const std::string& name) {
  for (const T& x : v) {
    if (x.name == name) return &x;
  }
  return nullptr;
}

}  // namespace

std::vector<std::string> CheckContext::methodNames() const {
  std::vector<std::string> out;
  for (const Method& m : methods) out.push_back(m.name);
  return out;
}

std::vector<std::string> CheckContext::caseMethods() const {
  std::vector<std::string> out;
  for (const Method& m : methods) {
    if (m.has_hierarchy) out.push_back(m.name);
  }
  return out;
}

const CheckContext::Method* CheckContext::findMethod(const std::string& name) const { return byName(methods, name); }
const CheckContext::Task* CheckContext::findTask(const std::string& name) const { return byName(tasks, name); }
const CheckContext::Contact* CheckContext::findContact(const std::string& name) const { return byName(contacts, name); }

std::vector<std::string> CheckContext::jointNames() const {
  std::vector<std::string> out;
  for (const Joint& j : joints) out.push_back(j.name);
  return out;
}

std::string knownName(const yaml::Node& n, const std::vector<std::string>& names, const std::string& kind, const std::string& list) {
  const std::string name = n.asString();
  if (!contains(names, name)) n.fail("unknown " + kind + " '" + name + "' (" + list + ": " + joinNames(names) + ")");
  return name;
}

std::vector<yaml::Node> atLeastOne(const yaml::Node& n, const std::string& what) {
  if (n.size() < 1) n.fail("expected at least one " + what);
  return n.elements();
}

std::string CheckContext::frame(const yaml::Node& n) const { return knownName(n, frames, "frame", "frames"); }
std::string CheckContext::surface(const yaml::Node& n) const { return knownName(n, surfaces, "contact surface", "surfaces"); }

std::vector<std::string> CheckContext::jointPatterns(const yaml::Node& n) const {
  std::vector<std::string> out;
  for (const yaml::Node& pn : atLeastOne(n, "joint pattern")) {
    const std::string pattern = pn.asString();
    int matched = 0;
    for (const Joint& j : joints) {
      if (!globMatch(pattern, j.name)) continue;
      ++matched;
      if (!contains(out, j.name)) out.push_back(j.name);
    }
    if (matched == 0) pn.fail("pattern '" + pattern + "' matches no joint");
  }
  return out;
}

std::vector<std::string> CheckContext::taskNames(const yaml::Node& n) const {
  std::vector<std::string> out;
  for (const yaml::Node& tn : atLeastOne(n, "task")) {
    out.push_back(tn.asString());
    if (!findTask(out.back())) tn.fail("unknown task '" + out.back() + "'");
  }
  return out;
}

std::string CheckContext::method(const yaml::Node& n) const {
  const std::string name = n.asEnum(methodNames());
  if (!findMethod(name)->has_hierarchy) n.fail("the case has no hierarchy for method " + name);
  return name;
}

void CheckContext::requireTasksInHierarchies(const yaml::Node& at, const std::vector<std::string>& task_names,
                                             const std::vector<std::string>& method_names) const {
  for (const std::string& m : method_names) {
    const Method* method = findMethod(m);
    for (const std::string& t : task_names) {
      if (!method || !contains(method->tasks, t)) {
        at.fail("task '" + t + "' is not in the hierarchy of method " + m +
                " (its channels are not recorded then); restrict the check with methods: [...]");
      }
    }
  }
}

std::string CheckReader::task(const std::string& key) {
  const yaml::Node tn = map.required(key);
  const std::string t = tn.asString();
  if (!context.findTask(t)) tn.fail("unknown task '" + t + "'");
  context.requireTasksInHierarchies(tn, {t}, methods);
  return t;
}

std::vector<std::string> CheckReader::tasks(const std::string& key) {
  const yaml::Node tn = map.required(key);
  std::vector<std::string> out = context.taskNames(tn);
  context.requireTasksInHierarchies(tn, out, methods);
  return out;
}

double CheckReader::number(const std::string& key, double fallback, double (yaml::Node::*read)() const) {
  if (auto v = map.optional(key)) return ((*v).*read)();
  return fallback;
}

std::vector<std::string> CheckReader::joints() {
  if (auto j = map.optional("joints")) return context.jointPatterns(*j);
  return context.jointNames();
}

const CheckContext::Contact& CheckReader::contact(std::string* source) {
  const yaml::Node cn = map.required("contact");
  const std::string name = cn.asString();
  const CheckContext::Contact* c = context.findContact(name);
  if (!c) cn.fail("unknown controller contact '" + name + "'");
  bool needs_sensor = true;
  if (source) {
    *source = "computed";
    if (auto src = map.optional("source")) *source = src->asEnum({"computed", "sensed"});
    needs_sensor = *source == "sensed";
  }
  if (needs_sensor && !c->has_sensor) cn.fail("contact '" + name + "' has no linked sensor (controller.contacts[].sensor)");
  return *c;
}

}  // namespace lexdyn::checks
