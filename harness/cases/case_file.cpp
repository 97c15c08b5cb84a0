#include "harness/cases/case_file.hpp"

#include "harness/cases/case_document.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/model/robot_description.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/tasks/orientation.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <memory>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

namespace lexdyn::cases {

namespace fs = std::filesystem;

namespace {
constexpr EventAction kEventActions[] = {EventAction::GraspOn,    EventAction::GraspOff,      EventAction::SetTarget,
                                         EventAction::AddContact, EventAction::RemoveContact, EventAction::TargetTrajectory,
                                         EventAction::Swing};
}  // namespace

const char* toString(EventAction a) {
  switch (a) {
    case EventAction::GraspOn:
      return "grasp_on";
    case EventAction::GraspOff:
      return "grasp_off";
    case EventAction::SetTarget:
      return "set_target";
    case EventAction::AddContact:
      return "add_contact";
    case EventAction::RemoveContact:
      return "remove_contact";
    case EventAction::TargetTrajectory:
      return "target_trajectory";
    case EventAction::Swing:
      return "swing";
  }
  return "unknown";
}

const char* toString(sim::SetpointProfile p) {
  switch (p) {
    case sim::SetpointProfile::Step:
      return "step";
    case sim::SetpointProfile::Linear:
      return "linear";
    case sim::SetpointProfile::Hermite:
      return "hermite";
  }
  return "?";
}

namespace {

namespace R = lexdyn::ranges;

/// The limits of joint j as a range a value must fall in ("[lo, hi] (rad or m)"), finite.
void requireWithinJointLimits(const yaml::Node& n, double v, const model::JointDescription& jd) {
  const double lo = std::max(jd.lower, -R::kMaxJointLimit), hi = std::min(jd.upper, R::kMaxJointLimit);
  if (!(v >= lo && v <= hi)) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "joint %s: expected a value within its limits [%g, %g] %s, found %g", jd.name.c_str(), lo, hi,
                  jd.type == model::JointType::Prismatic ? "m" : "rad", v);
    n.fail(buf);
  }
}

// A file named by the case, relative to the case file's directory; recorded in file_fields so
// that the effective case can name it from elsewhere.
std::string resolvePath(const yaml::Node& n, CaseSpec& c) {
  const fs::path rel(n.asString());
  const fs::path p = rel.is_absolute() ? rel : fs::path(c.path).parent_path() / rel;
  const fs::path norm = p.lexically_normal();
  std::error_code ec;
  if (!fs::is_regular_file(norm, ec)) n.fail("file not found: " + norm.string());
  c.file_fields.emplace_back(n.path(), norm.string());
  return norm.string();
}

