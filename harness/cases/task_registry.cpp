#include "harness/cases/task_registry.hpp"

#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/tasks/contact_force_bounds.hpp"
#include "lexdyn/tasks/equation_of_motion.hpp"
#include "lexdyn/tasks/velocity_min.hpp"
#include "lexdyn/tasks/wrench_min.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <limits>

namespace lexdyn::cases {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

namespace R = lexdyn::ranges;

std::string fmt(double v) { return formatNumber(v); }

// PD gains (kp 1/s^2, kv 1/s; kv absent: 2 sqrt(kp)). The task's discrete PD law over one
// control period dt is stable only for kv dt < 2 and kp dt^2 + 2 kv dt < 4 (lexdyn/common/
// input_ranges.hpp): gains beyond are refused here, naming the key, instead of a run that
// diverges to inf.
void readGains(yaml::StrictMap& m, tasks::PdGains& g, double dt) {
  if (auto gn = m.optional("gains")) {
    yaml::StrictMap gm(*gn);
    auto kp = gm.optional("kp");
    auto kv = gm.optional("kv");
    if (kp) g.kp = kp->asNonNegativeDouble();
    if (kv) g.kv = kv->asNonNegativeDouble();
    gm.finish();
    const double kvv = g.kv ? *g.kv : 2.0 * std::sqrt(g.kp);
    if (dt > 0.0 && (kvv * dt > R::kMaxPdKvDt || g.kp * dt * dt + 2.0 * kvv * dt > R::kMaxPdKpDt2Plus2KvDt)) {
      const yaml::Node& at = kv && kvv * dt > R::kMaxPdKvDt ? *kv : (kp ? *kp : *kv);
      at.fail("gains kp " + fmt(g.kp) + " /s^2, kv " + fmt(kvv) + " /s" + (g.kv ? "" : " (2 sqrt(kp))") +
              " make the task's discrete PD law unstable at the control period " + fmt(dt) + " s: expected kv dt < " + fmt(R::kMaxPdKvDt) +
              " and kp dt^2 + 2 kv dt < " + fmt(R::kMaxPdKpDt2Plus2KvDt) + ", found " + fmt(kvv * dt) + " and " +
              fmt(g.kp * dt * dt + 2.0 * kvv * dt));
    }
  }
}

Eigen::Vector3d position3(const yaml::Node& n) { return n.asVector3In(-R::kMaxPosition_m, R::kMaxPosition_m, "m"); }

// A joint target within the joint's limits (rad or m).
void requireWithinLimits(const yaml::Node& n, double v, const model::JointDescription& jd) {
  const double lo = std::max(jd.lower, -R::kMaxJointLimit), hi = std::min(jd.upper, R::kMaxJointLimit);
  if (!(v >= lo && v <= hi))
    n.fail("joint " + jd.name + ": expected a target within its limits [" + fmt(lo) + ", " + fmt(hi) + "], found " + fmt(v));
}

Eigen::Matrix3d readRotation(const yaml::Node& n) {
  if (!n.isSequence() || n.size() != 3) n.fail("expected a rotation matrix as 3 rows of 3 numbers");
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r) R.row(r) = n[r].asVector3().transpose();
  if ((R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 || R.determinant() <= 0.0) {
    n.fail("expected a rotation matrix (orthonormal to 1e-6, determinant +1)");
  }
  return R;
}

using Reader = void (*)(TaskSpec&, yaml::StrictMap&, const model::RobotDescription&, const std::vector<std::string>&, double dt);
using Maker = std::unique_ptr<tasks::TaskModel> (*)(const TaskSpec&, const model::RobotModel&, const tasks::ContactLayout&);
using Gains = const tasks::PdGains* (*)(const TaskSpec&);
using Target = TaskTargetLayout (*)(const TaskSpec&, const model::RobotDescription&);

/// A task type: its reader (the type's keys into TaskSpec::params), its builder, and, where the
/// type has them, its PD gains and the meaning of its target's values.
struct TaskType {
  const char* name;
  Reader read;
  Maker make;
  Gains gains = nullptr;
  Target target = nullptr;
};

void readNothing(TaskSpec&, yaml::StrictMap&, const model::RobotDescription&, const std::vector<std::string>&, double) {}

void readJointLimits(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::JointLimitsParams& p = s.params.emplace<tasks::JointLimitsParams>();
  if (auto v = m.optional("interaction_fraction")) p.interaction_fraction = v->asNonNegativeDouble();
  if (auto v = m.optional("safety_fraction")) p.safety_fraction = v->asNonNegativeDouble();
  if (auto v = m.optional("xi")) p.xi = v->asPositiveDouble();
  if (auto v = m.optional("adaptive")) p.adaptive = v->asBool();
  if (auto v = m.optional("velocity_limits")) p.velocity_limits = v->asBool();
}

void readTorqueLimits(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::TorqueLimitsParams& p = s.params.emplace<tasks::TorqueLimitsParams>();
  if (auto v = m.optional("scale")) {
    p.scale = v->asPositiveDouble();
    if (p.scale > 1.0) v->fail("expected a fraction of the URDF effort limit in (0, 1]");
  }
}

void readTrustRegion(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::TrustRegionParams& p = s.params.emplace<tasks::TrustRegionParams>();
  if (auto v = m.optional("delta")) {
    p.delta = v->asPositiveDouble();
    if (p.delta > R::kMaxDimensionless) v->asDoubleIn(0.0, R::kMaxDimensionless);
  }
}

void readSelfCollision(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double) {
  tasks::SelfCollisionParams& p = s.params.emplace<tasks::SelfCollisionParams>();
  if (auto pairs = m.optional("pairs")) {
    for (const yaml::Node& pn : pairs->elements()) {
      if (!pn.isSequence() || pn.size() != 2) pn.fail("expected a pair of capsule names [a, b]");
      const std::string a = pn[0].asString(), b = pn[1].asString();
      for (const auto& [node, name] : {std::pair<yaml::Node, std::string>{pn[0], a}, {pn[1], b}}) {
        if (d.findCapsule(name) < 0) {
          std::vector<std::string> names;
          for (const auto& c : d.capsules) names.push_back(c.name);
          node.fail("unknown capsule '" + name + "' (capsules: " + joinNames(names) + ")");
        }
      }
      p.pairs.emplace_back(a, b);
    }
  }
  if (auto v = m.optional("interaction_distance")) {
    p.interaction_distance = v->asPositiveDouble();
    if (p.interaction_distance > R::kMaxLength_m) v->asDoubleIn(0.0, R::kMaxLength_m, "m");
  }
  if (auto v = m.optional("safety_distance")) p.safety_distance = v->asDoubleIn(0.0, R::kMaxLength_m, "m");
  if (auto v = m.optional("xi")) p.xi = v->asPositiveDouble();
  if (auto v = m.optional("adaptive")) p.adaptive = v->asBool();
}

void readContact(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>& contacts, double dt) {
  tasks::ContactTaskParams& p = s.params.emplace<tasks::ContactTaskParams>();
  const yaml::Node c = m.required("contact");
  p.contact = c.asString();
  bool known = false;
  for (const auto& n : contacts) known = known || n == p.contact;
  if (!known) c.fail("unknown contact '" + p.contact + "' (controller.contacts: " + joinNames(contacts) + ")");
  readGains(m, p.gains, dt);
}

void readPosition(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::PositionParams& p = s.params.emplace<tasks::PositionParams>();
  p.frame = frameName(m.required("frame"), d);
  if (auto v = m.optional("point")) p.point = position3(*v);
  if (auto v = m.optional("target")) p.target = position3(*v);
  readGains(m, p.gains, dt);
}

void readOrientation(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::OrientationParams& p = s.params.emplace<tasks::OrientationParams>();
  p.frame = frameName(m.required("frame"), d);
  auto target = m.optional("target");
  auto rpy = m.optional("target_rpy_rad");
  if (target && rpy) rpy->fail("give either target or target_rpy_rad, not both");
  if (target) p.target = readRotation(*target);
  if (rpy) p.target = rotationFromRpy(rpy->asVector3In(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad"));
  readGains(m, p.gains, dt);
}

void readCom(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double dt) {
  tasks::ComParams& p = s.params.emplace<tasks::ComParams>();
  if (auto v = m.optional("target")) p.target = position3(*v);
  readGains(m, p.gains, dt);
}

void readComBox(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::ComBoxParams& p = s.params.emplace<tasks::ComBoxParams>();
  if (auto v = m.optional("lower")) p.lower = asBound3(*v);
  if (auto v = m.optional("upper")) p.upper = asBound3(*v);
  if (auto dn = m.optional("damper")) {
    yaml::StrictMap dm(*dn);
    if (auto v = dm.optional("interaction")) {
      p.damper.interaction = v->asPositiveDouble();
      if (p.damper.interaction > R::kMaxPosition_m) v->asDoubleIn(0.0, R::kMaxPosition_m, "m");
    }
    if (auto v = dm.optional("safety")) p.damper.safety = v->asDoubleIn(0.0, R::kMaxPosition_m, "m");
    if (auto v = dm.optional("xi")) p.damper.xi = v->asPositiveDouble();
    if (auto v = dm.optional("adaptive")) p.damper.adaptive = v->asBool();
    dm.finish();
  }
}

void readJointPosition(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::JointPositionParams& p = s.params.emplace<tasks::JointPositionParams>();
  const yaml::Node joints = m.required("joints");
  if (joints.size() < 1) joints.fail("expected at least one joint");
  for (const yaml::Node& jn : joints.elements()) p.joints.push_back(jointName(jn, d));
  if (auto v = m.optional("target")) {
    p.target = v->asVector(static_cast<int>(p.joints.size()));
    for (int k = 0; k < p.target.size(); ++k)
      requireWithinLimits((*v)[k], p.target[k], d.joints[static_cast<size_t>(d.findJoint(p.joints[static_cast<size_t>(k)]))]);
  }
  readGains(m, p.gains, dt);
}

void readPosture(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::PostureParams& p = s.params.emplace<tasks::PostureParams>();
  const int nj = static_cast<int>(d.joints.size());
  auto target = m.optional("target");
  auto posture = m.optional("posture");
  if (target && posture) posture->fail("give either target or posture, not both");
  if (target) {
    p.target = target->asVector(nj);
    for (int k = 0; k < nj; ++k) requireWithinLimits((*target)[k], p.target[k], d.joints[static_cast<size_t>(k)]);
  }
  if (posture) {
    const std::string name = posture->asString();
    std::vector<std::string> names;
    for (const auto& ps : d.postures) {
      if (ps.first == name) p.posture = name;
      names.push_back(ps.first);
    }
    if (p.posture.empty()) posture->fail("unknown posture '" + name + "' (postures: " + joinNames(names) + ")");
  }
  if (auto overrides = m.optional("joints")) {
    // Convenience: a named posture or a target with some joints changed; becomes `target`.
    if (!target && !posture) overrides->fail("joint overrides need a posture or a target to start from");
    if (posture) {
      for (const auto& ps : d.postures) {
        if (ps.first == p.posture) p.target = ps.second;
      }
      p.posture.clear();
    }
    for (const auto& [key, value] : overrides->entries()) {
      const int j = d.findJoint(key);
      if (j < 0) value.fail("unknown joint '" + key + "'");
      p.target[j] = value.asDouble();
      requireWithinLimits(value, p.target[j], d.joints[static_cast<size_t>(j)]);
    }
  }
  readGains(m, p.gains, dt);
}

template <class T>
std::unique_ptr<tasks::TaskModel> own(std::unique_ptr<T> t) {
  return std::unique_ptr<tasks::TaskModel>(std::move(t));
}

/// The builder of a task type whose constructor takes (name, model, params).
template <class Task, class Params>
std::unique_ptr<tasks::TaskModel> build(const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
  return own(std::make_unique<Task>(s.name, m, s.paramsAs<Params>()));
}

/// The PD gains of a params struct with a `gains` member.
template <class Params>
const tasks::PdGains* gainsOf(const TaskSpec& s) {
  return &s.paramsAs<Params>().gains;
}

TaskTargetLayout pointTarget(const TaskSpec&, const model::RobotDescription&) { return {{"x", "y", "z"}, true, {}}; }
TaskTargetLayout boxTarget(const TaskSpec&, const model::RobotDescription&) {
  return {{"lower_x", "lower_y", "lower_z", "upper_x", "upper_y", "upper_z"}, true, {}};
}
TaskTargetLayout jointsTarget(const TaskSpec& s, const model::RobotDescription&) {
  const std::vector<std::string>& joints = s.paramsAs<tasks::JointPositionParams>().joints;
  return {joints, false, joints};
}
TaskTargetLayout postureTarget(const TaskSpec&, const model::RobotDescription& d) {
  TaskTargetLayout t;
  for (const auto& j : d.joints) t.joints.push_back(j.name);
  return t;
}

// One entry per type, in the order of docs/controller.md.
const std::vector<TaskType>& registry() {
  static const std::vector<TaskType> types = {
      {"contact_force_bounds", readNothing,
       [](const TaskSpec& s, const model::RobotModel&, const tasks::ContactLayout& l) {
         return own(std::make_unique<tasks::ContactForceBoundsTask>(s.name, l));
       }},
      {"joint_limits", readJointLimits, build<tasks::JointLimitsTask, tasks::JointLimitsParams>},
      {"equation_of_motion", readNothing,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::EquationOfMotionTask>(s.name, m));
       }},
      {"torque_limits", readTorqueLimits, build<tasks::TorqueLimitsTask, tasks::TorqueLimitsParams>},
      {"trust_region", readTrustRegion, build<tasks::TrustRegionTask, tasks::TrustRegionParams>},
      {"self_collision", readSelfCollision, build<tasks::SelfCollisionTask, tasks::SelfCollisionParams>},
      {"contact", readContact,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout& l) {
         return own(std::make_unique<tasks::ContactTask>(s.name, m, l, s.paramsAs<tasks::ContactTaskParams>()));
       },
       gainsOf<tasks::ContactTaskParams>},
      {"position", readPosition, build<tasks::PositionTask, tasks::PositionParams>, gainsOf<tasks::PositionParams>, pointTarget},
      {"orientation", readOrientation, build<tasks::OrientationTask, tasks::OrientationParams>, gainsOf<tasks::OrientationParams>},
      {"com", readCom, build<tasks::ComTask, tasks::ComParams>, gainsOf<tasks::ComParams>, pointTarget},
      {"com_box", readComBox, build<tasks::ComBoxTask, tasks::ComBoxParams>, nullptr, boxTarget},
      {"joint_position", readJointPosition, build<tasks::JointPositionTask, tasks::JointPositionParams>,
       gainsOf<tasks::JointPositionParams>, jointsTarget},
      {"posture", readPosture, build<tasks::PostureTask, tasks::PostureParams>, gainsOf<tasks::PostureParams>, postureTarget},
      {"velocity_min", readNothing,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::VelocityMinTask>(s.name, m));
       }},
      {"wrench_min", readNothing,
       [](const TaskSpec& s, const model::RobotModel&, const tasks::ContactLayout& l) {
         return own(std::make_unique<tasks::WrenchMinTask>(s.name, l));
       }},
  };
  return types;
}

