// The robot data file (YAML, lexdyn-robot-data/1): what a URDF does not carry. Every entry is
// read on its own; a problem in one is recorded and the next is read, so that one run of the
// loader lists every problem of the file.
#include "lexdyn/model/detail/data_file.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_ranges.hpp"

#include <cmath>
#include <filesystem>
#include <limits>

namespace lexdyn::model::detail {

namespace {

constexpr const char* kDataFormat = "lexdyn-robot-data/1";

bool validName(const std::string& n) { return !n.empty() && n.find_first_of(" \t\r\n,\"'") == std::string::npos; }
std::string fmt(double v) { return formatNumber(v); }

template <class T>
int indexOfName(const std::vector<T>& items, const std::string& n) {
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

// '*' matches any run of characters (the cases' gain groups use the same patterns).
bool globMatch(const char* p, const char* s) {
  if (*p == '\0') return *s == '\0';
  if (*p == '*') return globMatch(p + 1, s) || (*s != '\0' && globMatch(p, s + 1));
  if (*s == '\0') return false;
  return *p == *s && globMatch(p + 1, s + 1);
}

const LockedJointDescription* lockedJoint(const RobotDescription& d, const std::string& joint) {
  for (const auto& l : d.locked_joints) {
    if (l.name == joint) return &l;
  }
  return nullptr;
}

bool coupledJoint(const RobotDescription& d, const std::string& joint) {
  for (const auto& c : d.coupled_joints) {
    if (c.name == joint) return true;
  }
  return false;
}

}  // namespace

BaseType readBaseType(const yaml::Node& root) {
  if (!root.raw()["base"]) root.fail("missing required key 'base' (free_flyer or fixed)");
  const yaml::Node b(root.raw()["base"], root.file(), "base");
  return b.asEnum({"free_flyer", "fixed"}) == "fixed" ? BaseType::Fixed : BaseType::FreeFlyer;
}

std::vector<std::string> readPackagePaths(const yaml::Node& root, ProblemList& problems) {
  std::vector<std::string> out;
  if (!root.raw()["package_path"]) return out;
  problems.attempt([&] {
    const yaml::Node node(root.raw()["package_path"], root.file(), "package_path");
    const std::filesystem::path dir = std::filesystem::path(root.file()).parent_path();
    for (const yaml::Node& e : node.elements()) {
      const std::filesystem::path rel(e.asString());
      const std::filesystem::path p = (rel.is_absolute() ? rel : dir / rel).lexically_normal();
      std::error_code ec;
      if (!std::filesystem::is_directory(p, ec)) e.fail("folder not found: " + p.string());
      out.push_back(p.string());
    }
  });
  return out;
}

MimicPolicy readMimicPolicy(const yaml::Node& root, ProblemList& problems) {
  MimicPolicy p;
  if (!root.raw()["mimic"]) return p;
  problems.attempt([&] {
    const yaml::Node node(root.raw()["mimic"], root.file(), "mimic");
    p.given = true;
    p.where = node.where();
    yaml::StrictMap m(node);
    const std::string mode = m.required("mode").asEnum({"locked", "coupled"});
    p.mode = mode == "coupled" ? MimicMode::Coupled : MimicMode::Locked;
    if (auto posture = m.optional("posture")) {
      if (p.mode == MimicMode::Coupled) posture->fail("a posture locks mimic joints: it goes with `mode: locked`");
      p.posture = posture->asString();
      const YAML::Node all = root.raw()["postures"];
      if (!all || !all.IsMap() || !all[p.posture]) posture->fail("no posture '" + p.posture + "' in the data file's postures");
      for (const auto& kv : all[p.posture]) {
        const yaml::Node v(kv.second, root.file(), "postures." + p.posture + "." + kv.first.Scalar());
        p.master_values[kv.first.Scalar()] = v.asDouble();
      }
    }
    m.finish();
  });
  return p;
}

void readDataFile(RobotDescription& d, const yaml::Node& root, ProblemList& problems) {
  yaml::StrictMap top(root);
  // An entry that fails is recorded and the next one is read.
  auto attempt = [&](const auto& f) { problems.attempt(f); };
  attempt([&] {
    const yaml::Node format = top.required("format");
    if (format.asString() != kDataFormat) format.fail(std::string("expected '") + kDataFormat + "', found '" + format.asString() + "'");
  });
  attempt([&] {
    const yaml::Node robot = top.required("robot");
    if (robot.asString() != d.name) {
      robot.fail("the URDF describes robot '" + d.name + "', this data file is for '" + robot.asString() + "'");
    }
  });
  top.required("base");  // read before the tree was built
  attempt([&] {
    if (auto u = top.optional("urdf")) d.data_urdf = u->asString();
  });
  attempt([&] {
    if (auto u = top.optional("mesh_up_axis")) d.mesh_up_axis_from_file = u->asEnum({"ignore", "file"}) == "file";
  });
  if (top.has("mimic")) top.optional("mimic");                // read before the tree was built
  if (top.has("package_path")) top.optional("package_path");  // read before the URDF's meshes were
  attempt([&] {
    if (auto g = top.optional("gravity")) {
      d.gravity = g->asVector3();
      if (!(d.gravity.norm() <= ranges::kMaxGravity_mps2)) {
        g->fail("expected |gravity| <= " + fmt(ranges::kMaxGravity_mps2) + " m/s^2, found " + fmt(d.gravity.norm()));
      }
    }
  });
  attempt([&] {
    if (auto mu = top.optional("friction_coefficient")) {
      d.friction_coefficient = mu->asPositiveDouble();
      if (d.friction_coefficient > ranges::kMaxFriction) {
        mu->fail("expected a friction coefficient in (0, " + fmt(ranges::kMaxFriction) + "], found " + fmt(d.friction_coefficient));
      }
    }
  });

  auto frameNames = [&]() {
    std::string s;
    for (const auto& f : d.frames) s += (s.empty() ? "" : ", ") + f.name;
    return s;
  };
  auto lookupFrame = [&](const yaml::Node& n) {
    const std::string name = n.asString();
    const int f = d.findFrame(name);
    if (f < 0) n.fail("unknown frame or link '" + name + "' (known: " + frameNames() + ")");
    return f;
  };
  // The entry's name: valid, and no earlier item of `items` (a `what`) has it.
  auto newName = [](yaml::StrictMap& m, const auto& items, const std::string& what) {
    const yaml::Node name = m.required("name");
    std::string n = name.asString();
    if (!validName(n)) name.fail("names may not contain whitespace, commas or quotes");
    if (indexOfName(items, n) >= 0) name.fail("duplicate " + what + " '" + n + "'");
    return n;
  };
  // f(m) for each entry m (a map) of the list `key` when the file has it; an entry's unknown keys
  // are refused once f has read it; a failing entry is recorded and the next one read.
  auto forEachEntry = [&](const char* key, const auto& f) {
    std::optional<yaml::Node> list;
    attempt([&] { list = top.optional(key); });
    if (!list) return;
    std::vector<yaml::Node> entries;
    attempt([&] { entries = list->elements(); });
    for (const yaml::Node& n : entries) {
      attempt([&] {
        yaml::StrictMap m(n);
        f(m);
        m.finish();
      });
    }
  };

  forEachEntry("frames", [&](yaml::StrictMap& m) {
    const yaml::Node name = m.required("name");
    const std::string fname = name.asString();
    if (!validName(fname)) name.fail("names may not contain whitespace, commas or quotes");
    if (d.findFrame(fname) >= 0) name.fail("frame name '" + fname + "' is already used by a link or frame");
    const int parent = lookupFrame(m.required("parent"));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    if (auto xyz = m.optional("xyz")) X.translation() = xyz->asVector3In(-ranges::kMaxLength_m, ranges::kMaxLength_m, "m");
    if (auto rpy = m.optional("rpy")) X.linear() = rotationFromRpy(rpy->asVector3In(-ranges::kMaxAngle_rad, ranges::kMaxAngle_rad, "rad"));
    FrameDescription f;
    f.name = fname;
    f.link = d.frames[static_cast<size_t>(parent)].link;
    f.placement = d.frames[static_cast<size_t>(parent)].placement * X;
    f.from_data_file = true;
    d.frames.push_back(f);
  });

  forEachEntry("contact_surfaces", [&](yaml::StrictMap& m) {
    ContactSurfaceDescription s;
    s.name = newName(m, d.contact_surfaces, "contact surface");
    s.frame = lookupFrame(m.required("frame"));
    const yaml::Node pts = m.required("points");
    if (pts.size() < 1) pts.fail("a contact surface needs at least one point");
    for (const yaml::Node& p : pts.elements()) s.points.push_back(p.asVector3In(-ranges::kMaxLength_m, ranges::kMaxLength_m, "m"));
    if (auto r = m.optional("radius")) s.radius = r->asDoubleIn(0.0, 1.0, "m");  // a ball foot: the points are sphere centres
    d.contact_surfaces.push_back(s);
  });
  if (!d.contact_surfaces.empty() && !top.has("friction_coefficient")) {
    problems.error(root.where(), "friction_coefficient is required when contact_surfaces are given");
  }

  forEachEntry("force_sensors", [&](yaml::StrictMap& m) {
    ForceSensorDescription s;
    s.name = newName(m, d.force_sensors, "force sensor");
    s.frame = lookupFrame(m.required("frame"));
    d.force_sensors.push_back(s);
  });

  forEachEntry("capsules", [&](yaml::StrictMap& m) {
    CapsuleDescription c;
    c.name = newName(m, d.capsules, "capsule");
    const int frame = lookupFrame(m.required("parent"));
    const Eigen::Isometry3d& X = d.frames[static_cast<size_t>(frame)].placement;
    c.link = d.frames[static_cast<size_t>(frame)].link;
    c.p0 = X * m.required("p0").asVector3In(-ranges::kMaxLength_m, ranges::kMaxLength_m, "m");
    c.p1 = X * m.required("p1").asVector3In(-ranges::kMaxLength_m, ranges::kMaxLength_m, "m");
    const yaml::Node rn = m.required("radius");
    c.radius = rn.asPositiveDouble();
    if (c.radius > ranges::kMaxLength_m) rn.fail("expected a radius in (0, " + fmt(ranges::kMaxLength_m) + "] m, found " + fmt(c.radius));
    d.capsules.push_back(c);
  });

  attempt([&] {
    auto pairs = top.optional("collision_pairs");
    if (!pairs) return;
    yaml::StrictMap m(*pairs);
    const yaml::Node di = m.required("interaction_distance");
    const yaml::Node ds = m.required("safety_distance");
    d.collision_interaction_distance = di.asPositiveDouble();
    d.collision_safety_distance = ds.asNonNegativeDouble();
    if (d.collision_interaction_distance > ranges::kMaxLength_m) di.fail("expected at most " + fmt(ranges::kMaxLength_m) + " m");
    if (!(d.collision_safety_distance < d.collision_interaction_distance))
      ds.fail("safety_distance must be smaller than interaction_distance");
    const yaml::Node list = m.required("pairs");
    for (const yaml::Node& pn : list.elements()) {
      attempt([&] {
        if (pn.size() != 2) pn.fail("a collision pair is a list of two capsule names");
        CollisionPairDescription cp;
        int ids[2];
        for (int k = 0; k < 2; ++k) {
          const yaml::Node e = pn[k];
          ids[k] = d.findCapsule(e.asString());
          if (ids[k] < 0) {
            std::string known;
            for (const auto& c : d.capsules) known += (known.empty() ? "" : ", ") + c.name;
            e.fail("unknown capsule '" + e.asString() + "' (known: " + known + ")");
          }
        }
        cp.capsule_a = ids[0];
        cp.capsule_b = ids[1];
        if (d.capsules[static_cast<size_t>(ids[0])].link == d.capsules[static_cast<size_t>(ids[1])].link) {
          pn.fail("both capsules are on the same link; a self-collision pair needs two links");
        }
        for (const auto& o : d.collision_pairs) {
          if ((o.capsule_a == cp.capsule_a && o.capsule_b == cp.capsule_b) ||
              (o.capsule_a == cp.capsule_b && o.capsule_b == cp.capsule_a)) {
            pn.fail("duplicate collision pair");
          }
        }
        d.collision_pairs.push_back(cp);
      });
    }
    m.finish();
  });

  // Limits the URDF leaves unspecified (effort="0", no <limit>) or gets wrong.
  attempt([&] {
    auto limits = top.optional("joint_limits");
    if (!limits) return;
    for (const auto& [jname, ln] : limits->entries()) {
      attempt([&] {
        const int j = d.findJoint(jname);
        if (j < 0) {
          ln.fail(lockedJoint(d, jname)
                      ? "joint '" + jname + "' is locked by the loader (" + lockedJoint(d, jname)->reason + "): not a joint of the model"
                  : coupledJoint(d, jname) ? "joint '" + jname + "' is a mimic joint coupled to its master: give the master's limits"
                                           : "unknown joint '" + jname + "'");
        }
        JointDescription& jd = d.joints[static_cast<size_t>(j)];
        yaml::StrictMap m(ln);
        if (auto e = m.optional("effort")) jd.effort_limit = e->asDoubleIn(ranges::kMinEffortLimit, ranges::kMaxEffortLimit, "N m or N");
        if (auto v = m.optional("velocity"))
          jd.velocity_limit = v->asDoubleIn(ranges::kMinVelocityLimit, ranges::kMaxVelocityLimit, "rad/s or m/s");
        std::optional<yaml::Node> lo = m.optional("lower"), hi = m.optional("upper");
        if (lo) jd.lower = lo->asDoubleIn(-ranges::kMaxJointLimit, ranges::kMaxJointLimit, "rad or m");
        if (hi) jd.upper = hi->asDoubleIn(-ranges::kMaxJointLimit, ranges::kMaxJointLimit, "rad or m");
        if ((lo || hi) && !(jd.lower < jd.upper)) ln.fail("expected lower < upper, found " + fmt(jd.lower) + " and " + fmt(jd.upper));
        m.finish();
      });
    }
  });

  forEachEntry("servo_gains", [&](yaml::StrictMap& m) {
    ServoGainGroup g;
    const yaml::Node match = m.required("match");
    g.match = match.asString();
    g.kp = m.required("kp").asDoubleIn(0.0, ranges::kMaxServoKp, "N m/rad (N/m)");
    g.kd = m.required("kd").asDoubleIn(0.0, ranges::kMaxServoKd, "N m s/rad (N s/m)");
    bool any = false;
    for (const auto& j : d.joints) any = any || globMatch(g.match.c_str(), j.name.c_str());
    if (!any) match.fail("pattern '" + g.match + "' matches no joint");
    d.servo_gains.push_back(g);
  });
  if (!d.servo_gains.empty()) {
    std::string missing;
    for (const auto& j : d.joints) {
      bool any = false;
      for (const auto& g : d.servo_gains) any = any || globMatch(g.match.c_str(), j.name.c_str());
      if (!any) missing += (missing.empty() ? "" : ", ") + j.name;
    }
    if (!missing.empty()) problems.error(root.where() + " servo_gains", "no gain group matches joint(s) " + missing);
  }

  attempt([&] {
    auto postures = top.optional("postures");
    if (!postures) return;
    for (const auto& [pname, pn] : postures->entries()) {
      attempt([&] {
        Eigen::VectorXd q = Eigen::VectorXd::Constant(static_cast<int>(d.joints.size()), std::numeric_limits<double>::quiet_NaN());
        std::vector<std::pair<std::string, double>> coupled_values;  // checked against their masters below
        for (const auto& [jname, vn] : pn.entries()) {
          const int j = d.findJoint(jname);
          const double v = vn.asDouble();
          if (j < 0) {
            if (coupledJoint(d, jname)) {  // a coupled mimic joint follows its master
              coupled_values.emplace_back(jname, v);
              continue;
            }
            const LockedJointDescription* l = lockedJoint(d, jname);
            if (!l) vn.fail("unknown joint '" + jname + "'");
            if (std::abs(v - l->value) > 1e-6) {  // a locked joint stays at its own value
              problems.warning(vn.where(), "joint '" + jname + "' is locked by the loader (" + l->reason + ") at " + fmt(l->value) +
                                               "; the posture's " + fmt(v) + " is not used");
            }
            continue;
          }
          const JointDescription& jd = d.joints[static_cast<size_t>(j)];
          if (v < jd.lower || v > jd.upper || std::abs(v) > ranges::kMaxJointLimit) {
            vn.fail("value " + fmt(v) + " is outside the joint limits [" + fmt(std::max(jd.lower, -ranges::kMaxJointLimit)) + ", " +
                    fmt(std::min(jd.upper, ranges::kMaxJointLimit)) + "]");
          }
          q[j] = v;
        }
        std::string missing;
        for (size_t j = 0; j < d.joints.size(); ++j) {
          if (std::isnan(q[static_cast<int>(j)])) missing += (missing.empty() ? "" : ", ") + d.joints[j].name;
        }
        if (!missing.empty()) pn.fail("posture '" + pname + "' does not give every joint; missing: " + missing);
        for (const auto& [cname, v] : coupled_values) {
          for (const auto& c : d.coupled_joints) {
            if (c.name != cname) continue;
            const double follows = c.multiplier * q[c.master] + c.offset;
            if (std::abs(v - follows) > 1e-6) {
              problems.warning(pn.where(),
                               "posture '" + pname + "': mimic joint '" + cname + "' at " + fmt(v) + " is not where its master puts it (" +
                                   fmt(c.multiplier) + " x " + d.joints[static_cast<size_t>(c.master)].name + " " + fmt(q[c.master]) +
                                   (c.offset != 0.0 ? " + " + fmt(c.offset) : "") + " = " + fmt(follows) + "): the master decides");
            }
          }
        }
        d.postures.emplace_back(pname, q);
      });
    }
  });
  attempt([&] { top.finish(); });
}

}  // namespace lexdyn::model::detail