// A folder named by the case (robot.package_path), like resolvePath.
std::string resolveDir(const yaml::Node& n, CaseSpec& c) {
  const fs::path rel(n.asString());
  const fs::path p = (rel.is_absolute() ? rel : fs::path(c.path).parent_path() / rel).lexically_normal();
  std::error_code ec;
  if (!fs::is_directory(p, ec)) n.fail("folder not found: " + p.string());
  c.file_fields.emplace_back(n.path(), p.string());
  return p.string();
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
  c.controller.type = *records::parseControllerType(type.asEnum(records::controllerTypeNames()));
  if (c.controller.type == records::ControllerType::Lexdyn) {
    c.controller.lexdyn = readLexdynSpec(m, d, c.control_period_s);
    m.finish();
    return;
  }
  c.controller.posture = postureByName(d, m.required("posture"));
  if (auto motions = m.optional("motions")) {
    // The commanded joints stay within their limits: posture + the motions' offsets.
    Eigen::VectorXd lo = Eigen::VectorXd::Zero(static_cast<int>(d.joints.size())), hi = lo;
    for (const yaml::Node& mn : motions->elements()) {
      yaml::StrictMap mm(mn);
      MotionSpec ms;
      const yaml::Node joints = mm.required("joints");
      if (joints.size() < 1) joints.fail("expected at least one joint");
      for (const yaml::Node& jn : joints.elements()) ms.joints.push_back(d.findJoint(jointName(jn, d)));
      ms.amplitude = mm.required("amplitude").asDoubleIn(-2.0 * R::kMaxJointLimit, 2.0 * R::kMaxJointLimit);
      // At least two control periods: a faster motion aliases at the control rate.
      ms.period_s = mm.required("period_s").asDoubleIn(2.0 * c.control_period_s, R::kMaxTime_s, "s");
      if (auto ph = mm.optional("phase_rad")) ms.phase_rad = ph->asDoubleIn(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad");
      if (auto st = mm.optional("start_s")) ms.start_s = st->asDoubleIn(0.0, R::kMaxTime_s, "s");
      if (auto w = mm.optional("waveform")) {
        ms.waveform = w->asEnum({"sine", "raised_cosine"}) == "sine" ? Waveform::Sine : Waveform::RaisedCosine;
      }
      mm.finish();
      const double a_lo = ms.waveform == Waveform::Sine ? -std::abs(ms.amplitude) : std::min(0.0, ms.amplitude);
      const double a_hi = ms.waveform == Waveform::Sine ? std::abs(ms.amplitude) : std::max(0.0, ms.amplitude);
      for (int j : ms.joints) {
        lo[j] += a_lo;
        hi[j] += a_hi;
      }
      c.controller.motions.push_back(ms);
    }
    Eigen::VectorXd posture;
    for (const auto& p : d.postures) {
      if (p.first == c.controller.posture) posture = p.second;
    }
    for (int j = 0; j < lo.size(); ++j) {
      const model::JointDescription& jd = d.joints[static_cast<size_t>(j)];
      if (posture[j] + lo[j] < jd.lower || posture[j] + hi[j] > jd.upper) {
        motions->fail("joint " + jd.name + " would be commanded over [" + std::to_string(posture[j] + lo[j]) + ", " +
                      std::to_string(posture[j] + hi[j]) + "], outside its limits [" + std::to_string(jd.lower) + ", " +
                      std::to_string(jd.upper) + "]");
      }
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
    k.stiffness = cm.required("stiffness").asDoubleIn(R::kMinContactStiffness, R::kMaxContactStiffness, "N/m^exponent");
    const yaml::Node ex = cm.required("exponent");
    k.exponent = ex.asDouble();
    if (!(k.exponent >= 1.0 && k.exponent <= R::kMaxContactExponent)) {
      ex.fail("expected an exponent in [1, 3], found " + ex.raw().Scalar());
    }
    k.dissipation_s_per_m = cm.required("dissipation_s_per_m").asDoubleIn(0.0, R::kMaxContactDissipation_s_per_m, "s/m");
    if (auto mu = cm.optional("friction_coefficient")) {
      k.friction_coefficient = mu->asPositiveDouble();
      if (k.friction_coefficient > R::kMaxFriction) mu->fail("expected a friction coefficient in (0, 10], found " + mu->raw().Scalar());
    } else {
      k.friction_coefficient = d.friction_coefficient;
      if (!(k.friction_coefficient > 0.0) && !d.contact_surfaces.empty()) {
        cm.node().fail("friction_coefficient is not in the robot data file; give it here");
      }
    }
    k.slip_velocity_m_per_s = cm.required("slip_velocity_m_per_s").asDoubleIn(R::kMinSlipVelocity_mps, R::kMaxSlipVelocity_mps, "m/s");
    if (auto g = cm.optional("ground_height_m")) k.ground_height_m = g->asDoubleIn(-R::kMaxPosition_m, R::kMaxPosition_m, "m");
    cm.finish();
  }
  {
    yaml::StrictMap sm(m.required("servo"));
    const yaml::Node prof = sm.required("setpoint_profile");
    const std::string p = prof.asEnum({"step", "linear", "hermite"});
    s.servo.profile =
        p == "step" ? sim::SetpointProfile::Step : (p == "linear" ? sim::SetpointProfile::Linear : sim::SetpointProfile::Hermite);
    const int nj = static_cast<int>(d.joints.size());
    Eigen::VectorXd kp = Eigen::VectorXd::Constant(nj, -1.0), kd = Eigen::VectorXd::Constant(nj, -1.0);
    // Scales of every group's gains (a servo perturbation: the real servos are stiffer or softer).
    double kp_scale = 1.0, kd_scale = 1.0;
    if (auto v = sm.optional("kp_scale")) kp_scale = v->asPositiveDouble();
    if (auto v = sm.optional("kd_scale")) kd_scale = v->asPositiveDouble();
    auto apply = [&](const GainGroup& g) {
      int matched = 0;
      for (int j = 0; j < nj; ++j) {
        if (globMatch(g.match, d.joints[static_cast<size_t>(j)].name)) {
          kp[j] = g.kp;
          kd[j] = g.kd;
          ++matched;
        }
      }
      c.gain_groups.push_back(g);
      return matched;
    };
    // The case's gain groups, or the robot data file's servo_gains (docs/model.md).
    const std::optional<yaml::Node> gains = sm.optional("gains");
    if (gains) {
      for (const yaml::Node& gn : gains->elements()) {
        yaml::StrictMap gm(gn);
        GainGroup g;
        const yaml::Node match = gm.required("match");
        g.match = match.asString();
        g.kp = gm.required("kp").asDoubleIn(0.0, R::kMaxServoKp, "N m/rad (N/m)");
        g.kd = gm.required("kd").asDoubleIn(0.0, R::kMaxServoKd, "N m s/rad (N s/m)");
        gm.finish();
        if (apply(g) == 0) match.fail("pattern '" + g.match + "' matches no joint");
      }
    } else {
      if (d.servo_gains.empty()) {
        sm.node().fail("no servo gains: give sim.servo.gains here, or servo_gains in the robot data file (" + d.data_path + ")");
      }
      for (const model::ServoGainGroup& sg : d.servo_gains) apply({sg.match, sg.kp, sg.kd});
    }
    std::vector<std::string> missing;
    for (int j = 0; j < nj; ++j) {
      if (kp[j] < 0.0) missing.push_back(d.joints[static_cast<size_t>(j)].name);
    }
    if (!missing.empty()) (gains ? *gains : sm.node()).fail("no gain group matches joint(s) " + joinNames(missing));
    s.servo.kp = kp_scale * kp;
    s.servo.kd = kd_scale * kd;
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
      g.frame = frameName(gm.required("frame"), d);
      g.stiffness_N_per_m = gm.required("stiffness_N_per_m").asPositiveDouble();
      if (g.stiffness_N_per_m > R::kMaxGraspStiffness_N_per_m)
        gm.required("stiffness_N_per_m").asDoubleIn(0.0, R::kMaxGraspStiffness_N_per_m, "N/m");
      g.damping_Ns_per_m = gm.required("damping_Ns_per_m").asDoubleIn(0.0, R::kMaxGraspDamping_Ns_per_m, "N s/m");
      g.rot_stiffness_Nm_per_rad = gm.required("rot_stiffness_Nm_per_rad").asPositiveDouble();
      if (g.rot_stiffness_Nm_per_rad > R::kMaxGraspRotStiffness_Nm_per_rad) {
        gm.required("rot_stiffness_Nm_per_rad").asDoubleIn(0.0, R::kMaxGraspRotStiffness_Nm_per_rad, "N m/rad");
      }
      g.rot_damping_Nms_per_rad = gm.required("rot_damping_Nms_per_rad").asDoubleIn(0.0, R::kMaxGraspRotDamping_Nms_per_rad, "N m s/rad");
      if (auto a = gm.optional("initially_active")) g.initially_active = a->asBool();
      gm.finish();
      s.grasps.push_back(g);
    }
  }
  if (auto model = m.optional("model")) {
    yaml::StrictMap mm(*model);
    auto linkPattern = [&](const yaml::Node& n) {
      const std::string pattern = n.asString();
      for (const auto& l : d.links) {
        if (globMatch(pattern, l.name)) return pattern;
        for (const auto& merged : l.merged_links) {
          if (globMatch(pattern, merged)) n.fail("'" + merged + "' is lumped into link " + l.name + " (a fixed joint); name " + l.name);
        }
      }
      n.fail("pattern '" + pattern + "' matches no link of the model");
    };
    // The entries {match: LINK_PATTERN, ...} of the list `key`: read(entry, pattern) reads the rest.
    auto linkEntries = [&](const char* key, auto read) {
      if (auto list = mm.optional(key)) {
        for (const yaml::Node& e : list->elements()) {
          yaml::StrictMap em(e);
          const std::string match = linkPattern(em.required("match"));
          read(em, match);
          em.finish();
        }
      }
    };
    linkEntries("mass_scale", [&](yaml::StrictMap& em, const std::string& match) {
      const yaml::Node sc = em.required("scale");
      const double scale = sc.asPositiveDouble();
      if (scale < 0.1 || scale > 10.0) sc.fail("expected a scale in [0.1, 10], found " + sc.raw().Scalar());
      c.sim_model.mass_scale.push_back(LinkMassScale{match, scale});
    });
    linkEntries("com_offset_m", [&](yaml::StrictMap& em, const std::string& match) {
      const yaml::Node off = em.required("offset");
      const Eigen::Vector3d offset = off.asVector3();
      if (offset.cwiseAbs().maxCoeff() > 0.5) off.fail("expected offsets within +-0.5 m");
      c.sim_model.com_offset.push_back(LinkComOffset{match, offset});
    });
    mm.finish();
  }
  if (auto integ = m.optional("integrator")) {
    yaml::StrictMap im(*integ);
    sim::IntegratorSettings& i = s.integrator;
    if (auto v = im.optional("rtol")) i.rtol = v->asDoubleIn(R::kMinIntegratorRtol, R::kMaxIntegratorRtol);
    if (auto v = im.optional("atol_position")) i.atol_position = v->asDoubleIn(R::kMinIntegratorAtol, R::kMaxIntegratorAtol, "m or rad");
    if (auto v = im.optional("atol_velocity"))
      i.atol_velocity = v->asDoubleIn(R::kMinIntegratorAtol, R::kMaxIntegratorAtol, "m/s or rad/s");
    if (auto v = im.optional("max_order")) {
      i.max_order = v->asInt();
      if (i.max_order < 1 || i.max_order > 5) v->fail("expected an integer in 1..5");
    }
    if (auto v = im.optional("max_steps_per_tick")) {
      i.max_steps_per_tick = v->asIntIn(1, R::kMaxIntegratorStepsPerTick);
    }
    if (auto v = im.optional("max_step_s"))
      i.max_step_s = v->asDoubleIn(0.0, c.control_period_s, "s (0: no limit; at most the control period)");
    if (auto v = im.optional("linear_solver")) {
      i.linear_solver =
          v->asEnum({"block_elimination", "dense_lu"}) == "dense_lu" ? sim::LinearSolver::DenseLU : sim::LinearSolver::BlockElimination;
    }
    if (auto v = im.optional("jacobian")) {
      i.jacobian = v->asEnum({"difference_quotient", "applied_forces"}) == "applied_forces" ? sim::IntegratorJacobian::AppliedForces
                                                                                            : sim::IntegratorJacobian::DifferenceQuotient;
    }
    im.finish();
  }
  m.finish();
}

/// What the check parsers may ask about the robot (harness/checks/check_registry.hpp).
checks::CheckContext robotContext(const model::RobotDescription& d) {
  checks::CheckContext x;
  for (const auto& f : d.frames) x.frames.push_back(f.name);
  for (const auto& s : d.contact_surfaces) x.surfaces.push_back(s.name);
  for (const auto& j : d.joints) x.joints.push_back({j.name, j.effort_limit});
  return x;
}

/// ... and about the case: its controller, with a lexdyn controller its contacts, tasks and
/// the hierarchy of each method. `d` may be null (comparisons need no robot).
checks::CheckContext checkContext(const CaseSpec& c, const model::RobotDescription* d) {
  checks::CheckContext x = d ? robotContext(*d) : checks::CheckContext{};
  x.controller = c.controller.type;
  x.control_period_s = c.control_period_s;
  if (!isLexdyn(c)) return x;
  const LexdynSpec& lx = c.controller.lexdyn;
  for (const ContactEntry& e : lx.contacts) x.contacts.push_back({e.name, e.normal, e.friction, !e.sensor.empty(), e.points});
  for (const TaskSpec& t : lx.tasks) {
    checks::CheckContext::Task task{t.name, t.type, false, 0.0, std::nullopt};
    if (const tasks::PdGains* g = taskGains(t)) {
      task.has_gains = true;
      task.kp = g->kp;
      task.kv = g->kv;
    }
    x.tasks.push_back(task);
  }
  for (const std::string& name : control::methodNames()) {
    checks::CheckContext::Method method{name, lx.hasHierarchy(name), usedTasks(lx, name), {}};
    for (const LevelEntry& l : lx.hierarchy(name)) method.levels.push_back(l.name);
    x.methods.push_back(method);
  }
  return x;
}

EventSpec readEvent(const yaml::Node& en, CaseSpec& c) {
  yaml::StrictMap em(en);
  EventSpec e;
  e.where = en.where();
  const yaml::Node at = em.required("at_s");
  e.at_s = at.asNonNegativeDouble();
  if (e.at_s > c.duration_s) at.fail("event after the end of the run (duration_s " + std::to_string(c.duration_s) + ")");
  const yaml::Node action = em.required("action");
  {
    std::vector<std::string> names;
    for (EventAction a : kEventActions) names.push_back(toString(a));
    const std::string name = action.asEnum(names);
    for (EventAction a : kEventActions) {
      if (name == toString(a)) e.action = a;
    }
  }
  const LexdynSpec& lx = c.controller.lexdyn;
  if (e.action == EventAction::GraspOn || e.action == EventAction::GraspOff) {
    const yaml::Node g = em.required("grasp");
    e.grasp = g.asString();
    bool known = false;
    for (const auto& gs : c.sim.grasps) known = known || gs.name == e.grasp;
    if (!known) g.fail("unknown grasp '" + e.grasp + "' (define it under sim.grasps)");
    if (isLexdyn(c)) {
      for (const auto& ce : lx.contacts) {
        if (ce.grasp == e.grasp)
          g.fail("grasp '" + e.grasp + "' is linked to controller contact '" + ce.name + "': use add_contact / remove_contact");
      }
    }
    em.finish();
    return e;
  }
  if (!isLexdyn(c)) action.fail(std::string("action ") + toString(e.action) + " needs controller type lexdyn");
  auto taskRef = [&]() {
    const yaml::Node tn = em.required("task");
    e.task = tn.asString();
    if (lx.findTask(e.task) < 0) tn.fail("unknown task '" + e.task + "'");
  };
  if (e.action == EventAction::AddContact || e.action == EventAction::RemoveContact) {
    const yaml::Node cn = em.required("contact");
    e.contact = cn.asString();
    if (lx.findContact(e.contact) < 0) cn.fail("unknown controller contact '" + e.contact + "'");
  } else if (e.action == EventAction::SetTarget) {
    taskRef();
    auto value = em.optional("value");
    auto rpy = em.optional("rpy_rad");
    auto lower = em.optional("lower");
    auto upper = em.optional("upper");
    const int given = (value ? 1 : 0) + (rpy ? 1 : 0) + ((lower || upper) ? 1 : 0);
    if (given != 1) en.fail("set_target needs exactly one of value, rpy_rad (orientation) or lower + upper (com_box)");
    if (value) {
      if (value->isSequence() && value->size() == 3 && (*value)[0].isSequence()) {
        e.value.resize(9);  // a rotation matrix given as 3 rows
        for (int r = 0; r < 3; ++r) e.value.segment<3>(3 * r) = (*value)[r].asVector3();
      } else {
        e.value = value->asVectorAnySize(1);
      }
    } else if (rpy) {
      e.value = tasks::rotationToTarget(rotationFromRpy(rpy->asVector3In(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad")));
    } else {
      if (!lower || !upper) en.fail("a box target needs both lower and upper");
      e.value.resize(6);
      e.value.head<3>() = asBound3(*lower);
      e.value.tail<3>() = asBound3(*upper);
    }
    if (auto r = em.optional("ramp_s")) {
      e.ramp_s = r->asDoubleIn(0.0, R::kMaxTime_s, "s");
      // Entry-wise linear interpolation: meaningful for positions, joint values and box bounds,
      // not for an orientation target (a rotation matrix).
      if (e.ramp_s > 0.0 && (rpy || e.value.size() == 9)) r->fail("ramp_s is not available for orientation targets");
    }
  } else if (e.action == EventAction::TargetTrajectory) {
    taskRef();
    const yaml::Node f = em.required("file");
    e.file = resolvePath(f, c);
    double window = 0.0;
    if (auto v = em.optional("moving_average_s")) window = v->asDoubleIn(0.0, R::kMaxTime_s, "s");
    bool loop = false;
    if (auto v = em.optional("loop")) loop = v->asBool();
    try {
      e.trajectory = TargetTrajectory::fromCsv(e.file, window, loop);
    } catch (const InputError& err) {
      f.fail(err.what());
    }
  } else if (e.action == EventAction::Swing) {
    taskRef();
    e.swing.from = em.required("from").asVector3In(-R::kMaxPosition_m, R::kMaxPosition_m, "m");
    e.swing.to = em.required("to").asVector3In(-R::kMaxPosition_m, R::kMaxPosition_m, "m");
    e.swing.period_s = em.required("period_s").asDoubleIn(2.0 * c.control_period_s, R::kMaxTime_s, "s (at least two control periods)");
    if (auto v = em.optional("phase_rad")) e.swing.phase_rad = v->asDoubleIn(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad");
  }
  em.finish();
  return e;
}

// Builds the controller of every method the case has a hierarchy for (so that --method works),
// and checks the events' targets against the built tasks and the contacts' grasp links.
void validateLexdyn(CaseSpec& c, const yaml::Node& controller_node) {
  LexdynSpec& lx = c.controller.lexdyn;
  const model::RobotModel model = model::RobotModel::fromFiles(c.urdf_path, c.data_path, c.robot_options);
  for (const ContactEntry& ce : lx.contacts) {
    if (ce.grasp.empty()) continue;
    const sim::GraspSettings* g = nullptr;
    for (const auto& gs : c.sim.grasps) {
      if (gs.name == ce.grasp) g = &gs;
    }
    if (!g) throw InputError(ce.where + ".grasp", "unknown grasp '" + ce.grasp + "' (define it under sim.grasps)");
    if (g->frame != ce.frame) {
      throw InputError(ce.where + ".grasp", "grasp '" + ce.grasp + "' is on frame " + g->frame + ", the contact on frame " + ce.frame);
    }
    const bool initially = std::find(lx.initial_contacts.begin(), lx.initial_contacts.end(), ce.name) != lx.initial_contacts.end();
    if (g->initially_active != initially) {
      throw InputError(ce.where + ".grasp", "grasp '" + ce.grasp + "' is " + (g->initially_active ? "" : "not ") +
                                                "initially active but contact '" + ce.name + "' is " + (initially ? "" : "not ") +
                                                "in initial_contacts; they switch together");
    }
    for (const auto& o : lx.contacts) {
      if (&o != &ce && o.grasp == ce.grasp) throw InputError(ce.where + ".grasp", "grasp '" + ce.grasp + "' is linked to two contacts");
    }
  }
  std::unique_ptr<control::Controller> first;
  const std::string chosen = lx.method;
  for (const std::string& name : control::methodNames()) {
    const std::string& m = name;
    if (!lx.hasHierarchy(m)) continue;
    const std::string where = lx.hierarchyWhere(m);
    const std::string chosen_where = lx.method_where;
    try {
      setMethod(lx, m, where);
      auto ctl = std::make_unique<control::Controller>(model, buildControllerConfig(lx, model));
      if (!first) first = std::move(ctl);
    } catch (const InputError& e) {
      setMethod(lx, chosen, chosen_where);
      throw InputError(where, std::string("(method ") + name + ") " + e.what());
    }
    setMethod(lx, chosen, chosen_where);
  }
  setMethod(lx, chosen, lx.method_where);
  (void)controller_node;
  for (const EventSpec& e : c.events) {
    if (e.task.empty()) continue;
    const int ti = first->taskIndex(e.task);
    const tasks::TaskModel& t = first->task(ti);
    const int n = t.targetSize();
    if (n == 0)
      throw InputError(e.where, "task '" + e.task + "' (" + lx.tasks[static_cast<size_t>(lx.findTask(e.task))].type + ") has no target");
    if (e.action == EventAction::SetTarget) {
      if (e.value.size() != n) {
        throw InputError(
            e.where, "task '" + e.task + "' takes a target of " + std::to_string(n) + " values, found " + std::to_string(e.value.size()));
      }
      try {
        t.checkTarget(e.value);
      } catch (const InputError& err) {
        throw InputError(e.where, err.what());
      }
      // The documented ranges (docs/simulator.md, "Ranges"): positions within 1e3 m, joint
      // targets within the joints' limits.
      const model::RobotDescription& d = model.description();
      const TaskTargetLayout target = taskTarget(lx.tasks[static_cast<size_t>(lx.findTask(e.task))], d);
      for (int k = 0; k < e.value.size(); ++k) {
        const double v = e.value[k];
        if (target.positions && std::isfinite(v) && std::abs(v) > R::kMaxPosition_m) {
          throw InputError(e.where + ".value[" + std::to_string(k) + "]",
                           "expected a position in [-1000, 1000] m, found " + std::to_string(v));
        }
        const int j = static_cast<size_t>(k) < target.joints.size() ? d.findJoint(target.joints[static_cast<size_t>(k)]) : -1;
        if (j >= 0) {
          const model::JointDescription& jd = d.joints[static_cast<size_t>(j)];
          if (!(v >= std::max(jd.lower, -R::kMaxJointLimit) && v <= std::min(jd.upper, R::kMaxJointLimit))) {
            throw InputError(e.where + ".value[" + std::to_string(k) + "]", "joint " + jd.name + ": expected a target within its limits [" +
                                                                                std::to_string(jd.lower) + ", " + std::to_string(jd.upper) +
                                                                                "], found " + std::to_string(v));
          }
        }
      }
    } else if (n != 3) {
      throw InputError(e.where, std::string(toString(e.action)) + " drives 3-D targets (position, com); task '" + e.task + "' takes " +
                                    std::to_string(n) + " values");
    }
  }
}

}  // namespace

std::string methodName(const CaseSpec& spec) { return isLexdyn(spec) ? spec.controller.lexdyn.method : ""; }

void overrideMethod(CaseSpec& spec, const std::string& method, const std::string& where) {
  if (!isLexdyn(spec)) throw InputError(where, "--method needs a case with controller type lexdyn");
  setMethod(spec.controller.lexdyn, control::findMethod(method, where).name, where);
  // The effective case holds it too.
  if (!spec.document.empty()) {
    YAML::Node root = YAML::Load(spec.document);
    root["controller"]["method"] = method;
    spec.document = doc::emit(root);
  }
  spec.overrides.push_back({"controller.method", method, "--method " + method});
}

namespace {

// expected_failures: [{method?, status?, checks?, reason}] (docs/cases.md, "Expected failures").
void readExpectedFailures(CaseSpec& c, const yaml::Node& list, const checks::CheckContext& context) {
  for (const yaml::Node& en : list.elements()) {
    yaml::StrictMap m(en);
    ExpectedFailure x;
    x.where = en.where();
    if (isLexdyn(c)) {
      x.method = context.method(m.required("method"));
    } else if (auto mn = m.optional("method")) {
      mn->fail(std::string("a case without methods (controller type ") + records::toString(c.controller.type) + ") names no method");
    }
    if (auto st = m.optional("status")) {
      using records::RunStatus;
      const RunStatus allowed[] = {RunStatus::Completed, RunStatus::ControllerFailure, RunStatus::IntegratorFailure, RunStatus::Diverged};
      std::vector<std::string> names;
      for (RunStatus a : allowed) names.push_back(records::toString(a));
      x.status = *records::parseRunStatus(st->asEnum(names));
    }
    if (auto cn = m.optional("checks")) {
      for (const yaml::Node& n : cn->elements()) {
        const std::string name = n.asString();
        const auto spec = std::find_if(c.checks.begin(), c.checks.end(), [&](const checks::CheckSpec& s) { return s.name == name; });
        if (spec == c.checks.end()) n.fail("unknown check '" + name + "' (the case's checks)");
        if (checks::machineDependent(*spec)) n.fail("check '" + name + "' measures wall-clock time: its outcome depends on the machine");
        if (!spec->methods.empty() && !x.method.empty() &&
            std::find(spec->methods.begin(), spec->methods.end(), x.method) == spec->methods.end()) {
          n.fail("check '" + name + "' does not apply to method " + x.method);
        }
        if (std::find(x.checks.begin(), x.checks.end(), name) != x.checks.end()) n.fail("check '" + name + "' listed twice");
        x.checks.push_back(name);
      }
      std::sort(x.checks.begin(), x.checks.end());
    }
    const yaml::Node reason = m.required("reason");
    x.reason = reason.asString();
    m.finish();
    if (x.status == records::RunStatus::Completed && x.checks.empty())
      en.fail("expected a failure: a status other than completed, or checks");
    for (const ExpectedFailure& o : c.expected_failures) {
      if (o.method == x.method) en.fail(x.method.empty() ? "a second entry (one at most)" : "a second entry for method " + x.method);
    }
    c.expected_failures.push_back(std::move(x));
  }
}

CaseSpec parseCase(const yaml::Node& root, const std::string& path) {
  yaml::StrictMap top(root);
  CaseSpec c;
  c.path = path;
  const yaml::Node name = top.required("name");
  c.name = name.asString();
  // The name names golden files and directories: no path separators or odd characters.
  if (c.name.size() > 128 ||
      c.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.") != std::string::npos ||
      c.name[0] == '.') {
    name.fail("expected a name of at most 128 letters, digits, '_', '-' and '.' (not starting with '.'), found '" + c.name.substr(0, 64) +
              (c.name.size() > 64 ? "...'" : "'"));
  }
  if (auto desc = top.optional("description")) c.description = desc->asString();
  {
    yaml::StrictMap r(top.required("robot"));
    c.urdf_path = resolvePath(r.required("urdf"), c);
    c.data_path = resolvePath(r.required("data"), c);
    if (auto strict = r.optional("strict")) c.robot_options.strict = strict->asBool();
    if (auto pp = r.optional("package_path")) {
      for (const yaml::Node& e : pp->elements()) c.robot_options.package_paths.push_back(resolveDir(e, c));
    }
    r.finish();
  }
  const model::RobotDescription d = model::loadRobotDescription(c.urdf_path, c.data_path, c.robot_options);
  c.robot_warnings = d.warnings;
  const yaml::Node duration = top.required("duration_s");
  c.duration_s = duration.asPositiveDouble();
  if (auto p = top.optional("control_period_s")) {
    c.control_period_s = p->asDoubleIn(R::kMinControlPeriod_s, R::kMaxControlPeriod_s, "s");
  }
  // At least one control tick (a shorter run computes nothing and would pass every check) and at
  // most kMaxTicks (the per-tick statistics and the trace grow with it).
  if (c.duration_s < c.control_period_s) {
    duration.fail("expected at least one control period (" + std::to_string(c.control_period_s) + " s), found " + duration.raw().Scalar());
  }
  if (c.duration_s / c.control_period_s > static_cast<double>(R::kMaxTicks)) {
    duration.fail("expected at most " + std::to_string(R::kMaxTicks) + " control ticks (" +
                  std::to_string(static_cast<double>(R::kMaxTicks) * c.control_period_s) + " s at this control period), found " +
                  duration.raw().Scalar() + " s (size guard)");
  }
  {
    yaml::StrictMap is(top.required("initial_state"));
    c.initial_state.posture = postureByName(d, is.required("posture"));
    if (auto jn = is.optional("joints")) {
      for (const auto& [key, value] : jn->entries()) {
        const int j = d.findJoint(key);
        if (j < 0) value.fail("unknown joint '" + key + "'");
        const double v = value.asDouble();
        requireWithinJointLimits(value, v, d.joints[static_cast<size_t>(j)]);
        c.initial_state.joints.emplace_back(j, v);
      }
    }
    if (auto xy = is.optional("base_xy")) {
      const Eigen::VectorXd v = xy->asVectorIn(2, -R::kMaxPosition_m, R::kMaxPosition_m, "m");
      c.initial_state.base_x = v[0];
      c.initial_state.base_y = v[1];
    }
    if (auto yaw = is.optional("base_yaw_rad")) c.initial_state.base_yaw_rad = yaw->asDoubleIn(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad");
    if (auto pn = is.optional("perturbation")) {
      yaml::StrictMap pm(*pn);
      PosturePerturbation& p = c.initial_state.perturbation;
      const yaml::Node seed = pm.required("seed");
      const int sv = seed.asInt();
      if (sv < 0) seed.fail("expected an integer >= 0");
      p.seed = static_cast<std::uint64_t>(sv);
      const yaml::Node amp = pm.required("amplitude_rad");
      p.amplitude_rad = amp.asNonNegativeDouble();
      if (p.amplitude_rad > 0.5) amp.fail("expected an amplitude <= 0.5 rad (a small perturbation), found " + amp.raw().Scalar());
      std::vector<std::string> names = robotContext(d).jointNames();
      if (auto j = pm.optional("joints")) names = robotContext(d).jointPatterns(*j);
      for (const auto& n : names) p.joints.push_back(d.findJoint(n));
      pm.finish();
    }
    const bool floating = d.base == model::BaseType::FreeFlyer;
    if (auto st = is.optional("settle")) {
      const std::string v = st->asEnum({"static_equilibrium", "base_only", "none"});
      c.initial_state.settle =
          v == "static_equilibrium" ? sim::Settle::StaticEquilibrium : (v == "base_only" ? sim::Settle::BaseOnly : sim::Settle::None);
      c.initial_state.settle_given = true;
      c.initial_state.settle_where = st->where();
      if (c.initial_state.settle == sim::Settle::BaseOnly && !floating) st->fail("base_only needs a free-flyer base");
      if (c.initial_state.settle != sim::Settle::None && floating && d.contact_surfaces.empty()) {
        st->fail("a floating robot without contact surfaces has no static equilibrium; use none");
      }
    } else {
      c.initial_state.settle = floating && !d.contact_surfaces.empty() ? sim::Settle::StaticEquilibrium : sim::Settle::None;
      c.initial_state.settle_where = is.node().where() + " (settle: " + sim::toString(c.initial_state.settle) + ", the default)";
    }
    is.finish();
  }
  const yaml::Node controller_node = top.required("controller");
  readController(c, controller_node, d);
  readSim(c, top.required("sim"), d);
  if (auto events = top.optional("events")) {
    for (const yaml::Node& en : events->elements()) c.events.push_back(readEvent(en, c));
    std::stable_sort(c.events.begin(), c.events.end(), [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });
  }
  if (auto tr = top.optional("trace")) {
    yaml::StrictMap tm(*tr);
    if (auto v = tm.optional("every_n_ticks")) {
      c.trace.every_n_ticks = v->asIntIn(1, R::kMaxTraceEvery);
    }
    if (auto v = tm.optional("flush_every_rows")) {
      c.trace.flush_every_rows = v->asIntIn(1, R::kMaxTraceEvery);
    }
    if (auto v = tm.optional("frames")) {
      for (const yaml::Node& fn : v->elements()) {
        const std::string f = frameName(fn, d);
        if (std::find(c.trace.frames.begin(), c.trace.frames.end(), f) != c.trace.frames.end()) fn.fail("frame '" + f + "' listed twice");
        c.trace.frames.push_back(f);
      }
    }
    if (auto v = tm.optional("timings")) c.trace.timings = v->asBool();
    tm.finish();
  }
  const yaml::Node checks = top.required("checks");
  const checks::CheckContext check_context = checkContext(c, &d);
  for (const yaml::Node& cn : checks.elements()) {
    checks::CheckSpec cs = checks::readCheck(cn, check_context);
    for (const auto& o : c.checks) {
      if (o.name == cs.name) cn.fail("duplicate check name '" + cs.name + "'");
    }
    c.checks.push_back(cs);
  }
  if (auto comps = top.optional("comparisons")) {
    if (!isLexdyn(c)) comps->fail("comparisons need controller type lexdyn");
    for (const yaml::Node& cn : comps->elements()) {
      checks::ComparisonSpec cs = readComparison(cn, c);
      for (const auto& o : c.comparisons) {
        if (o.name == cs.name) cn.fail("duplicate comparison name '" + cs.name + "'");
      }
      c.comparisons.push_back(cs);
    }
  }
  if (auto xf = top.optional("expected_failures")) readExpectedFailures(c, *xf, check_context);
  std::optional<yaml::Node> stop = top.optional("stop_at_s");
  top.finish();
  if (isLexdyn(c)) validateLexdyn(c, controller_node);
  c.scenario_duration_s = c.duration_s;
  if (stop) {
    c.stop_at_s = stop->asPositiveDouble();
    if (c.stop_at_s < c.control_period_s) stop->fail("expected at least one control period (" + std::to_string(c.control_period_s) + " s)");
    c.duration_s = std::min(c.duration_s, c.stop_at_s);
  }
  return c;
}

}  // namespace

CaseSpec loadCase(const std::string& path) { return loadCase(path, {}); }

CaseSpec loadCase(const std::string& path, const std::vector<Override>& overrides) {
  const yaml::Node file_root = yaml::loadFile(path);
  if (overrides.empty()) {
    CaseSpec c = parseCase(file_root, path);
    c.document = doc::emit(file_root.raw());
    return c;
  }
  doc::Document d;
  d.file = path;
  d.overrides = overrides;
  // The file's own error, when it does not load as it is: the readers stopped there, so an
  // override of a key after it cannot be checked; the file's error is then the one reported
  // (an override never masks it, e.g. a robot file that does not load behind --duration).
  std::unique_ptr<InputError> file_error;
  {
    // The keys the readers accept, recorded on the file as it is (an error there may be what
    // an override mends: the keys read up to it are known all the same).
    yaml::KeyRecorder recorder;
    try {
      parseCase(file_root, path);
    } catch (const InputError& e) {
      file_error = std::make_unique<InputError>(e);
    }
    d.schema.keys = recorder.paths();
  }
  d.root = yaml::loadFile(path).raw();  // a second tree (YAML::Clone would drop the line numbers)
  for (const Override& o : overrides) {
    const YAML::Node value = doc::parseValue(o);
    try {
      d.canonical.push_back(doc::set(d.root, o.path, value, d.schema, o.label).canonical);
    } catch (const InputError&) {
      // An earlier override may have created the section this one sets a key in (say
      // controller.solver, absent from the file): the keys the readers accept there are recorded
      // on the document as the overrides so far left it, and the override is tried again.
      yaml::KeyRecorder recorder;
      try {
        parseCase(yaml::Node(d.root, path, ""), path);
      } catch (const InputError&) {}
      for (const std::string& k : recorder.paths())
        if (std::find(d.schema.keys.begin(), d.schema.keys.end(), k) == d.schema.keys.end()) d.schema.keys.push_back(k);
      try {
        d.canonical.push_back(doc::set(d.root, o.path, value, d.schema, o.label).canonical);
      } catch (const InputError&) {
        if (file_error) throw InputError(*file_error);
        throw;
      }
    }
  }
  try {
    CaseSpec c = parseCase(yaml::Node(d.root, path, ""), path);
    c.overrides = overrides;
    c.document = doc::emit(d.root);
    return c;
  } catch (const InputError& e) {
    const std::string where = doc::relabel(d, e.where());
    if (where == e.where()) throw;
    throw InputError(where, e.detail());
  }
}

std::string effectiveCaseText(const CaseSpec& spec, const std::string& dest_dir) {
  YAML::Node root = YAML::Load(spec.document);
  const doc::Schema none;
  for (const auto& [key, resolved] : spec.file_fields) {
    std::string value = resolved;
    if (!dest_dir.empty()) {
      std::error_code ec;
      const fs::path base = fs::weakly_canonical(fs::absolute(dest_dir), ec);
      const fs::path target = fs::weakly_canonical(fs::absolute(resolved), ec);
      // Relative where the two share a folder below the root (the file moves with its tree),
      // absolute otherwise.
      const auto first = [](const fs::path& p) { return std::next(p.begin()) == p.end() ? fs::path() : *std::next(p.begin()); };
      const bool shared = !first(base).empty() && first(base) == first(target);
      value = shared ? target.lexically_relative(base).string() : target.string();
      if (value.empty()) value = target.string();
    } else {
      value = fs::absolute(resolved).lexically_normal().string();
    }
    doc::set(root, key, YAML::Node(value), none, "file field " + key);
  }
  std::string header = "# Effective case: " + spec.path;
  if (spec.overrides.empty()) header += " (no overrides)";
  for (const Override& o : spec.overrides) header += "\n#   " + o.label;
  header += "\n# Written by lexdyn-harness; runs on its own: lexdyn-harness run THIS_FILE --out DIR\n";
  return header + doc::emit(root);
}

model::RobotDescription simulatedRobot(const CaseSpec& spec) {
  model::RobotDescription d = model::loadRobotDescription(spec.urdf_path, spec.data_path, spec.robot_options);
  for (const LinkMassScale& s : spec.sim_model.mass_scale) {
    for (auto& l : d.links) {
      if (!globMatch(s.match, l.name)) continue;
      l.mass *= s.scale;
      l.inertia *= s.scale;  // same shape, denser
    }
  }
  for (const LinkComOffset& o : spec.sim_model.com_offset) {
    for (auto& l : d.links) {
      if (globMatch(o.match, l.name)) l.com += o.offset_m;
    }
  }
  return d;
}

namespace {
// splitmix64: a counter-based generator, the same numbers on every platform.
std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
}  // namespace

Eigen::VectorXd initialJointPositions(const CaseSpec& spec, const model::RobotDescription& robot) {
  const InitialStateSpec& is = spec.initial_state;
  Eigen::VectorXd q = robot.posture(is.posture);
  for (const auto& [j, v] : is.joints) q[j] = v;
  const PosturePerturbation& p = is.perturbation;
  if (p.amplitude_rad > 0.0) {
    for (int j : p.joints) {
      // u in [-1, 1] from the top 53 bits of mix64(seed, joint index).
      const std::uint64_t h = mix64(mix64(p.seed) ^ static_cast<std::uint64_t>(j));
      const double u = 2.0 * (static_cast<double>(h >> 11) * 0x1.0p-53) - 1.0;
      const model::JointDescription& J = robot.joints[static_cast<size_t>(j)];
      q[j] = std::clamp(q[j] + p.amplitude_rad * u, J.lower, J.upper);
    }
  }
  return q;
}

const ExpectedFailure* expectedFailureFor(const CaseSpec& spec, const std::string& method) {
  for (const ExpectedFailure& x : spec.expected_failures) {
    if (x.method == method) return &x;
  }
  return nullptr;
}

checks::ComparisonSpec readComparison(const yaml::Node& node, const CaseSpec& cs) {
  return checks::readComparison(node, checkContext(cs, nullptr));
}

}  // namespace lexdyn::cases
