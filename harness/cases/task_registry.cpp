#include "harness/cases/task_registry.hpp"

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

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

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
              " make the task's discrete PD law unstable at the control period " + fmt(dt) + " s: expected kv dt < " +
              fmt(R::kMaxPdKvDt) + " and kp dt^2 + 2 kv dt < " + fmt(R::kMaxPdKpDt2Plus2KvDt) + ", found " + fmt(kvv * dt) + " and " +
              fmt(g.kp * dt * dt + 2.0 * kvv * dt));
    }
  }
}

Eigen::Vector3d position3(const yaml::Node& n) { return n.asVector3In(-R::kMaxPosition_m, R::kMaxPosition_m, "m"); }

// A joint target within the joint's limits (rad or m).
void requireWithinLimits(const yaml::Node& n, double v, const model::JointDescription& jd) {
  const double lo = std::max(jd.lower, -R::kMaxJointLimit), hi = std::min(jd.upper, R::kMaxJointLimit);
  if (!(v >= lo && v <= hi)) n.fail("joint " + jd.name + ": expected a target within its limits [" + fmt(lo) + ", " + fmt(hi) + "], found " + fmt(v));
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

struct TaskType {
  const char* name;
  Reader read;
  Maker make;
};

void readNothing(TaskSpec&, yaml::StrictMap&, const model::RobotDescription&, const std::vector<std::string>&, double) {}

void readJointLimits(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::JointLimitsParams& p = s.joint_limits;
  if (auto v = m.optional("interaction_fraction")) p.interaction_fraction = v->asNonNegativeDouble();
  if (auto v = m.optional("safety_fraction")) p.safety_fraction = v->asNonNegativeDouble();
  if (auto v = m.optional("xi")) p.xi = v->asPositiveDouble();
  if (auto v = m.optional("adaptive")) p.adaptive = v->asBool();
  if (auto v = m.optional("velocity_limits")) p.velocity_limits = v->asBool();
}

void readTorqueLimits(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  if (auto v = m.optional("scale")) {
    s.torque_limits.scale = v->asPositiveDouble();
    if (s.torque_limits.scale > 1.0) v->fail("expected a fraction of the URDF effort limit in (0, 1]");
  }
}

void readTrustRegion(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  if (auto v = m.optional("delta")) {
    s.trust_region.delta = v->asPositiveDouble();
    if (s.trust_region.delta > R::kMaxDimensionless) v->asDoubleIn(0.0, R::kMaxDimensionless);
  }
}

void readSelfCollision(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double) {
  tasks::SelfCollisionParams& p = s.self_collision;
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
  const yaml::Node c = m.required("contact");
  s.contact.contact = c.asString();
  bool known = false;
  for (const auto& n : contacts) known = known || n == s.contact.contact;
  if (!known) c.fail("unknown contact '" + s.contact.contact + "' (controller.contacts: " + joinNames(contacts) + ")");
  readGains(m, s.contact.gains, dt);
}

void readPosition(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::PositionParams& p = s.position;
  p.frame = frameName(m.required("frame"), d);
  if (auto v = m.optional("point")) p.point = position3(*v);
  if (auto v = m.optional("target")) p.target = position3(*v);
  readGains(m, p.gains, dt);
}

void readOrientation(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::OrientationParams& p = s.orientation;
  p.frame = frameName(m.required("frame"), d);
  auto target = m.optional("target");
  auto rpy = m.optional("target_rpy_rad");
  if (target && rpy) rpy->fail("give either target or target_rpy_rad, not both");
  if (target) p.target = readRotation(*target);
  if (rpy) p.target = rotationFromRpy(rpy->asVector3In(-R::kMaxAngle_rad, R::kMaxAngle_rad, "rad"));
  readGains(m, p.gains, dt);
}

void readCom(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double dt) {
  if (auto v = m.optional("target")) s.com.target = position3(*v);
  readGains(m, s.com.gains, dt);
}

void readComBox(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription&, const std::vector<std::string>&, double) {
  tasks::ComBoxParams& p = s.com_box;
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
  tasks::JointPositionParams& p = s.joint_position;
  const yaml::Node joints = m.required("joints");
  if (joints.size() < 1) joints.fail("expected at least one joint");
  for (const yaml::Node& jn : joints.elements()) p.joints.push_back(jointName(jn, d));
  if (auto v = m.optional("target")) {
    p.target = v->asVector(static_cast<int>(p.joints.size()));
    for (int k = 0; k < p.target.size(); ++k) requireWithinLimits((*v)[k], p.target[k], d.joints[static_cast<size_t>(d.findJoint(p.joints[static_cast<size_t>(k)]))]);
  }
  readGains(m, p.gains, dt);
}

void readPosture(TaskSpec& s, yaml::StrictMap& m, const model::RobotDescription& d, const std::vector<std::string>&, double dt) {
  tasks::PostureParams& p = s.posture;
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

const std::vector<TaskType>& registry() {
  static const std::vector<TaskType> types = {
      {"contact_force_bounds", readNothing,
       [](const TaskSpec& s, const model::RobotModel&, const tasks::ContactLayout& l) {
         return own(std::make_unique<tasks::ContactForceBoundsTask>(s.name, l));
       }},
      {"joint_limits", readJointLimits,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::JointLimitsTask>(s.name, m, s.joint_limits));
       }},
      {"equation_of_motion", readNothing,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::EquationOfMotionTask>(s.name, m));
       }},
      {"torque_limits", readTorqueLimits,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::TorqueLimitsTask>(s.name, m, s.torque_limits));
       }},
      {"trust_region", readTrustRegion,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::TrustRegionTask>(s.name, m, s.trust_region));
       }},
      {"self_collision", readSelfCollision,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::SelfCollisionTask>(s.name, m, s.self_collision));
       }},
      {"contact", readContact,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout& l) {
         return own(std::make_unique<tasks::ContactTask>(s.name, m, l, s.contact));
       }},
      {"position", readPosition,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::PositionTask>(s.name, m, s.position));
       }},
      {"orientation", readOrientation,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::OrientationTask>(s.name, m, s.orientation));
       }},
      {"com", readCom,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::ComTask>(s.name, m, s.com));
       }},
      {"com_box", readComBox,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::ComBoxTask>(s.name, m, s.com_box));
       }},
      {"joint_position", readJointPosition,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::JointPositionTask>(s.name, m, s.joint_position));
       }},
      {"posture", readPosture,
       [](const TaskSpec& s, const model::RobotModel& m, const tasks::ContactLayout&) {
         return own(std::make_unique<tasks::PostureTask>(s.name, m, s.posture));
       }},
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