const TaskType* findType(const std::string& name) {
  for (const TaskType& t : registry()) {
    if (name == t.name) return &t;
  }
  return nullptr;
}

}  // namespace

namespace {
template <class T>
std::vector<std::string> namesOf(const std::vector<T>& v) {
  std::vector<std::string> out;
  for (const T& x : v) out.push_back(x.name);
  return out;
}
}  // namespace

std::string frameName(const yaml::Node& n, const model::RobotDescription& d) {
  return checks::knownName(n, namesOf(d.frames), "frame", "frames");
}

std::string jointName(const yaml::Node& n, const model::RobotDescription& d) {
  return checks::knownName(n, namesOf(d.joints), "joint", "joints");
}

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

const std::vector<std::string>& taskTypes() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const TaskType& t : registry()) v.emplace_back(t.name);
    return v;
  }();
  return names;
}

double asBound(const yaml::Node& n) {
  if (n.isScalar() && n.raw().Tag() != "!") {
    const std::string& s = n.raw().Scalar();
    if (s == ".inf" || s == "+.inf" || s == "inf" || s == "+inf" || s == ".Inf" || s == ".INF") return kInf;
    if (s == "-.inf" || s == "-inf" || s == "-.Inf" || s == "-.INF") return -kInf;
  }
  return n.asDoubleIn(-R::kMaxPosition_m, R::kMaxPosition_m, "m (or .inf, -.inf)");
}

