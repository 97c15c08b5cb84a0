#include "harness/cases/lexdyn_spec.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lexdyn::cases {

namespace {

namespace R = lexdyn::ranges;

// Dimensionless controller parameters (thresholds in multiples of dt^2, damping, weights):
// within [0, 1e6] (docs/simulator.md, "Ranges").
double dimensionless(const yaml::Node& n) { return n.asDoubleIn(0.0, R::kMaxDimensionless); }

void readParams(yaml::StrictMap& pm, control::ControllerParams& p) {
  if (auto v = pm.optional("nu_dt2")) p.nu_dt2 = dimensionless(*v);
  if (auto v = pm.optional("xi_dt2")) p.xi_dt2 = dimensionless(*v);
  if (auto v = pm.optional("zeta_dt2")) p.zeta_dt2 = dimensionless(*v);
  if (auto v = pm.optional("new_dof_diagonal_dt2")) p.new_dof_diagonal_dt2 = dimensionless(*v);
  if (auto v = pm.optional("rho_dt2")) p.rho_dt2 = dimensionless(*v);
  if (auto v = pm.optional("eps_dt2")) p.eps_dt2 = dimensionless(*v);
  if (auto v = pm.optional("newton_target")) {
    p.newton_target =
        v->asEnum({"zero", "previous_velocity"}) == "zero" ? control::NewtonTarget::Zero : control::NewtonTarget::PreviousVelocity;
  }
  if (auto v = pm.optional("damping")) p.damping = dimensionless(*v);
  if (auto v = pm.optional("use_qmod")) p.use_qmod = v->asBool();
  if (auto v = pm.optional("sr1")) p.sr1 = v->asBool();
  if (auto v = pm.optional("bfgs_secant")) {
    const std::string r = v->asEnum({"current_multipliers", "full_difference", "gauss_newton"});
    p.bfgs_secant = r == "current_multipliers" ? control::BfgsSecant::CurrentMultipliers
                    : r == "full_difference"   ? control::BfgsSecant::FullDifference
                                               : control::BfgsSecant::GaussNewton;
  }
  if (auto v = pm.optional("ah_add_jtj")) p.ah_add_jtj = v->asBool();
  if (auto v = pm.optional("multiplier_scale")) {
    p.multiplier_scale = v->asEnum({"dt", "one"}) == "dt" ? control::MultiplierScale::Dt : control::MultiplierScale::One;
  }
  if (auto v = pm.optional("newton_identity_weight")) p.newton_identity_weight = dimensionless(*v);
  if (auto v = pm.optional("stop_after_level")) p.stop_after_level = v->asString();
  if (auto v = pm.optional("rank_switching")) p.rank_switching = v->asBool();
  if (auto v = pm.optional("sign_change_guard")) p.sign_change_guard = v->asBool();
  if (auto v = pm.optional("wls_infeasibility_tolerance")) {
    p.wls_infeasibility_tolerance = v->asPositiveDouble();
    if (p.wls_infeasibility_tolerance > 1.0) v->asDoubleIn(0.0, 1.0);
  }
}

solver::Options readSolver(yaml::StrictMap& sm, double dt) {
  solver::Options o = control::defaultSolverOptions();
  if (auto v = sm.optional("paper_rules")) {
    if (v->asBool()) o = control::paperSolverOptions(dt);
  }
  auto positiveInt = [](const yaml::Node& n) { return n.asIntIn(1, R::kMaxSolverIterations); };
  auto nonNegativeInt = [](const yaml::Node& n) { return n.asIntIn(0, R::kMaxSolverIterations); };
  // Tolerances are relative: positive and at most 1e-2 (beyond, every row counts as dependent,
  // satisfied or optimal).
  auto tolerance = [](const yaml::Node& n) {
    const double t = n.asPositiveDouble();
    if (t > R::kMaxSolverTolerance) n.asDoubleIn(0.0, R::kMaxSolverTolerance);
    return t;
  };
  if (auto v = sm.optional("max_iterations")) o.max_iterations = positiveInt(*v);
  if (auto v = sm.optional("rank_tolerance")) o.rank_tolerance = tolerance(*v);
  if (auto v = sm.optional("feasibility_tolerance")) o.feasibility_tolerance = tolerance(*v);
  if (auto v = sm.optional("zero_tolerance")) o.zero_tolerance = tolerance(*v);
  if (auto v = sm.optional("dual_tolerance")) o.dual_tolerance = tolerance(*v);
  if (auto v = sm.optional("eliminate_first_level")) o.eliminate_first_level = v->asBool();
  if (auto v = sm.optional("elimination_tolerance")) {
    o.elimination_tolerance = v->asPositiveDouble();
    if (o.elimination_tolerance > 1.0) v->asDoubleIn(0.0, 1.0);
  }
  if (auto v = sm.optional("split_force_coordinates")) {
    o.split_from_variable = v->asBool() ? solver::Options::kSplitAtControllerForces : -1;
  }
  if (auto v = sm.optional("spanning_stages")) o.spanning_stages = v->asBool();
  if (auto v = sm.optional("spanning_any_rows")) o.spanning_any_rows = v->asBool();
  if (auto v = sm.optional("spanning_structured")) o.spanning_structured = v->asBool();
  if (auto v = sm.optional("lazy_snapshots")) o.lazy_snapshots = v->asBool();
  if (auto v = sm.optional("project_unit_suffix")) o.project_unit_suffix = v->asBool();
  if (auto v = sm.optional("restart_after_bound_change")) o.restart_after_bound_change = v->asBool();
  if (auto v = sm.optional("swap_reflectors")) o.swap_reflectors = v->asBool();
  if (auto v = sm.optional("last_level_projection")) {
    const std::string mode = v->asString();
    if (mode == "auto") {
      o.last_level_projection = solver::Options::LastLevel::Auto;
    } else if (mode == "never") {
      o.last_level_projection = solver::Options::LastLevel::Never;
    } else if (mode == "always") {
      o.last_level_projection = solver::Options::LastLevel::Always;
    } else {
      v->fail("expected auto, never or always, found \"" + mode + "\"");
    }
  }
  if (auto v = sm.optional("bland_after_degenerate_steps")) o.bland_after_degenerate_steps = positiveInt(*v);
  if (auto v = sm.optional("cycle_tolerance_factor")) o.cycle_tolerance_factor = v->asDoubleIn(1.0, R::kMaxDimensionless);
  // The paper's termination rules individually (0 disables a rule); override paper_rules.
  if (auto v = sm.optional("stop_slack_norm")) o.stop_slack_norm = dimensionless(*v);
  if (auto v = sm.optional("stop_optimality_iterations")) o.stop_optimality_iterations = nonNegativeInt(*v);
  if (auto v = sm.optional("stop_total_iterations")) o.stop_total_iterations = nonNegativeInt(*v);
  return o;
}

// A contact_margins map (controller.contact_margins or a contact's `margins`): the keys it gives
// replace those of `m`.
tasks::ContactMargins readMargins(const yaml::Node& node, tasks::ContactMargins m) {
  yaml::StrictMap mm(node);
  if (auto v = mm.optional("friction")) {
    m.friction = v->asDouble();
    if (!(m.friction >= 0.0 && m.friction < 1.0)) v->fail("expected the fraction of the friction coefficient kept in reserve, in [0, 1)");
  }
  if (auto v = mm.optional("cop_m")) m.cop_m = v->asDoubleIn(0.0, R::kMaxLength_m, "m");
  if (auto v = mm.optional("min_normal_N")) m.min_normal_N = v->asDoubleIn(0.0, 1.0e5, "N");

  mm.finish();
  return m;
}

// The controller's contact of an entry, margins applied (the frame id is the caller's: it needs
// the model). Returns the margins' problems (empty when they fit the contact).
std::vector<std::string> plannedContact(const ContactEntry& c, tasks::ContactSpec& cs) {
  cs.name = c.name;
  cs.points = c.points;
  cs.fixed = c.fixed;
  cs.friction = c.friction;
  cs.normal_in_frame = c.normal;
  cs.point = c.dims == 3;
  return tasks::applyContactMargins(cs, c.margins);
}

}  // namespace