std::string joinNames(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

std::string frameName(const yaml::Node& n, const model::RobotDescription& d) {
  const std::string name = n.asString();
  if (d.findFrame(name) < 0) {
    std::vector<std::string> names;
    for (const auto& f : d.frames) names.push_back(f.name);
    n.fail("unknown frame '" + name + "' (frames: " + joinNames(names) + ")");
  }
  return name;
}

std::string jointName(const yaml::Node& n, const model::RobotDescription& d) {
  const std::string name = n.asString();
  if (d.findJoint(name) < 0) {
    std::vector<std::string> names;
    for (const auto& j : d.joints) names.push_back(j.name);
    n.fail("unknown joint '" + name + "' (joints: " + joinNames(names) + ")");
  }
  return name;
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

TaskSpec readTaskSpec(const yaml::Node& node, const model::RobotDescription& robot, const std::vector<std::string>& contacts,
                      double control_period_s) {
  yaml::StrictMap m(node);
  TaskSpec s;
  s.where = node.where();
  const yaml::Node name = m.required("name");
  s.name = name.asString();
  requireChannelName(name, s.name);
  const yaml::Node type = m.required("type");
  s.type = type.asEnum(taskTypes());
  const TaskType* t = findType(s.type);
  t->read(s, m, robot, contacts, control_period_s);
  m.finish();
  return s;
}

std::unique_ptr<tasks::TaskModel> makeTask(const TaskSpec& spec, const model::RobotModel& model,
                                           const tasks::ContactLayout& layout) {
  const TaskType* t = findType(spec.type);
  if (!t) throw InputError(spec.where, "unknown task type '" + spec.type + "'");
  try {
    return t->make(spec, model, layout);
  } catch (const InputError& e) {
    throw InputError(spec.where, e.what());
  }
}

}  // namespace lexdyn::cases