Eigen::Vector3d asBound3(const yaml::Node& n) {
  if (!n.isSequence() || n.size() != 3) n.fail("expected a sequence of 3 numbers (.inf and -.inf allowed)");
  return Eigen::Vector3d(asBound(n[0]), asBound(n[1]), asBound(n[2]));
}

void requireChannelName(const yaml::Node& n, const std::string& name) {
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) n.fail("names may contain only letters, digits, '_' and '-' (they name trace channels), found '" + name + "'");
  }
}

std::string channelName(const yaml::Node& n) {
  std::string name = n.asString();
  requireChannelName(n, name);
  return name;
}

TaskSpec readTaskSpec(const yaml::Node& node, const model::RobotDescription& robot, const std::vector<std::string>& contacts,
                      double control_period_s) {
  yaml::StrictMap m(node);
  TaskSpec s;
  s.where = node.where();
  s.name = channelName(m.required("name"));
  const yaml::Node type = m.required("type");
  s.type = type.asEnum(taskTypes());
  const TaskType* t = findType(s.type);
  t->read(s, m, robot, contacts, control_period_s);
  m.finish();
  return s;
}

const tasks::PdGains* taskGains(const TaskSpec& spec) {
  const TaskType* t = findType(spec.type);
  return t && t->gains ? t->gains(spec) : nullptr;
}

TaskTargetLayout taskTarget(const TaskSpec& spec, const model::RobotDescription& robot) {
  const TaskType* t = findType(spec.type);
  return t && t->target ? t->target(spec, robot) : TaskTargetLayout{};
}

std::unique_ptr<tasks::TaskModel> makeTask(const TaskSpec& spec, const model::RobotModel& model, const tasks::ContactLayout& layout) {
  const TaskType* t = findType(spec.type);
  if (!t) throw InputError(spec.where, "unknown task type '" + spec.type + "'");
  try {
    return t->make(spec, model, layout);
  } catch (const InputError& e) {
    throw InputError(spec.where, e.what());
  }
}

}  // namespace lexdyn::cases