tasks::ContactMargins defaultContactMargins(const std::vector<Eigen::Vector3d>& points, bool point_contact, double weight_N) {
  // exp1's margins on HRP-2 (0.1, 1 cm on soles of half extents 0.07 m, 10 N per corner of 4 for
  // 637 N; docs/results.md, "exp1 variants nobody tuned for"), as fractions.
  tasks::ContactMargins m = kNoContactMargins;
  if (points.empty()) return m;
  m.friction = 0.1;
  if (!point_contact && points.size() >= 3) {
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& p : points) {
      lo = lo.cwiseMin(p.head<2>());
      hi = hi.cwiseMax(p.head<2>());
    }
    m.cop_m = std::min(0.01, std::floor(0.14 * 0.5 * (hi - lo).minCoeff() * 1000.0) / 1000.0);
  }
  m.min_normal_N = std::round(10.0 * 0.063 * weight_N / static_cast<double>(points.size())) / 10.0;
  return m;
}

namespace {

ContactEntry readContact(const yaml::Node& node, const model::RobotDescription& d, const tasks::ContactMargins& margins,
                         const std::optional<yaml::Node>& margins_node, bool default_margins, double weight_N) {
  yaml::StrictMap m(node);
  ContactEntry c;
  c.where = node.where();
  c.name = channelName(m.required("name"));
  auto surface = m.optional("surface");
  auto frame = m.optional("frame");
  if (surface && frame) frame->fail("give either surface or frame (with points), not both");
  if (!surface && !frame) m.node().fail("a contact needs a surface (of the robot data file) or a frame with points");
  if (surface) {
    c.surface = surface->asString();
    bool found = false;
    std::vector<std::string> names;
    for (const auto& s : d.contact_surfaces) {
      names.push_back(s.name);
      if (s.name != c.surface) continue;
      found = true;
      c.frame = d.frames[static_cast<size_t>(s.frame)].name;
      c.points = s.points;
      // Ball feet (radius): the controller holds the point of each sphere below its centre
      // along the frame's -z (the sole frame is z up in the posture), where it touches the ground.
      for (auto& p : c.points) p.z() -= s.radius;
    }
    if (!found) surface->fail("unknown contact surface '" + c.surface + "' (surfaces: " + joinNames(names) + ")");
  } else {
    c.frame = frameName(*frame, d);
    const yaml::Node pts = m.required("points");
    if (pts.size() < 1) pts.fail("expected at least one point");
    for (const yaml::Node& p : pts.elements()) c.points.push_back(p.asVector3In(-R::kMaxLength_m, R::kMaxLength_m, "m"));
  }
  if (auto v = m.optional("fixed")) c.fixed = v->asBool();
  c.dims = c.points.size() == 1 && !c.fixed ? 3 : 6;
  if (auto v = m.optional("dims")) {
    const double k = v->asDouble();
    if (k != 3.0 && k != 6.0) v->fail("expected 3 (a point contact: its position held) or 6 (the frame's pose held)");
    c.dims = static_cast<int>(k);
    if (c.dims == 3 && c.points.size() != 1)
      v->fail("dims 3 is a point contact: it needs exactly one point (this contact has " + std::to_string(c.points.size()) + ")");
  }
  if (auto v = m.optional("normal")) {
    if (c.dims == 3) v->fail("a point contact (dims 3) takes the ground's normal (world +z); normal is for a contact of dims 6");
    c.normal = v->asVector3();
    if (!(c.normal.norm() > 1e-9)) v->fail("expected a nonzero normal");
    c.normal.normalize();
  }
  if (auto v = m.optional("friction")) {
    c.friction = v->asPositiveDouble();
    if (c.friction > R::kMaxFriction) v->asDoubleIn(0.0, R::kMaxFriction);
  } else if (d.friction_coefficient > 0.0) {
    c.friction = d.friction_coefficient;
  } else {
    m.node().fail("the robot data file has no friction_coefficient; give friction here");
  }
  c.margins = default_margins && !c.fixed ? defaultContactMargins(c.points, c.dims == 3, weight_N) : margins;
  c.margins_default = default_margins && !c.fixed;
  if (c.margins_default) {
    // The default CoP margin is sized from the points' bounding box: a narrow or slanted polygon
    // may give less room; halve it until the polygon gives it (none below 0.1 mm).
    tasks::ContactSpec planned;
    while (c.margins.cop_m > 0.0 && !plannedContact(c, planned).empty()) {
      c.margins.cop_m = c.margins.cop_m * 0.5 < 1e-4 ? 0.0 : c.margins.cop_m * 0.5;
    }
  }
  std::optional<yaml::Node> own = m.optional("margins");
  if (own) {
    c.margins = readMargins(*own, c.margins);
    c.margins_default = false;
  }
  {
    // The margins must fit the contact (a CoP margin smaller than its support polygon).
    tasks::ContactSpec planned;
    const std::vector<std::string> problems = plannedContact(c, planned);
    if (!problems.empty()) {
      const yaml::Node& at = own ? *own : (margins_node ? *margins_node : m.node());
      at.fail(problems.front() + (own ? "" : " (the margins of controller.contact_margins; give this contact its own `margins`)"));
    }
  }
  if (auto v = m.optional("grasp")) c.grasp = v->asString();  // checked against sim.grasps by loadCase
  if (auto v = m.optional("sensor")) {
    c.sensor = v->asString();
    bool found = false;
    std::vector<std::string> names;
    for (const auto& s : d.force_sensors) {
      names.push_back(s.name);
      found = found || s.name == c.sensor;
    }
    if (!found) v->fail("unknown force sensor '" + c.sensor + "' (sensors: " + joinNames(names) + ")");
  }
  m.finish();
  return c;
}

std::vector<LevelEntry> readLevels(const yaml::Node& node, const LexdynSpec& spec, bool wls) {
  std::vector<LevelEntry> out;
  const std::vector<yaml::Node> items = node.elements();
  if (items.empty()) node.fail("expected at least one level");
  if (wls && items.size() != 2)
    node.fail("the WLS baseline needs exactly two levels (hard constraints, weighted objective), found " + std::to_string(items.size()));
  std::vector<std::string> seen;
  for (size_t l = 0; l < items.size(); ++l) {
    yaml::StrictMap m(items[l]);
    LevelEntry e;
    e.where = items[l].where();
    const yaml::Node name = m.required("name");
    e.name = channelName(name);
    for (const auto& o : out) {
      if (o.name == e.name) name.fail("duplicate level name '" + e.name + "'");
    }
    const yaml::Node tasks = m.required("tasks");
    for (const yaml::Node& tn : tasks.elements()) {
      const std::string t = tn.asString();
      if (spec.findTask(t) < 0) {
        std::vector<std::string> names;
        for (const auto& ts : spec.tasks) names.push_back(ts.name);
        tn.fail("unknown task '" + t + "' (controller.tasks: " + joinNames(names) + ")");
      }
      for (const auto& s : seen) {
        if (s == t) tn.fail("task '" + t + "' appears twice in this hierarchy");
      }
      seen.push_back(t);
      e.tasks.push_back(t);
    }
    const bool objective = wls && l == 1;
    if (auto w = m.optional("weights")) {
      if (!objective) w->fail("weights are for the WLS objective level (the second of wls_levels) only");
      e.weights.assign(e.tasks.size(), -1.0);
      for (const auto& [task, value] : w->entries()) {
        size_t k = 0;
        while (k < e.tasks.size() && e.tasks[k] != task) ++k;
        if (k == e.tasks.size()) value.fail("task '" + task + "' is not on this level (tasks: " + joinNames(e.tasks) + ")");
        e.weights[k] = value.asDoubleIn(R::kMinWeight, R::kMaxWeight);
      }
      std::vector<std::string> missing;
      for (size_t k = 0; k < e.tasks.size(); ++k) {
        if (e.weights[k] < 0.0) missing.push_back(e.tasks[k]);
      }
      if (!missing.empty()) w->fail("no weight for task(s) " + joinNames(missing));
    } else if (objective) {
      m.node().fail("the WLS objective level needs weights: {task: weight, ...}");
    }
    m.finish();
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

const std::vector<LevelEntry>& LexdynSpec::hierarchy(const std::string& m) const {
  return control::findMethod(m, "method").weighted_hierarchy ? wls_levels : levels;
}

const char* LexdynSpec::hierarchyKey(const std::string& m) const {
  return control::findMethod(m, "method").weighted_hierarchy ? "wls_levels" : "levels";
}

const std::string& LexdynSpec::hierarchyWhere(const std::string& m) const {
  return control::findMethod(m, "method").weighted_hierarchy ? wls_levels_where : levels_where;
}

namespace {

// The index of the entry named `name`, or -1.
template <class Entry>
int indexOfName(const std::vector<Entry>& entries, const std::string& name) {
  for (size_t i = 0; i < entries.size(); ++i) {
    if (entries[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace

int LexdynSpec::findTask(const std::string& name) const { return indexOfName(tasks, name); }

int LexdynSpec::findContact(const std::string& name) const { return indexOfName(contacts, name); }

LexdynSpec readLexdynSpec(yaml::StrictMap& m, const model::RobotDescription& d, double dt) {
  LexdynSpec s;
  const yaml::Node method = m.required("method");
  s.method = method.asEnum(control::methodNames());
  s.method_where = method.where();
  if (auto v = m.optional("feedforward_torque")) s.feedforward_torque = v->asBool();
  if (auto v = m.optional("state_feedback")) s.state_feedback = v->asEnum({"measured", "integrated", "measured_position"});
  if (auto pn = m.optional("params")) {
    yaml::StrictMap pm(*pn);
    readParams(pm, s.params);
    pm.finish();
  }
  if (auto sn = m.optional("solver")) {
    yaml::StrictMap sm(*sn);
    s.params.solver = readSolver(sm, dt);
    sm.finish();
  }
  s.params.dt = dt;
  s.params.method = s.method;
  // Per-method overrides of `params` (e.g. the sec. V-A point mass: the damping each domain is
  // run with). Keys as in `params`, on top of them.
  const std::vector<std::string> names = control::methodNames();
  for (const std::string& name : names) {
    control::ControllerParams& mp = s.params_by_method[name];
    mp = s.params;
    mp.method = name;
  }
  if (auto mp = m.optional("method_params")) {
    for (const auto& [name, node] : mp->entries()) {
      const auto it = s.params_by_method.find(name);
      if (it == s.params_by_method.end()) node.fail("unknown method '" + name + "' (" + joinNames(names) + ")");
      yaml::StrictMap pm(node);
      readParams(pm, it->second);
      pm.finish();
    }
  }
  s.params = s.params_by_method.at(s.method);
  if (auto g = m.optional("divergence_guard")) {
    if (g->isScalar()) {
      if (g->asEnum({"off", "on"}) == "off") s.guard.enabled = false;
    } else {
      yaml::StrictMap gm(*g);
      DivergenceGuard& q = s.guard;
      if (auto v = gm.optional("position_m")) q.position_m = v->asPositiveDouble();
      if (auto v = gm.optional("angle_rad")) q.angle_rad = v->asPositiveDouble();
      if (auto v = gm.optional("contact_lost_s")) q.contact_lost_s = v->asPositiveDouble();
      if (auto v = gm.optional("contact_lost_fraction")) q.contact_lost_fraction = v->asDoubleIn(0.0, 1.0);
      if (auto v = gm.optional("torque_factor")) q.torque_factor = v->asDoubleIn(1.0, 1.0e6);
      if (auto v = gm.optional("task_error")) q.task_error = v->asPositiveDouble();
      gm.finish();
    }
  }
  const std::optional<yaml::Node> margins_node = m.optional("contact_margins");
  if (margins_node && (margins_node->isScalar() || margins_node->isNull())) {
    if (margins_node->isNull() || margins_node->asString() != "none")
      margins_node->fail("expected `none` (no margin) or a map {friction, cop_m, min_normal_N}");
    s.contact_margins = kNoContactMargins;
  } else if (margins_node) {
    s.contact_margins = readMargins(*margins_node, kNoContactMargins);
  }
  s.contact_margins_default = !margins_node;
  double mass_kg = 0.0;
  for (const auto& l : d.links) mass_kg += l.mass;
  const double weight_N = mass_kg * d.gravity.norm();
  if (auto cn = m.optional("contacts")) {
    for (const yaml::Node& c : cn->elements()) {
      ContactEntry e = readContact(c, d, s.contact_margins, margins_node, s.contact_margins_default, weight_N);
      if (s.findContact(e.name) >= 0) c.fail("duplicate contact name '" + e.name + "'");
      s.contacts.push_back(std::move(e));
    }
  }
  std::vector<std::string> contact_names;
  for (const auto& c : s.contacts) contact_names.push_back(c.name);
  if (auto ic = m.optional("initial_contacts")) {
    for (const yaml::Node& n : ic->elements()) {
      const std::string name = n.asString();
      if (s.findContact(name) < 0) n.fail("unknown contact '" + name + "' (controller.contacts: " + joinNames(contact_names) + ")");
      for (const auto& o : s.initial_contacts) {
        if (o == name) n.fail("contact '" + name + "' listed twice");
      }
      s.initial_contacts.push_back(name);
    }
  }
  const yaml::Node tasks = m.required("tasks");
  for (const yaml::Node& tn : tasks.elements()) {
    TaskSpec t = readTaskSpec(tn, d, contact_names, dt);
    if (s.findTask(t.name) >= 0) tn.fail("duplicate task name '" + t.name + "'");
    s.tasks.push_back(std::move(t));
  }
  auto levels = m.optional("levels");
  auto wls = m.optional("wls_levels");
  if (!levels && !wls) {
    std::vector<std::string> strict, weighted;  // the registry's methods reading each hierarchy
    for (const std::string& n : names) (control::findMethod(n, "").weighted_hierarchy ? weighted : strict).push_back(n);
    m.node().fail("expected a hierarchy: levels (" + joinNames(strict) + ") and/or wls_levels (" + joinNames(weighted) + ")");
  }
  if (levels) {
    s.levels = readLevels(*levels, s, false);
    s.levels_where = levels->where();
  }
  if (wls) {
    s.wls_levels = readLevels(*wls, s, true);
    s.wls_levels_where = wls->where();
  }
  m.finish();  // unknown keys first (e.g. a misspelt `levels`)
  if (!s.hasHierarchy(s.method)) {
    method.fail("method " + s.method + " needs " + s.hierarchyKey(s.method) + ", which the case does not define");
  }
  return s;
}

control::ControllerConfig buildControllerConfig(const LexdynSpec& spec, const model::RobotModel& model) {
  control::ControllerConfig cfg;
  cfg.params = spec.params;
  cfg.params.method = spec.method;
  for (const ContactEntry& c : spec.contacts) {
    tasks::ContactSpec cs;
    plannedContact(c, cs);  // its margins were checked when the case was read
    cs.frame = model.frameId(c.frame);
    cfg.contacts.push_back(cs);
  }
  cfg.initial_contacts = spec.initial_contacts;
  const tasks::ContactLayout layout(model.nv(), cfg.contacts);
  for (const TaskSpec& t : spec.tasks) cfg.tasks.push_back(makeTask(t, model, layout));
  for (const LevelEntry& l : spec.hierarchy(spec.method)) {
    control::LevelSpec ls;
    ls.name = l.name;
    for (const std::string& t : l.tasks) ls.tasks.push_back(spec.findTask(t));
    ls.weights = l.weights;
    cfg.levels.push_back(ls);
  }
  return cfg;
}

void setMethod(LexdynSpec& spec, const std::string& method, const std::string& where) {
  if (!spec.hasHierarchy(method)) {
    throw InputError(where, "method " + method + " needs controller." + spec.hierarchyKey(method) + ", which the case does not define");
  }
  spec.method = method;
  const auto it = spec.params_by_method.find(method);
  if (it != spec.params_by_method.end()) spec.params = it->second;
  spec.params.method = method;
  spec.method_where = where;
}

std::vector<std::string> usedTasks(const LexdynSpec& spec, const std::string& m) {
  std::vector<char> used(spec.tasks.size(), 0);
  for (const LevelEntry& l : spec.hierarchy(m)) {
    for (const std::string& t : l.tasks) used[static_cast<size_t>(spec.findTask(t))] = 1;
  }
  std::vector<std::string> out;
  for (size_t i = 0; i < spec.tasks.size(); ++i) {
    if (used[i]) out.push_back(spec.tasks[i].name);
  }
  return out;
}

}  // namespace lexdyn::cases
