#include "harness/cases/case_file.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/model/robot_description.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace lexdyn::cases {

namespace fs = std::filesystem;

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

const char* toString(sim::SetpointProfile p) {
  switch (p) {
    case sim::SetpointProfile::Step: return "step";
    case sim::SetpointProfile::Linear: return "linear";
    case sim::SetpointProfile::Hermite: return "hermite";
  }
  return "?";
}

namespace {

std::string resolvePath(const yaml::Node& n, const std::string& case_path) {
  const fs::path rel(n.asString());
  const fs::path p = rel.is_absolute() ? rel : fs::path(case_path).parent_path() / rel;
  const fs::path norm = p.lexically_normal();
  std::error_code ec;
  if (!fs::is_regular_file(norm, ec)) n.fail("file not found: " + norm.string());
  return norm.string();
}

std::string joinNames(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

int jointByName(const model::RobotDescription& d, const yaml::Node& n) {
  const std::string name = n.asString();
  const int j = d.findJoint(name);
  if (j < 0) {
    std::vector<std::string> names;
    for (const auto& jd : d.joints) names.push_back(jd.name);
    n.fail("unknown joint '" + name + "' (joints: " + joinNames(names) + ")");
  }
  return j;
}

std::string frameByName(const model::RobotDescription& d, const yaml::Node& n) {
  const std::string name = n.asString();
  if (d.findFrame(name) < 0) {
    std::vector<std::string> names;
    for (const auto& f : d.frames) names.push_back(f.name);
    n.fail("unknown frame '" + name + "' (frames: " + joinNames(names) + ")");
  }
  return name;
}

std::string surfaceByName(const model::RobotDescription& d, const yaml::Node& n) {
  const std::string name = n.asString();
  std::vector<std::string> names;
  for (const auto& s : d.contact_surfaces) {
    if (s.name == name) return name;
    names.push_back(s.name);
  }
  n.fail("unknown contact surface '" + name + "' (surfaces: " + joinNames(names) + ")");
}

std::string postureByName(const model::RobotDescription& d, const yaml::Node& n) {
  const std::string name = n.asString();
  std::vector<std::string> names;
  for (const auto& p : d.postures) {
    if (p.first == name) return name;
    names.push_back(p.first);
  }
  n.fail("unknown posture '" + name + "' (postures: " + joinNames(names) + ")");
}

void readController(CaseSpec& c, const yaml::Node& node, const model::RobotDescription& d) {
  yaml::StrictMap m(node);
  const yaml::Node type = m.required("type");
  c.controller.type = type.asEnum({"posture_servo"});
  c.controller.posture = postureByName(d, m.required("posture"));
  if (auto motions = m.optional("motions")) {
    for (const yaml::Node& mn : motions->elements()) {
      yaml::StrictMap mm(mn);
      MotionSpec ms;
      const yaml::Node joints = mm.required("joints");
      if (joints.size() < 1) joints.fail("expected at least one joint");
      for (const yaml::Node& jn : joints.elements()) ms.joints.push_back(jointByName(d, jn));
      ms.amplitude = mm.required("amplitude").asDouble();
      ms.period_s = mm.required("period_s").asPositiveDouble();
      if (auto ph = mm.optional("phase_rad")) ms.phase_rad = ph->asDouble();
      if (auto st = mm.optional("start_s")) ms.start_s = st->asNonNegativeDouble();
      if (auto w = mm.optional("waveform")) {
        ms.waveform = w->asEnum({"sine", "raised_cosine"}) == "sine" ? Waveform::Sine : Waveform::RaisedCosine;
      }
      mm.finish();
      c.controller.motions.push_back(ms);
    }
  }
  m.finish();
}

void readSim(CaseSpec& c, const yaml::Node& node, const model::RobotDescription& d) {
  yaml::StrictMap m(node);
  sim::SimulatorSettings& s = c.sim;
  s.control_period_s = c.control_period_s;
  {
    yaml::StrictMap cm(m.required("contact"));
    sim::ContactSettings& k = s.contact;
    k.stiffness = cm.required("stiffness").asPositiveDouble();
    const yaml::Node ex = cm.required("exponent");
    k.exponent = ex.asDouble();
    if (!(k.exponent >= 1.0)) ex.fail("expected an exponent >= 1");
    k.dissipation_s_per_m = cm.required("dissipation_s_per_m").asNonNegativeDouble();
    if (auto mu = cm.optional("friction_coefficient")) {
      k.friction_coefficient = mu->asPositiveDouble();
    } else {
      k.friction_coefficient = d.friction_coefficient;
      if (!(k.friction_coefficient > 0.0) && !d.contact_surfaces.empty()) {
        cm.node().fail("friction_coefficient is not in the robot data file; give it here");
      }
    }
    k.slip_velocity_m_per_s = cm.required("slip_velocity_m_per_s").asPositiveDouble();
    if (auto g = cm.optional("ground_height_m")) k.ground_height_m = g->asDouble();
    cm.finish();
  }
  {
    yaml::StrictMap sm(m.required("servo"));
    const yaml::Node prof = sm.required("setpoint_profile");
    const std::string p = prof.asEnum({"step", "linear", "hermite"});
    s.servo.profile = p == "step" ? sim::SetpointProfile::Step
                                  : (p == "linear" ? sim::SetpointProfile::Linear : sim::SetpointProfile::Hermite);
    const int nj = static_cast<int>(d.joints.size());
    Eigen::VectorXd kp = Eigen::VectorXd::Constant(nj, -1.0), kd = Eigen::VectorXd::Constant(nj, -1.0);
    const yaml::Node gains = sm.required("gains");
    for (const yaml::Node& gn : gains.elements()) {
      yaml::StrictMap gm(gn);
      GainGroup g;
      const yaml::Node match = gm.required("match");
      g.match = match.asString();
      g.kp = gm.required("kp").asNonNegativeDouble();
      g.kd = gm.required("kd").asNonNegativeDouble();
      gm.finish();
      int matched = 0;
      for (int j = 0; j < nj; ++j) {
        if (globMatch(g.match, d.joints[static_cast<size_t>(j)].name)) {
          kp[j] = g.kp;
          kd[j] = g.kd;
          ++matched;
        }
      }
      if (matched == 0) match.fail("pattern '" + g.match + "' matches no joint");
      c.gain_groups.push_back(g);
    }
    std::vector<std::string> missing;
    for (int j = 0; j < nj; ++j) {
      if (kp[j] < 0.0) missing.push_back(d.joints[static_cast<size_t>(j)].name);
    }
    if (!missing.empty()) gains.fail("no gain group matches joint(s) " + joinNames(missing));
    s.servo.kp = kp;
    s.servo.kd = kd;
    sm.finish();
  }
  if (auto grasps = m.optional("grasps")) {
    for (const yaml::Node& gn : grasps->elements()) {
      yaml::StrictMap gm(gn);
      sim::GraspSettings g;
      const yaml::Node name = gm.required("name");
      g.name = name.asString();
      if (g.name.find_first_of(" \t\r\n,\"'") != std::string::npos) {
        name.fail("names may not contain whitespace, commas or quotes");
      }
      for (const auto& o : s.grasps) {
        if (o.name == g.name) name.fail("duplicate grasp '" + g.name + "'");
      }
      g.frame = frameByName(d, gm.required("frame"));
      g.stiffness_N_per_m = gm.required("stiffness_N_per_m").asPositiveDouble();
      g.damping_Ns_per_m = gm.required("damping_Ns_per_m").asNonNegativeDouble();
      g.rot_stiffness_Nm_per_rad = gm.required("rot_stiffness_Nm_per_rad").asPositiveDouble();
      g.rot_damping_Nms_per_rad = gm.required("rot_damping_Nms_per_rad").asNonNegativeDouble();
      if (auto a = gm.optional("initially_active")) g.initially_active = a->asBool();
      gm.finish();
      s.grasps.push_back(g);
    }
  }
  if (auto integ = m.optional("integrator")) {
    yaml::StrictMap im(*integ);
    sim::IntegratorSettings& i = s.integrator;
    if (auto v = im.optional("rtol")) i.rtol = v->asPositiveDouble();
    if (auto v = im.optional("atol_position")) i.atol_position = v->asPositiveDouble();
    if (auto v = im.optional("atol_velocity")) i.atol_velocity = v->asPositiveDouble();
    if (auto v = im.optional("max_order")) {
      i.max_order = v->asInt();
      if (i.max_order < 1 || i.max_order > 5) v->fail("expected an integer in 1..5");
    }
    if (auto v = im.optional("max_steps_per_tick")) {
      i.max_steps_per_tick = v->asInt();
      if (i.max_steps_per_tick < 1) v->fail("expected an integer >= 1");
    }
    if (auto v = im.optional("max_step_s")) i.max_step_s = v->asNonNegativeDouble();
    im.finish();
  }
  m.finish();
}

checks::CheckSpec readCheck(const yaml::Node& node, const model::RobotDescription& d) {
  yaml::StrictMap m(node);
  checks::CheckSpec c;
  c.where = node.where();
  c.type = m.required("type").asEnum(checks::checkTypes());
  c.name = c.type;
  if (auto n = m.optional("name")) c.name = n->asString();
  if (auto f = m.optional("from_s")) c.from_s = f->asNonNegativeDouble();
  auto surfaces = [&]() {
    const yaml::Node s = m.required("surfaces");
    if (s.size() < 1) s.fail("expected at least one contact surface");
    for (const yaml::Node& sn : s.elements()) c.surfaces.push_back(surfaceByName(d, sn));
  };
  if (c.type == "frame_drift") {
    c.frame = frameByName(d, m.required("frame"));
    c.limit = m.required("limit_m").asPositiveDouble();
  } else if (c.type == "force_balance") {
    surfaces();
    c.limit = m.required("limit_rel").asPositiveDouble();
  } else if (c.type == "contact_slip") {
    surfaces();
    c.limit = m.required("limit_m").asPositiveDouble();
  } else if (c.type == "frame_height") {
    c.frame = frameByName(d, m.required("frame"));
    c.limit = m.required("min_m").asDouble();
  }
  m.finish();
  return c;
}

}  // namespace

CaseSpec loadCase(const std::string& path) {
  const yaml::Node root = yaml::loadFile(path);
  yaml::StrictMap top(root);
  CaseSpec c;
  c.path = path;
  c.name = top.required("name").asString();
  if (auto desc = top.optional("description")) c.description = desc->asString();
  {
    yaml::StrictMap r(top.required("robot"));
    c.urdf_path = resolvePath(r.required("urdf"), path);
    c.data_path = resolvePath(r.required("data"), path);
    r.finish();
  }
  const model::RobotDescription d = model::loadRobotDescription(c.urdf_path, c.data_path);
  c.duration_s = top.required("duration_s").asPositiveDouble();
  if (auto p = top.optional("control_period_s")) c.control_period_s = p->asPositiveDouble();
  {
    yaml::StrictMap is(top.required("initial_state"));
    c.initial_state.posture = postureByName(d, is.required("posture"));
    if (auto xy = is.optional("base_xy")) {
      const Eigen::VectorXd v = xy->asVector(2);
      c.initial_state.base_x = v[0];
      c.initial_state.base_y = v[1];
    }
    if (auto yaw = is.optional("base_yaw_rad")) c.initial_state.base_yaw_rad = yaw->asDouble();
    const bool floating = d.base == model::BaseType::FreeFlyer;
    if (auto st = is.optional("settle")) {
      const std::string v = st->asEnum({"static_equilibrium", "base_only", "none"});
      c.initial_state.settle = v == "static_equilibrium" ? sim::Settle::StaticEquilibrium
                                                          : (v == "base_only" ? sim::Settle::BaseOnly : sim::Settle::None);
      c.initial_state.settle_given = true;
      c.initial_state.settle_where = st->where();
      if (c.initial_state.settle == sim::Settle::BaseOnly && !floating) st->fail("base_only needs a free-flyer base");
      if (c.initial_state.settle != sim::Settle::None && floating && d.contact_surfaces.empty()) {
        st->fail("a floating robot without contact surfaces has no static equilibrium; use none");
      }
    } else {
      c.initial_state.settle =
          floating && !d.contact_surfaces.empty() ? sim::Settle::StaticEquilibrium : sim::Settle::None;
      c.initial_state.settle_where = is.node().where() + " (settle: " + sim::toString(c.initial_state.settle) + ", the default)";
    }
    is.finish();
  }
  readController(c, top.required("controller"), d);
  readSim(c, top.required("sim"), d);
  if (auto events = top.optional("events")) {
    for (const yaml::Node& en : events->elements()) {
      yaml::StrictMap em(en);
      EventSpec e;
      e.where = en.where();
      const yaml::Node at = em.required("at_s");
      e.at_s = at.asNonNegativeDouble();
      if (e.at_s > c.duration_s) at.fail("event after the end of the run (duration_s " + std::to_string(c.duration_s) + ")");
      e.action = em.required("action").asEnum({"grasp_on", "grasp_off"});
      const yaml::Node g = em.required("grasp");
      e.grasp = g.asString();
      bool known = false;
      for (const auto& gs : c.sim.grasps) known = known || gs.name == e.grasp;
      if (!known) g.fail("unknown grasp '" + e.grasp + "' (define it under sim.grasps)");
      em.finish();
      c.events.push_back(e);
    }
    std::stable_sort(c.events.begin(), c.events.end(), [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });
  }
  if (auto tr = top.optional("trace")) {
    yaml::StrictMap tm(*tr);
    if (auto v = tm.optional("every_n_ticks")) {
      c.trace.every_n_ticks = v->asInt();
      if (c.trace.every_n_ticks < 1) v->fail("expected an integer >= 1");
    }
    if (auto v = tm.optional("flush_every_rows")) {
      c.trace.flush_every_rows = v->asInt();
      if (c.trace.flush_every_rows < 1) v->fail("expected an integer >= 1");
    }
    if (auto v = tm.optional("frames")) {
      for (const yaml::Node& fn : v->elements()) c.trace.frames.push_back(frameByName(d, fn));
    }
    tm.finish();
  }
  const yaml::Node checks = top.required("checks");
  for (const yaml::Node& cn : checks.elements()) {
    checks::CheckSpec cs = readCheck(cn, d);
    for (const auto& o : c.checks) {
      if (o.name == cs.name) cn.fail("duplicate check name '" + cs.name + "'");
    }
    c.checks.push_back(cs);
  }
  top.finish();
  return c;
}

}  // namespace lexdyn::cases
