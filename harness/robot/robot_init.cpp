#include "harness/robot/robot_init.hpp"

#include "harness/cases/case_file.hpp"
#include "harness/robot/mesh.hpp"
#include "harness/robot/robot_layout.hpp"
#include "harness/robot/srdf.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/problems.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <unistd.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace lexdyn::robot {

namespace fs = std::filesystem;

namespace {

std::string num(double v, int digits = 6) {
  if (v == 0.0) return "0";
  return formatNumber(v, digits);
}

// A YAML scalar: plain when safe, single-quoted otherwise.
std::string yamlString(const std::string& s) {
  const bool plain = !s.empty() && s.find_first_of(":#{}[],&*!|>'\"%@`") == std::string::npos && s[0] != '-' && s[0] != '?' &&
                     s != "true" && s != "false" && s != "null" && s != "yes" && s != "no" && s != "on" && s != "off" &&
                     !(std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '.' || s[0] == '+');
  if (plain) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

std::string vec3(const Eigen::Vector3d& v, int digits = 6) {
  auto clean = [](double x) { return std::abs(x) < 1e-12 ? 0.0 : x; };
  return "[" + num(clean(v.x()), digits) + ", " + num(clean(v.y()), digits) + ", " + num(clean(v.z()), digits) + "]";
}

// URDF roll-pitch-yaw of a rotation (R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Vector3d rpyOf(const Eigen::Matrix3d& R) {
  const double pitch = std::atan2(-R(2, 0), std::sqrt(R(0, 0) * R(0, 0) + R(1, 0) * R(1, 0)));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return {roll, pitch, yaw};
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// Relative to from_dir when the two share a folder below the root (the files move together),
// absolute otherwise.
std::string relativePath(const std::string& target, const fs::path& from_dir) {
  std::error_code ec;
  const fs::path t = fs::weakly_canonical(fs::absolute(target), ec);
  const fs::path b = fs::weakly_canonical(fs::absolute(from_dir), ec);
  const auto first = [](const fs::path& p) { return std::next(p.begin()) == p.end() ? fs::path() : *std::next(p.begin()); };
  if (first(t).empty() || first(t) != first(b)) return t.string();
  return t.lexically_relative(b).string();
}

// A posture value as text: 6 significant digits, or all 17 when the rounded value would fall
// outside the joint's limits (a value clamped onto a limit).
std::string postureValue(double v, const model::JointDescription& J) {
  const std::string short_text = num(v);
  const double back = std::strtod(short_text.c_str(), nullptr);
  if (back >= J.lower && back <= J.upper) return short_text;
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

struct Posture {
  std::string name;
  Eigen::VectorXd q;
  std::string source;
  std::vector<std::string> clamped;  // joint: note
  int given = -1;                    // joints the SRDF state gives (-1: all, not from an SRDF)
};

// Every joint at 0; a joint whose range excludes 0 at 10 % of its range inside the nearer limit
// (a joint started at its limit is held there by the joint-limit task's damper: a quadruped's
// knee at its stop keeps the base from moving).
Posture neutralPosture(const model::RobotDescription& d) {
  Posture p;
  p.name = "neutral";
  p.q = Eigen::VectorXd::Zero(static_cast<int>(d.joints.size()));
  for (size_t j = 0; j < d.joints.size(); ++j) {
    const auto& J = d.joints[j];
    double v = 0.0;
    if (0.0 < J.lower || 0.0 > J.upper) {
      const double margin = std::isfinite(J.upper - J.lower) ? 0.1 * (J.upper - J.lower) : 0.0;
      v = 0.0 < J.lower ? J.lower + margin : J.upper - margin;
      p.clamped.push_back(J.name + ": 0 is outside [" + num(J.lower) + ", " + num(J.upper) + "], taken as " + num(v) +
                          " (10 % of its range inside the limit)");
    }
    p.q[static_cast<int>(j)] = v;
  }
  p.source = "every joint at 0 (the URDF's zero configuration), one whose range excludes 0 inside its limits";
  return p;
}

std::vector<Posture> srdfPostures(const model::RobotDescription& d, const Srdf& s) {
  std::vector<Posture> out;
  for (const auto& st : s.states) {
    Posture p = neutralPosture(d);
    p.name = st.name;
    std::string sanitized;
    for (char c : p.name) sanitized += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
    p.name = sanitized.empty() ? "srdf_state" : sanitized;
    p.clamped.clear();
    int given = 0;
    for (const auto& [joint, value] : st.values) {
      const int j = d.findJoint(joint);
      const auto& J = d.joints[static_cast<size_t>(j)];
      double v = value;
      if ((v < J.lower || v > J.upper) && J.type == model::JointType::Revolute && std::isfinite(v)) {
        // The same angle a turn away may be inside (an SRDF written for another range, e.g. [0, 2 pi]).
        const double two_pi = 2.0 * 3.14159265358979323846;
        const double w = v + two_pi * std::ceil((J.lower - v) / two_pi);
        if (w >= J.lower && w <= J.upper) {
          p.clamped.push_back(joint + ": " + num(v) + " is outside [" + num(J.lower) + ", " + num(J.upper) + "], taken as the same angle " +
                              num(w));
          v = w;
        }
      }
      if (v < J.lower || v > J.upper) {
        const double c = std::min(std::max(v, J.lower), J.upper);
        p.clamped.push_back(joint + ": " + num(v) + " is outside [" + num(J.lower) + ", " + num(J.upper) + "], clamped to " + num(c));
        v = c;
      }
      p.q[j] = v;
      ++given;
    }
    p.given = given;
    p.source = "the SRDF group state '" + st.name + "' (" + s.path + ":" + std::to_string(st.line) + ", " + std::to_string(given) + " of " +
               std::to_string(d.joints.size()) + " joints; the others at 0)";
    out.push_back(p);
  }
  return out;
}

const Posture& choosePosture(const std::vector<Posture>& ps, const std::string& wanted, const std::string& srdf) {
  if (!wanted.empty()) {
    std::string names;
    for (const auto& p : ps) {
      if (p.name == wanted) return p;
      names += (names.empty() ? "" : ", ") + p.name;
    }
    throw InputError("--posture", "no posture '" + wanted + "' (" + (srdf.empty() ? "without --srdf: " : "") + "postures: " + names + ")");
  }
  for (const char* pref : {"half_sitting", "standing", "stand", "ready", "default", "home", "neutral", "init", "initial"}) {
    for (const auto& p : ps) {
      if (lower(p.name) == pref) return p;
    }
  }
  return ps.front();
}

// A frame name not used by a link or frame of d, nor by `taken`.
std::string freeName(const model::RobotDescription& d, const std::vector<std::string>& taken, const std::string& want) {
  std::string n = want;
  for (int k = 2; d.findFrame(n) >= 0 || std::find(taken.begin(), taken.end(), n) != taken.end(); ++k) n = want + "_" + std::to_string(k);
  return n;
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw InputError(path.string(), std::string("cannot write: ") + std::strerror(errno));
}

// COLLADA files may declare another up axis than z. ROS's tools (RViz, MoveIt) take a mesh's
// coordinates as written whatever it declares, and most packages are written for them; some
// (exported for tools that turn the mesh) are right only turned. The links' own centres of mass
// decide: the interpretation that puts them nearer their meshes' centres, by a clear margin.
struct UpAxisChoice {
  bool apply = false;
  std::string line;  // the data file's line (empty: every mesh is z up)
  std::string note;  // for the summary
};

UpAxisChoice chooseMeshUpAxis(const model::RobotDescription& d, MeshCache& cache) {
  UpAxisChoice c;
  std::map<char, int> files;
  std::map<std::string, bool> seen;
  double sum_written = 0.0, sum_turned = 0.0;
  int compared = 0;
  for (const auto& g : d.geometries) {
    if (g.type != model::GeometryType::Mesh || g.mesh_path.empty()) continue;
    const Mesh* m = nullptr;
    try {
      m = &cache.get(g.mesh_path);
    } catch (const InputError&) {
      continue;  // said by the layout's reading
    }
    if (m->up_axis == 'Z' || m->vertices.empty()) continue;
    if (!seen[g.mesh_path]) {
      seen[g.mesh_path] = true;
      ++files[m->up_axis];
    }
    const model::LinkDescription& L = d.links[static_cast<size_t>(g.link)];
    if (g.urdf_link != L.name || !(L.mass > 0.0)) continue;  // a lumped link's own CoM is not kept
    Eigen::Vector3f lo = m->vertices.front(), hi = lo;
    for (const auto& v : m->vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    const Eigen::Vector3d centre = (0.5 * (lo + hi)).cast<double>();
    const Eigen::Matrix3d R = upAxisRotation(m->up_axis).cast<double>();
    sum_written += (g.placement * centre.cwiseProduct(g.scale) - L.com).norm();
    sum_turned += (g.placement * (R * centre).cwiseProduct(g.scale) - L.com).norm();
    ++compared;
  }
  if (files.empty()) return c;
  std::string declared;
  for (const auto& [axis, n] : files)
    declared += std::string(declared.empty() ? "" : ", ") + std::to_string(n) + " declare " + axis + "_UP";
  auto cm = [&](double sum) {
    char b[32];
    std::snprintf(b, sizeof(b), "%.1f cm", 100.0 * sum / compared);
    return std::string(b);
  };
  const std::string fit = compared == 0 ? std::string("no link with mass to compare")
                                        : "the links' centres of mass lie " + cm(sum_turned) +
                                              " on average from their meshes' centres with the up axis applied, " + cm(sum_written) +
                                              " as written (" + std::to_string(compared) + " meshes)";
  c.apply = compared > 0 && sum_turned < 0.5 * sum_written;
  c.note = "meshes: of the COLLADA files, " + declared + "; " + fit + ": " + (c.apply ? "turned to z up" : "taken as written");
  c.line = std::string("mesh_up_axis: ") + (c.apply ? "file" : "ignore") + "               # guessed: " + fit +
           (c.apply ? " (file: COLLADA meshes turned by their <up_axis>)" : " (ignore: as ROS's tools read them)") + "\n";
  return c;
}

struct Draft {
  std::string robot_file;  // file name of the data file
  std::string data, stand, reach, base, lift;
  std::vector<std::string> summary;
  std::vector<std::string> warnings;
};

// Contact stiffness for a static penetration of 1 mm under an even share of the weight on each
// contact point: k d^1.5 = m g / n.
double contactStiffness(double mass, int points) {
  const double share = mass * kGravity / std::max(points, 1);
  return std::clamp(share / std::pow(1e-3, 1.5), 1e3, 1e9);
}

Draft draft(const model::RobotDescription& d, const RobotLayout& L, const Posture& posture, const std::vector<Posture>& postures,
            const InitOptions& o, const fs::path& final_dir, const Srdf* srdf, const UpAxisChoice& up) {
  Draft out;
  out.robot_file = d.name + ".yaml";
  const std::string urdf_rel = relativePath(o.urdf, final_dir);
  const double dt = o.control_period_s;
  std::ostringstream y;
  y << "# " << d.name << ": the data file of " << urdf_rel << " (format: docs/model.md), drafted by\n"
    << "# `lexdyn-harness robot init`" << (srdf ? " with the SRDF " + relativePath(srdf->path, final_dir) : std::string(" (no SRDF)"))
    << ".\n"
    << "# Every value the URDF does not carry is a guess; the comment beside it says where it came from.\n"
    << "# Check it with `lexdyn-harness robot check " << out.robot_file << "` and correct what is wrong\n"
    << "# (docs/model.md, \"Bringing your own robot\").\n"
    << "format: lexdyn-robot-data/1\n"
    << "robot: " << yamlString(d.name) << "\n"
    << "urdf: " << yamlString(urdf_rel) << "              # the URDF this file describes (robot check reads it)\n"
    << "base: " << (d.base == model::BaseType::Fixed ? "fixed" : "free_flyer") << "                  # guessed: " << L.base_reason << "\n"
    << up.line;
  if (!o.package_paths.empty()) {
    y << "package_path: [";
    for (size_t k = 0; k < o.package_paths.size(); ++k) y << (k ? ", " : "") << yamlString(relativePath(o.package_paths[k], final_dir));
    y << "]   # folders for the URDF's package:// meshes (--package-path)\n";
  }
  if (!L.feet.empty()) {
    y << "friction_coefficient: 0.7          # guessed: rubber soles on a hard floor (HRP-2's walking controller uses 0.7)\n";
  }
  if (!d.mimics.empty() && o.mimic == "locked") {
    y << "mimic: {mode: locked, posture: " << yamlString(posture.name) << "}   # the URDF's " << d.mimics.size()
      << " <mimic> joint(s) held at their masters' value in this posture (--mimic locked); `{mode: coupled}` moves them\n";
  } else if (!d.mimics.empty()) {
    y << "mimic: {mode: coupled}             # the URDF's " << d.mimics.size()
      << " <mimic> joint(s) move with their masters; `{mode: locked, posture: P}` holds them at posture P instead\n";
  }
  // Frames: soles and grasp points.
  std::vector<std::string> taken;
  std::vector<std::string> sole_frames, grasp_frames;
  y << "frames:\n";
  for (const auto& f : L.feet) {
    std::string base = f.surface;
    if (base.size() > 5 && base.compare(base.size() - 5, 5, "_FOOT") == 0) base = base.substr(0, base.size() - 5);
    const std::string name = freeName(d, taken, base + "_SOLE");
    taken.push_back(name);
    sole_frames.push_back(name);
    y << "  # " << f.surface << ": z up in posture '" << posture.name << "', at the centre of its contact points.\n"
      << "  - {name: " << yamlString(name) << ", parent: " << yamlString(f.link) << ", xyz: " << vec3(f.sole_in_body.translation())
      << ", rpy: " << vec3(rpyOf(f.sole_in_body.linear())) << "}\n";
  }
  for (const auto& a : L.arms) {
    const std::string name = freeName(d, taken, a.side.empty() ? "GRASP" : a.side + "_GRASP");
    taken.push_back(name);
    grasp_frames.push_back(name);
    y << "  # guessed: " << a.source << "\n"
      << "  - {name: " << yamlString(name) << ", parent: " << yamlString(a.end_link) << ", xyz: " << vec3(a.grasp_in_body) << "}\n";
  }
  if (L.feet.empty() && L.arms.empty()) y << "  []\n";
  if (!L.feet.empty()) {
    y << "contact_surfaces:\n";
    for (size_t k = 0; k < L.feet.size(); ++k) {
      const auto& f = L.feet[k];
      y << "  # guessed: " << f.source << "\n"
        << "  - name: " << f.surface << "\n"
        << "    frame: " << yamlString(sole_frames[k]) << "\n";
      if (f.radius > 0.0) {
        // A ball foot: the sphere's centre above the point where it touches, and its radius.
        y << "    radius: " << num(f.radius, 5) << "   # a ball foot: the point is the sphere's centre (the simulator rolls it)\n"
          << "    points: [";
        for (size_t i = 0; i < f.points.size(); ++i) y << (i ? ", " : "") << vec3(f.points[i] + Eigen::Vector3d(0.0, 0.0, f.radius), 5);
      } else {
        y << "    points: [";
        for (size_t i = 0; i < f.points.size(); ++i) y << (i ? ", " : "") << vec3(f.points[i], 5);
      }
      y << "]\n";
    }
    y << "force_sensors:   # assumed: a 6-axis sensor at each sole (it reads the ground's wrench on the foot; the URDF declares none)\n";
    for (size_t k = 0; k < L.feet.size(); ++k) {
      y << "  - {name: " << L.feet[k].surface << "_SENSOR, frame: " << yamlString(sole_frames[k]) << "}\n";
    }
  }
  std::vector<std::string> unlimited;
  for (const auto& J : d.joints) {
    if (std::isinf(J.effort_limit)) unlimited.push_back(J.name);
  }
  if (!unlimited.empty()) {
    y << "# The URDF leaves the effort limit of " << unlimited.size() << " joint(s) unspecified (taken as unlimited: no torque\n"
      << "# limit). Give them here when known:\n# joint_limits:\n";
    for (size_t k = 0; k < unlimited.size() && k < 4; ++k) y << "#   " << unlimited[k] << ": {effort: ...}\n";
  }
  y << "# Servo gains, sized per joint (docs/model.md, \"Servo gains\"): kp = the load torque m g r for a 5 mrad\n"
    << "# static deflection (at least effort / 0.5 rad), kd = max(4 dt kp, 1.4 sqrt(kp I)), dt = " << num(dt) << " s.\n"
    << "servo_gains:\n";
  for (size_t j = 0; j < d.joints.size(); ++j) {
    const ServoGains g = sizeServo(d, L, static_cast<int>(j), dt);
    y << "  - {match: " << yamlString(d.joints[j].name) << ", kp: " << num(g.kp, 3) << ", kd: " << num(g.kd, 3) << "}   # " << g.source
      << "\n";
  }
  y << "postures:\n";
  std::vector<const Posture*> written{&posture};
  for (const auto& p : postures) {
    if (p.name != posture.name) written.push_back(&p);
  }
  for (const Posture* p : written) {
    y << "  " << yamlString(p->name) << ":   # " << p->source << "\n";
    for (size_t j = 0; j < d.joints.size(); ++j) {
      y << "    " << yamlString(d.joints[j].name) << ": " << postureValue(p->q[static_cast<int>(j)], d.joints[j]);
      for (const auto& c : p->clamped) {
        if (c.compare(0, d.joints[j].name.size() + 1, d.joints[j].name + ":") == 0) y << "   # " << c.substr(d.joints[j].name.size() + 2);
      }
      y << "\n";
    }
  }
  out.data = y.str();

  // Cases.
  const std::string root = d.links[0].name;
  auto robotSection = [&]() {
    std::ostringstream r;
    r << "robot:\n  urdf: " << yamlString(urdf_rel) << "\n  data: " << yamlString(out.robot_file) << "\n";
    if (!o.package_paths.empty()) {
      r << "  package_path: [";
      for (size_t k = 0; k < o.package_paths.size(); ++k) r << (k ? ", " : "") << yamlString(relativePath(o.package_paths[k], final_dir));
      r << "]\n";
    }
    if (o.strict) r << "  strict: true\n";
    return r.str();
  };
  int points = 0;
  for (const auto& f : L.feet) points += static_cast<int>(f.points.size());
  const double k_contact = contactStiffness(L.mass, points);
  auto simSection = [&](double dissipation) {
    std::ostringstream s;
    s << "sim:\n";
    s << "  contact:";
    if (points > 0) {
      s << "\n    stiffness: " << num(k_contact, 2)
        << "              # sized: 1 mm of static penetration under an even share of the weight on each of the " << points
        << " contact points\n";
    } else {
      s << "                          # (the robot has no contact points: nothing touches the ground)\n    stiffness: " << num(k_contact, 2)
        << "\n";
    }
    s << "    exponent: 1.5\n"
      << "    dissipation_s_per_m: " << num(dissipation) << "\n"
      << "    slip_velocity_m_per_s: 1.0e-3\n"
      << "  servo:\n"
      << "    setpoint_profile: hermite\n"
      << "    # gains: the data file's servo_gains\n"
      << "  integrator: {rtol: 1.0e-4, atol_position: 1.0e-6, atol_velocity: 1.0e-4}\n";
    return s.str();
  };
  std::string surfaces;
  for (const auto& f : L.feet) surfaces += (surfaces.empty() ? "" : ", ") + f.surface;
  {
    std::ostringstream c;
    c << "# " << d.name << " holds posture '" << posture.name << "' for 10 s under its joint servos alone (no balance\n"
      << "# control), drafted by `lexdyn-harness robot init`: a first check of the model, its servo gains and\n"
      << "# (legged robots) its soles. "
      << (L.feet.empty() ? "" : "It starts in static equilibrium on its feet (docs/simulator.md, \"Initial state\").\n# ")
      << "Run: lexdyn-harness run stand.yaml --out out/stand\n"
      << "name: " << yamlString(d.name + "_stand") << "\n"
      << "description: " << yamlString(d.name + " holds its posture for 10 s by its joint servos alone.") << "\n"
      << robotSection() << "duration_s: 10.0\ncontrol_period_s: " << num(dt) << "\n"
      << "initial_state:\n  posture: " << yamlString(posture.name) << "\n  settle: " << (L.feet.empty() ? "none" : "static_equilibrium")
      << "\n"
      << "controller:\n  type: posture_servo\n  posture: " << yamlString(posture.name) << "\n"
      << simSection(5.0) << "trace:\n  frames: [" << yamlString(root);
    for (const auto& s : sole_frames) c << ", " << yamlString(s);
    for (const auto& g : grasp_frames) c << ", " << yamlString(g);
    c << "]\nchecks:\n";
    if (!L.feet.empty()) {
      c << "  # The base stays where the equilibrium put it, the feet carry the weight and do not slip.\n"
        << "  - {name: base_drift, type: frame_drift, frame: " << yamlString(root) << ", limit_m: 0.002}\n"
        << "  - {name: vertical_force_balance, type: force_balance, surfaces: [" << surfaces << "], limit_rel: 0.01}\n"
        << "  - {name: foot_slip, type: contact_slip, surfaces: [" << surfaces << "], limit_m: 0.0005}\n";
    } else {
      const std::string f = grasp_frames.empty() ? d.frames.back().name : grasp_frames[0];
      c << "  # The arm holds its posture: the end of the arm drifts by less than 2 mm under gravity.\n"
        << "  - {name: hand_drift, type: frame_drift, frame: " << yamlString(f) << ", from_s: 1.0, limit_m: 0.002}\n";
    }
    out.stand = c.str();
  }

  // Reach: the two hands of a legged robot (as exp1), or the hand(s) of a fixed-base robot (one
  // arm, or two as on a dual-arm torso).
  const bool humanoid = L.legged && L.arms.size() == 2 && L.feet.size() == 2;
  const bool arm = !L.legged && d.base == model::BaseType::Fixed && (L.arms.size() == 1 || L.arms.size() == 2);
  if (humanoid || arm) {
    std::ostringstream c;
    std::vector<std::string> hand_tasks;
    std::vector<Eigen::Vector3d> in_reach, out_of_reach;
    // The layout has the base at the origin; the simulated robot stands on the ground z = 0 (a
    // fixed base stays where it is).
    const Eigen::Vector3d ground = humanoid ? Eigen::Vector3d(0.0, 0.0, L.lowest_z) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d fwd = L.forward, left = Eigen::Vector3d::UnitZ().cross(L.forward), up = Eigen::Vector3d::UnitZ();
    for (size_t k = 0; k < L.arms.size(); ++k) {
      ArmLayout a = L.arms[k];
      a.shoulder -= ground;
      const double s = a.side == "LEFT" ? 1.0 : -1.0;
      const double R = a.reach;
      if (humanoid) {
        // exp1's targets relative to HRP-2's shoulders and 0.75 m reach: [0.4, +-0.5, 1.3] m is
        // (0.53, +-0.33, -0.04) reaches from the shoulder; [0.4, -+2, 2] m is out of reach.
        in_reach.push_back(a.shoulder + R * (0.53 * fwd + s * 0.33 * left - 0.04 * up));
        out_of_reach.push_back(a.shoulder + R * (0.53 * fwd + s * 2.33 * left + 0.9 * up));
      } else if (a.side.empty()) {
        in_reach.push_back(a.shoulder + 0.6 * R * (0.8 * fwd + 0.3 * left + 0.52 * up).normalized());
        out_of_reach.push_back(a.shoulder + 2.0 * R * (0.6 * fwd - 0.5 * left + 0.62 * up).normalized());
      } else {
        // One of two arms: in front and to its own side, then out of reach outwards (the hands
        // do not cross).
        in_reach.push_back(a.shoulder + 0.6 * R * (0.8 * fwd + s * 0.3 * left + 0.52 * up).normalized());
        out_of_reach.push_back(a.shoulder + 2.0 * R * (0.6 * fwd + s * 0.5 * left + 0.62 * up).normalized());
      }
      hand_tasks.push_back(a.side.empty() ? "hand" : lower(a.side) + "_hand");
    }
    // exp1 holds the in-reach targets for 30 s and the out-of-reach ones for 90 s; the draft 20 s
    // and 40 s, the hands' convergence judged over its last 10 s.
    const double switch_s = 20.0, duration = 60.0;
    c << "# " << d.name << ": the " << (L.arms.size() == 2 ? "hands reach" : "hand reaches") << " targets inside the arm's reach, then (at "
      << num(switch_s) << " s) targets out of\n# reach" << (humanoid ? ", as in the paper's experiment 1 (cases/exp1.yaml)" : "")
      << "; drafted by `lexdyn-harness robot init`. The targets are placed from\n"
      << "# the arms' geometry; every method of the case runs it (--method bfgs | ah | gn | wls).\n"
      << "# Run: lexdyn-harness run reach.yaml --out out/reach --method bfgs\n"
      << "name: " << yamlString(d.name + "_reach") << "\n"
      << "description: "
      << yamlString(std::string(humanoid             ? "Two-foot stance; hands"
                                : L.arms.size() == 2 ? "Fixed base; the hands"
                                                     : "Fixed base; the hand") +
                    " to targets within reach, then out of reach.")
      << "\n"
      << robotSection() << "duration_s: " << num(duration) << "\ncontrol_period_s: " << num(dt) << "\n"
      << "initial_state:\n  posture: " << yamlString(posture.name) << "\n  settle: " << (humanoid ? "static_equilibrium" : "none") << "\n\n"
      << "controller:\n  type: lexdyn\n  method: bfgs                       # --method overrides it\n  feedforward_torque: true\n"
      << "  state_feedback: integrated\n"
      << "  params: {nu_dt2: 1.0e-12, xi_dt2: 1.0e-12, zeta_dt2: 1.0e-3, rho_dt2: 1.0e-12, eps_dt2: 1.0e-3, newton_identity_weight: 1.0e-4"
      << (humanoid ? ", stop_after_level: contacts}" : "}") << "\n";
    if (humanoid) {
      // The default margins (exp1's scaled to the soles and the weight: cases::defaultContactMargins),
      // written out so that the draft shows them: the narrowest sole's CoP margin and the foot with
      // the most points' minimum force per point.
      double cop = std::numeric_limits<double>::infinity(), fmin_point = std::numeric_limits<double>::infinity();
      for (const auto& f : L.feet) {
        const tasks::ContactMargins fm = cases::defaultContactMargins(f.points, f.points.size() == 1, L.mass * kGravity);
        if (f.points.size() >= 3) cop = std::min(cop, fm.cop_m);
        fmin_point = std::min(fmin_point, fm.min_normal_N);
      }
      if (!std::isfinite(cop)) cop = 0.0;
      if (!std::isfinite(fmin_point)) fmin_point = 0.0;
      c << "  contact_margins: {friction: 0.1, cop_m: " << num(cop, 3) << ", min_normal_N: " << num(fmin_point, 3)
        << "}   # exp1's, scaled to these soles and this weight (docs/results.md)\n";
      c << "  method_params:\n    wls: {stop_after_level: hard}\n";
    }
    c << "  solver:\n    paper_rules: true\n";
    if (humanoid) {
      c << "  contacts:\n";
      for (const auto& f : L.feet)
        c << "    - {name: " << f.surface << ", surface: " << f.surface << ", sensor: " << f.surface << "_SENSOR}\n";
      c << "  initial_contacts: [" << surfaces << "]\n";
    }
    c << "  tasks:\n"
      << "    - {name: joint_limits, type: joint_limits}\n";
    if (humanoid) c << "    - {name: force_bounds, type: contact_force_bounds}\n";
    c << "    - {name: dynamics, type: equation_of_motion}\n"
      << "    - {name: torque_limits, type: torque_limits}\n"
      << "    - {name: trust, type: trust_region, delta: 0.01}\n";
    std::vector<std::string> contact_tasks;
    if (humanoid) {
      for (const auto& f : L.feet) {
        contact_tasks.push_back(lower(f.surface));
        c << "    - {name: " << lower(f.surface) << ", type: contact, contact: " << f.surface << "}\n";
      }
      // The CoM box of exp1 relative to the support: +-28 % of the soles' half length, +-34 % of
      // the half width, about the CoM of the posture.
      const std::vector<Eigen::Vector2d> poly = supportPolygon(L);
      Eigen::Vector2d lo = poly.empty() ? Eigen::Vector2d::Zero() : poly[0], hi = lo;
      for (const auto& p : poly) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      const Eigen::Vector2d half = 0.5 * (hi - lo);
      const Eigen::Vector2d box(std::max(0.005, 0.28 * half.x()), std::max(0.005, 0.34 * half.y()));
      const Eigen::Vector2d c0 = L.com.head<2>();
      // Each face at least 1.5 times the box's half extent inside the support's edge (a posture
      // whose CoM sits near a heel would otherwise put the face near that edge, and the plan, held
      // there, rolls or folds the robot), but never nearer the posture's CoM than a quarter of it.
      Eigen::Vector2d box_lo = c0 - box, box_hi = c0 + box;
      for (int i = 0; i < 2; ++i) {
        box_lo[i] = std::max(box_lo[i], std::min(lo[i] + 1.5 * box[i], c0[i] - 0.25 * box[i]));
        box_hi[i] = std::min(box_hi[i], std::max(hi[i] - 1.5 * box[i], c0[i] + 0.25 * box[i]));
      }
      c << "    # exp1's CoM box (+-0.03 x +-0.06 m on HRP-2's 0.22 x 0.35 m support) scaled to this support: +-28 % of its half length,\n"
        << "    # +-34 % of its half width, about the posture's centre of mass, each face at least 1.5 times that inside the support's "
           "edge.\n"
        << "    - {name: com_box, type: com_box, lower: [" << num(box_lo.x(), 4) << ", " << num(box_lo.y(), 4) << ", -.inf], upper: ["
        << num(box_hi.x(), 4) << ", " << num(box_hi.y(), 4) << ", .inf]}\n";
    }
    for (size_t k = 0; k < L.arms.size(); ++k) {
      c << "    - {name: " << hand_tasks[k] << ", type: position, frame: " << yamlString(grasp_frames[k])
        << ", target: " << vec3(in_reach[k], 4) << ", gains: {kp: 0.3}}   # "
        << num((in_reach[k] - (L.arms[k].shoulder - ground)).norm() / L.arms[k].reach * 100.0, 3) << " % of the reach ("
        << num(L.arms[k].reach, 3) << " m) from the shoulder\n";
    }
    c << "    - {name: velocity, type: velocity_min}\n";
    if (humanoid) c << "    - {name: wrench, type: wrench_min}\n";
    c << "    - {name: posture, type: posture, posture: " << yamlString(posture.name) << "}     # WLS only\n";
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
      return s;
    };
    c << "  levels:\n"
      << "    - {name: bounds, tasks: [joint_limits" << (humanoid ? ", force_bounds" : "") << "]}\n"
      << "    - {name: dynamics, tasks: [dynamics, torque_limits]}\n"
      << "    - {name: trust, tasks: [trust]}\n";
    if (humanoid) c << "    - {name: contacts, tasks: [" << list(contact_tasks) << "]}\n    - {name: com, tasks: [com_box]}\n";
    c << "    - {name: hands, tasks: [" << list(hand_tasks) << "]}\n"
      << "    - {name: velocity, tasks: [velocity]}\n";
    if (humanoid) c << "    - {name: wrench, tasks: [wrench]}\n";
    c << "  wls_levels:\n"
      << "    - {name: hard, tasks: [joint_limits" << (humanoid ? ", force_bounds" : "") << ", dynamics, torque_limits"
      << (humanoid ? ", " + list(contact_tasks) + ", com_box" : std::string()) << "]}\n"
      << "    - name: objective\n      tasks: [" << list(hand_tasks) << ", posture" << (humanoid ? ", wrench" : "")
      << "]\n      weights: {";
    for (const auto& h : hand_tasks) c << h << ": 1.0, ";
    c << "posture: 1.0e-3" << (humanoid ? ", wrench: 1.0e-5" : "") << "}\n\n";
    c << simSection(humanoid ? 50.0 : 5.0) << "\nevents:\n";
    for (size_t k = 0; k < L.arms.size(); ++k) {
      c << "  - {at_s: " << num(switch_s) << ", action: set_target, task: " << hand_tasks[k] << ", value: " << vec3(out_of_reach[k], 4)
        << "}   # out of reach\n";
    }
    // The top of the trunk: the body not part of an arm whose centre of mass is highest in the
    // posture (the head, the chest); a robot folding forward at the hip lowers it long before its
    // base. The check is on its origin, at 80 % of the origin's height in the posture.
    std::string top;
    double top_z = -1e9, top_origin_z = 0.0;
    if (humanoid) {
      std::vector<bool> in_arm(d.links.size(), false);
      for (const auto& a : L.arms) in_arm[static_cast<size_t>(d.joints[static_cast<size_t>(a.first_joint)].child_link)] = true;
      for (size_t b = 1; b < d.links.size(); ++b) {
        if (in_arm[static_cast<size_t>(d.parentBody(static_cast<int>(b)))]) in_arm[b] = true;
      }
      for (size_t b = 0; b < d.links.size(); ++b) {
        if (!(d.links[b].mass > 0.0)) continue;
        const double z = (L.body_pose[b] * d.links[b].com).z();  // its centre of mass's height
        if (!in_arm[b] && z > top_z + 1e-9) {
          top_z = z;
          top = d.links[b].name;
          top_origin_z = L.body_pose[b].translation().z();
        }
      }
      if (top == root) top.clear();
    }
    c << "\ntrace:\n  every_n_ticks: 1\n  frames: [" << yamlString(root);
    if (!top.empty()) c << ", " << yamlString(top);
    for (const auto& g : grasp_frames) c << ", " << yamlString(g);
    c << "]\n\nchecks:\n"
      << "  # Each hand reaches its target within reach (1 cm) before the targets move out of reach at " << num(switch_s) << " s.\n";
    for (const auto& h : hand_tasks) {
      c << "  - {name: " << h << "_reached, type: task_error, tasks: [" << h << "], statistic: max, from_s: " << num(switch_s - 5.0)
        << ", to_s: " << num(switch_s - 0.01) << ", limit: 0.01}\n";
    }
    c << "  - {name: hands_settled, type: task_error, tasks: [" << list(hand_tasks)
      << "], statistic: range, from_s: " << num(duration - 10.0) << ", limit: 0.005}\n";
    if (humanoid) {
      c << "  - {name: feet_held, type: task_error, tasks: [" << list(contact_tasks) << "], statistic: max, from_s: 0.1, limit: 0.001}\n"
        << "  - {name: upright, type: frame_height, frame: " << yamlString(root)
        << ", min_m: " << num(0.5 * (L.body_pose[0].translation().z() - L.lowest_z), 3) << "}   # half the base's height in the posture\n";
      if (!top.empty()) {
        c << "  - {name: trunk_up, type: frame_height, frame: " << yamlString(top)
          << ", min_m: " << num(0.8 * (top_origin_z - L.lowest_z), 3) << "}   # 80 % of the height of '" << top
          << "' in the posture: the trunk does not fold\n";
      }
    }
    c << "  - {name: torques, type: torque_limits, source: both, limit_fraction: 1.0}\n";
    if (humanoid) {
      for (const auto& f : L.feet) {
        const std::string n = lower(f.surface);
        c << "  - {name: " << n << "_unilateral, type: contact_unilateral, contact: " << f.surface << ", source: sensed, min_N: 0.0}\n"
          << "  - {name: " << n << "_friction, type: contact_friction, contact: " << f.surface
          << ", source: sensed, min_normal_N: " << num(std::max(1.0, 0.015 * L.mass * kGravity), 2) << "}\n";
        if (f.points.size() >= 3) {
          c << "  - {name: " << n << "_cop, type: contact_cop, contact: " << f.surface
            << ", source: sensed, min_normal_N: " << num(std::max(1.0, 0.015 * L.mass * kGravity), 2) << ", limit_m: -0.001}\n";
        }
      }
    }
    c << "  - {name: joint_accel_sign_changes, type: joint_acceleration_sign_changes, source: commanded, dead_band_rad_per_s2: 0.05, "
         "limit_per_s: 5.0}\n"
      << "  - {name: joint_velocity_hf, type: joint_velocity_hf_energy, source: measured, cutoff_hz: 5.0, limit_rad2_per_s2: 0.1}\n"
      << "  - {name: controller_ok, type: controller_status, allowed: [ok, solver_stopped_early], limit_count: 0}\n"
      << "  - {name: active_set_peak, type: active_set_peak, limit_iterations: 50}\n"
      << "  - {name: tick_time_p99, type: tick_time, timer: tick, percentile: 99, limit_us: 5000}\n";
    out.reach = c.str();
  }

  // Base: a legged robot without the two arms of a reach (a quadruped, a hexapod) moves its base
  // on its feet: to a target within reach (lower, forward and to the side), tilted, then to one
  // out of reach (its height higher). A robot on four feet also lifts one foot and puts it back
  // (lift_foot.yaml): its base first moves over the other three.
  if (L.legged && d.base == model::BaseType::FreeFlyer && !humanoid && L.feet.size() >= 2) {
    const double h = L.body_pose[0].translation().z() - L.lowest_z;  // the base's height above the ground
    const Eigen::Vector3d fwd = L.forward, left = Eigen::Vector3d::UnitZ().cross(L.forward);
    const Eigen::Vector3d start(0.0, 0.0, h);
    std::vector<std::string> contact_tasks;
    for (const auto& f : L.feet) contact_tasks.push_back(lower(f.surface));
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
      return s;
    };
    const double fmin = std::max(1.0, 0.015 * L.mass * kGravity);
    // The controller (exp1's parameters and levels, the feet as contacts, the base's position
    // and attitude), with `extra_task` (a task line) on a level of its own below the base's.
    auto controller = [&](std::ostream& c, const Eigen::Vector3d& base_target, const std::string& extra_task,
                          const std::string& extra_name) {
      c << "controller:\n  type: lexdyn\n  method: bfgs                       # --method overrides it\n  feedforward_torque: true\n"
        << "  state_feedback: integrated\n"
        << "  params: {nu_dt2: 1.0e-12, xi_dt2: 1.0e-12, zeta_dt2: 1.0e-3, rho_dt2: 1.0e-12, eps_dt2: 1.0e-3, newton_identity_weight: "
           "1.0e-4, "
           "stop_after_level: contacts}\n"
        << "  method_params:\n    wls: {stop_after_level: hard}\n"
        << "  solver:\n    paper_rules: true\n"
        << "  contacts:   # a foot of one point is a point contact (3 rows: its position; docs/controller.md)\n";
      for (const auto& f : L.feet)
        c << "    - {name: " << f.surface << ", surface: " << f.surface << ", sensor: " << f.surface << "_SENSOR}\n";
      c << "  initial_contacts: [" << surfaces << "]\n"
        << "  tasks:\n"
        << "    - {name: joint_limits, type: joint_limits}\n"
        << "    - {name: force_bounds, type: contact_force_bounds}\n"
        << "    - {name: dynamics, type: equation_of_motion}\n"
        << "    - {name: torque_limits, type: torque_limits}\n"
        << "    - {name: trust, type: trust_region, delta: 0.01}\n";
      for (const auto& f : L.feet) c << "    - {name: " << lower(f.surface) << ", type: contact, contact: " << f.surface << "}\n";
      c << "    - {name: base_position, type: position, frame: " << yamlString(root) << ", target: " << vec3(base_target, 4)
        << ", gains: {kp: 1.0}}   # from " << vec3(start, 4) << " (the posture's base " << num(h, 3) << " m above the ground)\n"
        << "    - {name: base_orientation, type: orientation, frame: " << yamlString(root)
        << ", gains: {kp: 1.0}}   # holds the start's attitude\n"
        << extra_task << "    - {name: velocity, type: velocity_min}\n"
        << "    - {name: wrench, type: wrench_min}\n"
        << "    - {name: posture, type: posture, posture: " << yamlString(posture.name) << "}     # WLS only\n"
        << "  levels:\n"
        << "    - {name: bounds, tasks: [joint_limits, force_bounds]}\n"
        << "    - {name: dynamics, tasks: [dynamics, torque_limits]}\n"
        << "    - {name: trust, tasks: [trust]}\n"
        << "    - {name: contacts, tasks: [" << list(contact_tasks) << "]}\n"
        << "    - {name: base, tasks: [base_position, base_orientation]}\n";
      if (!extra_name.empty()) c << "    - {name: " << extra_name << ", tasks: [" << extra_name << "]}\n";
      c << "    - {name: velocity, tasks: [velocity]}\n"
        << "    - {name: wrench, tasks: [wrench]}\n"
        << "  wls_levels:\n"
        << "    - {name: hard, tasks: [joint_limits, force_bounds, dynamics, torque_limits, " << list(contact_tasks) << "]}\n"
        << "    - name: objective\n      tasks: [base_position, base_orientation, " << (extra_name.empty() ? "" : extra_name + ", ")
        << "posture, wrench]\n"
        << "      weights: {base_position: 1.0, base_orientation: 1.0, " << (extra_name.empty() ? "" : extra_name + ": 1.0, ")
        << "posture: 1.0e-3, wrench: 1.0e-5}\n\n";
    };
    // The checks every legged case shares: feet, posture, forces, oscillations, solver.
    auto commonChecks = [&](std::ostream& c) {
      c << "  - {name: feet_held, type: task_error, tasks: [" << list(contact_tasks) << "], statistic: max, from_s: 0.1, limit: 0.001}\n"
        << "  - {name: upright, type: frame_height, frame: " << yamlString(root) << ", min_m: " << num(0.5 * h, 3)
        << "}   # half the base's height in the posture\n"
        << "  - {name: torques, type: torque_limits, source: both, limit_fraction: 1.0}\n";
      for (const auto& f : L.feet) {
        const std::string n = lower(f.surface);
        c << "  - {name: " << n << "_unilateral, type: contact_unilateral, contact: " << f.surface << ", source: sensed, min_N: 0.0}\n"
          << "  - {name: " << n << "_friction, type: contact_friction, contact: " << f.surface
          << ", source: sensed, min_normal_N: " << num(fmin, 2) << "}\n";
        if (f.points.size() >= 3) {
          c << "  - {name: " << n << "_cop, type: contact_cop, contact: " << f.surface << ", source: sensed, min_normal_N: " << num(fmin, 2)
            << ", limit_m: -0.001}\n";
        }
      }
      c << "  - {name: joint_accel_sign_changes, type: joint_acceleration_sign_changes, source: commanded, dead_band_rad_per_s2: 0.05, "
           "limit_per_s: 5.0}\n"
        << "  - {name: joint_velocity_hf, type: joint_velocity_hf_energy, source: measured, cutoff_hz: 5.0, limit_rad2_per_s2: 0.1}\n"
        << "  - {name: controller_ok, type: controller_status, allowed: [ok, solver_stopped_early], limit_count: 0}\n"
        << "  - {name: active_set_peak, type: active_set_peak, limit_iterations: 50}\n"
        << "  - {name: tick_time_p99, type: tick_time, timer: tick, percentile: 99, limit_us: 5000}\n";
    };
    {
      std::ostringstream c;
      const Eigen::Vector3d in_reach = start + h * (0.1 * fwd + 0.05 * left - 0.1 * Eigen::Vector3d::UnitZ());
      const Eigen::Vector3d out_of_reach = start + Eigen::Vector3d(0.0, 0.0, h);
      // Tilted: pitched nose-down by 0.1 rad about the robot's left axis, as a body turns to look down.
      const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.1, left).toRotationMatrix() * L.body_pose[0].linear();
      // kp 1 (kv 2): 6 s after a step the error is 1.7 % of it.
      const double move_s = 6.0, tilt_s = 8.0, switch_s = 20.0, duration = 40.0;
      auto rot9 = [](const Eigen::Matrix3d& R) {
        std::string s = "[";
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) s += std::string(i || j ? ", " : "") + num(std::abs(R(i, j)) < 1e-12 ? 0.0 : R(i, j), 6);
        return s + "]";
      };
      c << "# " << d.name << ": the base moves on the feet to a target within reach (by 10 % of its height lower, forward\n"
        << "# and to the side), at " << num(tilt_s) << " s it tilts nose-down by 0.1 rad, at " << num(switch_s)
        << " s its target moves out of reach (its height\n# above the ground higher); drafted by `lexdyn-harness robot init`. "
        << "Every method runs it (--method bfgs | ah | gn | wls).\n"
        << "# Run: lexdyn-harness run base.yaml --out out/base --method bfgs\n"
        << "name: " << yamlString(d.name + "_base") << "\n"
        << "description: "
        << yamlString("On " + std::to_string(L.feet.size()) + " feet; the base to a target within reach, tilted, then out of reach.")
        << "\n"
        << robotSection() << "duration_s: " << num(duration) << "\ncontrol_period_s: " << num(dt) << "\n"
        << "initial_state:\n  posture: " << yamlString(posture.name) << "\n  settle: static_equilibrium\n\n";
      controller(c, in_reach, "", "");
      c << simSection(5.0) << "\nevents:\n"
        << "  - {at_s: " << num(tilt_s) << ", action: set_target, task: base_orientation, value: " << rot9(tilt)
        << "}   # 0.1 rad nose-down\n"
        << "  - {at_s: " << num(switch_s) << ", action: set_target, task: base_position, value: " << vec3(out_of_reach, 4)
        << "}   # out of reach\n"
        << "\ntrace:\n  every_n_ticks: 1\n  frames: [" << yamlString(root) << "]\n\nchecks:\n"
        << "  # The base reaches its target (5 mm) before it tilts, then its tilt (0.01 rad) before the switch.\n"
        << "  - {name: base_reached, type: task_error, tasks: [base_position], statistic: max, from_s: " << num(move_s)
        << ", to_s: " << num(tilt_s - 0.01) << ", limit: 0.005}\n"
        << "  - {name: base_tilted, type: task_error, tasks: [base_orientation], statistic: max, from_s: " << num(tilt_s + 6.0)
        << ", to_s: " << num(switch_s - 0.01) << ", limit: 0.01}\n"
        << "  - {name: base_settled, type: task_error, tasks: [base_position], statistic: range, from_s: " << num(duration - 10.0)
        << ", limit: 0.005}\n";
      commonChecks(c);
      out.base = c.str();
    }
    if (L.feet.size() == 4) {
      // Lift the first foot: the base over the centroid of the other three, then the foot up by
      // 15 % of the base's height and down again 1 mm into the ground, then the contact again.
      const auto& lifted = L.feet[0];
      Eigen::Vector2d others = Eigen::Vector2d::Zero();
      for (size_t k = 1; k < 4; ++k) others += L.feet[k].points_world[0].head<2>() / 3.0;
      // The base carries the centre of mass with it: moved by the centroid of the other three
      // less the CoM, it puts the CoM over that centroid.
      const Eigen::Vector3d shifted = start + Eigen::Vector3d(others.x() - L.com.x(), others.y() - L.com.y(), 0.0);
      Eigen::Vector3d foot = Eigen::Vector3d::Zero();
      for (const auto& p : lifted.points_world) foot += p / static_cast<double>(lifted.points_world.size());
      foot.z() -= L.lowest_z;  // on the ground
      const Eigen::Vector3d up = foot + Eigen::Vector3d(0.0, 0.0, 0.15 * h), down = foot - Eigen::Vector3d(0.0, 0.0, 0.001);
      // kp 1 (kv 2): 6 s after a step the error is 1.7 % of it.
      const double off_s = 8.0, down_s = 16.0, on_s = 24.0, duration = 36.0;
      const std::string task = lower(lifted.surface) + "_lift";
      const std::string sole = sole_frames[0];
      std::ostringstream c;
      c << "# " << d.name << ": the base moves over the other three feet (to their centroid), at " << num(off_s) << " s foot "
        << lifted.surface << " leaves the\n# ground and rises by 15 % of the base's height, at " << num(down_s)
        << " s it goes back down, at " << num(on_s)
        << " s it is a contact again and the base\n# returns; drafted by `lexdyn-harness robot init`. Every method runs it "
        << "(--method bfgs | ah | gn | wls).\n"
        << "# Run: lexdyn-harness run lift_foot.yaml --out out/lift_foot --method bfgs\n"
        << "name: " << yamlString(d.name + "_lift_foot") << "\n"
        << "description: " << yamlString("On four feet; one foot lifted and put back.") << "\n"
        << robotSection() << "duration_s: " << num(duration) << "\ncontrol_period_s: " << num(dt) << "\n"
        << "initial_state:\n  posture: " << yamlString(posture.name) << "\n  settle: static_equilibrium\n\n";
      controller(c, shifted,
                 "    - {name: " + task + ", type: position, frame: " + yamlString(sole) +
                     ", gains: {kp: 1.0}}   # holds the foot, then lifts it\n",
                 task);
      c << simSection(5.0) << "\nevents:\n"
        << "  - {at_s: " << num(off_s) << ", action: remove_contact, contact: " << lifted.surface << "}\n"
        << "  - {at_s: " << num(off_s) << ", action: set_target, task: " << task << ", value: " << vec3(up, 4) << "}   # up\n"
        << "  - {at_s: " << num(down_s) << ", action: set_target, task: " << task << ", value: " << vec3(down, 4)
        << "}   # down, 1 mm into the ground\n"
        << "  - {at_s: " << num(on_s) << ", action: add_contact, contact: " << lifted.surface << "}\n"
        << "  - {at_s: " << num(on_s) << ", action: set_target, task: base_position, value: " << vec3(start, 4) << "}   # back\n"
        << "\ntrace:\n  every_n_ticks: 1\n  frames: [" << yamlString(root) << ", " << yamlString(sole) << "]\n\nchecks:\n"
        << "  # The base is over the other feet (5 mm) before the foot leaves; the foot reaches its height\n"
        << "  # (5 mm), then the ground (3 mm); the put-back foot carries load again.\n"
        << "  - {name: base_shifted, type: task_error, tasks: [base_position], statistic: max, from_s: " << num(off_s - 1.0)
        << ", to_s: " << num(off_s - 0.01) << ", limit: 0.005}\n"
        << "  - {name: foot_lifted, type: task_error, tasks: [" << task << "], statistic: max, from_s: " << num(off_s + 6.0)
        << ", to_s: " << num(down_s - 0.01) << ", limit: 0.005}\n"
        << "  - {name: foot_down, type: task_error, tasks: [" << task << "], statistic: max, from_s: " << num(down_s + 6.0)
        << ", to_s: " << num(on_s - 0.01) << ", limit: 0.003}\n"
        << "  - {name: " << lower(lifted.surface) << "_reloaded, type: contact_unilateral, contact: " << lifted.surface
        << ", source: sensed, from_s: " << num(on_s + 6.0) << ", min_N: " << num(fmin, 2)
        << "}   # loaded: 1.5 % of the weight, the friction checks' threshold\n";
      commonChecks(c);
      out.lift = c.str();
    }
  }
  out.summary.push_back("base: " + std::string(d.base == model::BaseType::Fixed ? "fixed" : "free_flyer") + " (" + L.base_reason + ")");
  out.summary.push_back("mass " + num(L.mass, 4) + " kg, height " + num(L.height, 3) + " m in posture '" + posture.name + "' (" +
                        posture.source + ")");
  for (const auto& f : L.feet) {
    out.summary.push_back("foot " + f.surface + " on link '" + f.link + "': " + std::to_string(f.points.size()) +
                          " contact point(s) from " + f.source);
  }
  for (const auto& a : L.arms) {
    out.summary.push_back("arm " + (a.side.empty() ? std::string("(single)") : a.side) + ": hand link '" + a.end_link + "', reach " +
                          num(a.reach, 3) + " m");
  }
  if (!L.feet.empty()) {
    // The centre of mass over the support: the stand tips when it is outside, and a small margin
    // leaves the servos' deflection and the contacts' compliance little room.
    const std::vector<Eigen::Vector2d> poly = supportPolygon(L);
    const double margin = marginInPolygon(poly, L.com.head<2>());
    if (poly.size() >= 3) {
      out.summary.push_back("centre of mass " + num(100.0 * std::abs(margin), 3) + " cm " + (margin >= 0.0 ? "inside" : "outside") +
                            " the support polygon's nearest edge in posture '" + posture.name + "'");
    }
    if (poly.size() >= 3 && margin < 0.01) {
      out.warnings.push_back("posture '" + posture.name + "': the centre of mass is " + num(100.0 * std::abs(margin), 3) + " cm " +
                             (margin >= 0.0 ? "inside" : "outside") + " the support polygon's nearest edge: the stand " +
                             (margin >= 0.0 ? "may tip" : "tips") +
                             "; give another --posture (an SRDF group state) or correct the posture in the data file");
    }
  }
  if (!up.note.empty()) out.summary.push_back(up.note);
  for (const auto& n : L.notes) out.summary.push_back(n);
  return out;
}

// The arm's joints (model joint indices) from the shoulder (its first joint) out to its hand.
std::vector<int> armJoints(const model::RobotDescription& d, const ArmLayout& a) {
  std::vector<int> chain;
  const int first_body = d.joints[static_cast<size_t>(a.first_joint)].child_link;
  for (int b = a.end_body; b > 0; b = d.parentBody(b)) {
    const int j = d.links[static_cast<size_t>(b)].parent_joint;
    if (j >= 0) chain.insert(chain.begin(), j);
    if (b == first_body) break;
  }
  return chain;
}

// An arm whose shoulder cannot hold it stretched out level: the gravity torque of the arm (its
// subtree's mass at the distance of its centre of mass from the joint, that distance scaled by
// the arm's reach over the posture's shoulder-to-hand distance: the arm straightened) against the
// effort limit of each of the arm's first two joints. Out-of-reach targets stretch the arms; a
// shoulder (or a trunk) at its limit then leaves the plan no authority over the trunk, and the
// drafted reach folds such a robot forward (docs/results.md, "A heavier humanoid").
std::vector<std::string> armsThatCannotHold(const model::RobotDescription& d, const RobotLayout& L) {
  std::vector<std::string> out;
  for (const auto& a : L.arms) {
    const std::vector<int> chain = armJoints(d, a);
    const double span = (a.grasp_world - a.shoulder).norm();
    const double stretch = span > 1e-6 ? std::max(1.0, a.reach / span) : 1.0;
    for (size_t k = 0; k < std::min<size_t>(2, chain.size()); ++k) {
      const int j = chain[k];
      const auto& J = d.joints[static_cast<size_t>(j)];
      if (J.type == model::JointType::Prismatic || !std::isfinite(J.effort_limit) || static_cast<size_t>(j) >= L.loads.size()) continue;
      const JointLoad& load = L.loads[static_cast<size_t>(j)];
      const double lever = std::min(a.reach, load.lever * stretch);
      const double torque = load.mass * kGravity * lever;
      if (torque > J.effort_limit) {
        out.push_back("the " + (a.side.empty() ? std::string("arm") : lower(a.side) + " arm") + "'s joint '" + J.name +
                      "' cannot hold the arm " + "stretched out level: that takes about " + num(torque, 3) + " N m (" + num(load.mass, 3) +
                      " kg at " + num(lever, 2) + " m), its effort limit is " + num(J.effort_limit, 3) +
                      " N m; targets out of reach saturate it and the drafted reach " +
                      "may fold the robot (docs/results.md, \"A heavier humanoid\")");
      }
    }
  }
  return out;
}

// An arm near a singularity in the posture (stretched out, or folded onto its axis): the
// smallest singular value of its hand's position Jacobian over the arm's joints under 2 % of the
// largest. The drafted reach starts there, where the hand cannot move every way.
std::vector<std::string> armSingularities(const model::RobotDescription& d, const RobotLayout& L, const std::string& posture) {
  std::vector<std::string> out;
  if (L.arms.empty() && L.feet.empty()) return out;
  const model::RobotModel m(d);
  model::ModelData data = m.createData();
  model::Configuration q = m.neutralConfiguration();
  q.joints = L.posture;
  m.update(data, q, Eigen::VectorXd::Zero(m.nv()));
  Eigen::MatrixXd J(3, m.nv());
  for (const auto& a : L.arms) {
    // The arm's joints' velocity columns.
    std::vector<int> cols;
    for (const int j : armJoints(d, a)) cols.push_back(m.jointVelocityOffset() + j);
    if (cols.size() < 3) continue;
    m.pointJacobian(data, m.frameId(a.end_link), a.grasp_in_body, J);
    Eigen::MatrixXd Ja(3, static_cast<int>(cols.size()));
    for (size_t k = 0; k < cols.size(); ++k) Ja.col(static_cast<int>(k)) = J.col(cols[k]);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Ja);
    const Eigen::VectorXd sv = svd.singularValues();
    if (sv[0] > 0.0 && sv[2] < 0.02 * sv[0]) {
      out.push_back("posture '" + posture + "': the " + (a.side.empty() ? std::string("arm") : lower(a.side) + " arm") +
                    " is near a singularity (its hand's position Jacobian has singular values " + num(sv[0], 3) + ", " + num(sv[1], 3) +
                    ", " + num(sv[2], 3) +
                    " m/rad: stretched out or folded): the drafted reach starts there; another --posture starts it better");
    }
  }
  // A leg so (a straight knee): the base moves slowly, if at all, in the direction the leg cannot
  // move its foot, and a drafted base case starts there.
  if (d.base == model::BaseType::FreeFlyer) {
    for (const auto& f : L.feet) {
      std::vector<int> cols;
      for (int b = f.body; b > 0; b = d.parentBody(b)) {
        if (d.links[static_cast<size_t>(b)].parent_joint >= 0)
          cols.push_back(m.jointVelocityOffset() + d.links[static_cast<size_t>(b)].parent_joint);
      }
      if (cols.size() < 3) continue;
      const Eigen::Vector3d sole = f.sole_in_body.translation();
      m.pointJacobian(data, m.frameId(f.link), sole, J);
      Eigen::MatrixXd Jl(3, static_cast<int>(cols.size()));
      for (size_t k = 0; k < cols.size(); ++k) Jl.col(static_cast<int>(k)) = J.col(cols[k]);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jl);
      const Eigen::VectorXd sv = svd.singularValues();
      if (sv[0] > 0.0 && sv[2] < 0.02 * sv[0]) {
        out.push_back(
            "posture '" + posture + "': the leg of " + f.surface +
            " is near a singularity (its foot's position Jacobian has singular values " + num(sv[0], 3) + ", " + num(sv[1], 3) + ", " +
            num(sv[2], 3) +
            " m/rad: a straight knee?): the base can hardly move along the leg; a posture with the knees bent (--posture, an SRDF) "
            "moves it");
      }
    }
  }
  return out;
}

// The legs of a drafted zero posture brought under their hips and, for point feet, bent. A leg
// whose foot stands ahead of or behind its first pitch joint (the hip's) by more than a tenth of
// the hip's height and 1 cm (a quadruped's knee clamped inside its range with the thigh at 0 puts
// every foot forward) moves its pitch joints so that the foot is under that joint, the sole's
// pitch kept (a leg with a third pitch joint). Otherwise the centre of mass stands over one pair
// of feet: the others carry almost nothing, and a plan that keeps a minimum normal force on every
// foot has to shift the weight at the start. Point feet on legs stretched beyond 85 % of their
// reach (straight knees: the base can hardly move along the legs) go up to that, every point foot
// to the same height. Returns what moved ("joint: note"); a leg it cannot place within its
// joints' ranges is left as it was (docs/model.md, "The drafted posture").
std::vector<std::string> feetUnderHips(const model::RobotDescription& d, const RobotLayout& L, Eigen::VectorXd& posture) {
  std::vector<std::string> moved;
  if (d.base != model::BaseType::FreeFlyer || !L.legged) return moved;
  const model::RobotModel m(d);
  model::ModelData data = m.createData();
  model::Configuration q = m.neutralConfiguration();
  // The model in the posture, its base turned as the layout turned it (soles flat): the frame of
  // the layout's poses, so that the hips and the feet below are where the layout saw them.
  q.base_rotation = L.base_rotation;
  q.joints = posture;
  m.update(data, q, Eigen::VectorXd::Zero(m.nv()));
  std::vector<Eigen::Isometry3d> pose;
  for (int b = 0; b < m.numBodies(); ++b) pose.push_back(m.bodyPlacement(data, b));
  // The bodies each foot's chain passes through: a joint above a body that carries two feet (a
  // spine, a waist) is the trunk's, never a leg's.
  std::vector<int> feet_below(d.links.size(), 0);
  for (const auto& f : L.feet) {
    for (int b = f.body; b >= 0; b = d.parentBody(b)) ++feet_below[static_cast<size_t>(b)];
  }
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ(), fwd = L.forward, lateral = up.cross(fwd);
  constexpr double kStretch = 0.85;
  struct Leg {
    const FootLayout* foot = nullptr;
    std::vector<int> pitch;                          // hip first
    std::vector<double> sign;                        // of each axis along the lateral direction
    Eigen::Vector3d sole = Eigen::Vector3d::Zero();  // in the foot's body
    Eigen::Vector3d hip = Eigen::Vector3d::Zero(), foot_world = Eigen::Vector3d::Zero();
    double reach = 0.0;  // the pitch chain's length in the sagittal plane, stretched
  };
  std::vector<Leg> legs;
  for (const auto& f : L.feet) {
    Leg g;
    g.foot = &f;
    for (int b = f.body; b > 0 && feet_below[static_cast<size_t>(b)] == 1; b = d.parentBody(b)) {
      const int j = d.links[static_cast<size_t>(b)].parent_joint;
      if (j < 0) continue;
      const auto& Jd = d.joints[static_cast<size_t>(j)];
      if (Jd.type != model::JointType::Revolute) continue;
      const double a = (pose[static_cast<size_t>(Jd.child_link)].linear() * Jd.axis).dot(lateral);
      if (std::abs(a) < 0.9) continue;
      g.pitch.insert(g.pitch.begin(), j);
      g.sign.insert(g.sign.begin(), a > 0.0 ? 1.0 : -1.0);
    }
    if (g.pitch.size() < 2) continue;
    for (const auto& p : f.points) g.sole += p;
    g.sole = f.sole_in_body * (g.sole / static_cast<double>(f.points.size()));
    g.foot_world = pose[static_cast<size_t>(f.body)] * g.sole;
    auto origin = [&](int j) { return pose[static_cast<size_t>(d.joints[static_cast<size_t>(j)].child_link)].translation(); };
    g.hip = origin(g.pitch[0]);
    auto planar = [&](const Eigen::Vector3d& v) { return (v - v.dot(lateral) * lateral).norm(); };
    for (size_t k = 0; k + 1 < g.pitch.size(); ++k) g.reach += planar(origin(g.pitch[k + 1]) - origin(g.pitch[k]));
    g.reach += planar(g.foot_world - origin(g.pitch.back()));
    if (!((g.hip - g.foot_world).dot(up) > 0.0)) continue;
    legs.push_back(g);
  }
  // The point feet's common height: each stretched leg bent to kStretch of its reach.
  std::optional<double> common_z;
  for (const Leg& g : legs) {
    if (!g.foot->point_foot) continue;
    const double h = (g.hip - g.foot_world).dot(up);
    const double z = g.hip.dot(up) - std::min(h, kStretch * g.reach);
    if (h > kStretch * g.reach + 1e-3 && (!common_z || z > *common_z)) common_z = z;
  }
  // Every leg placed (into `out`): the point feet (every foot with `all_feet`) at `point_z`, the
  // others at their height. False when a leg that had to move could not: feet at different
  // heights would stand on some only.
  auto place = [&](const std::optional<double>& point_z, bool all_feet, std::vector<std::string>& moved, Eigen::VectorXd& out) {
    bool all_bent = true;
    for (const Leg& g : legs) {
      const FootLayout& f = *g.foot;
      const double height = (g.hip - g.foot_world).dot(up);
      const double offset = (g.foot_world - g.hip).dot(fwd);
      const double foot_z = (f.point_foot || all_feet) && point_z ? *point_z : g.foot_world.dot(up);
      const bool bend = std::abs(foot_z - g.foot_world.dot(up)) > 1e-3;
      if (std::abs(offset) <= std::max(0.01, 0.1 * height) && !bend) continue;  // nothing to move
      const int frame = m.frameId(f.link);
      const bool keep_pitch = !f.point_foot && g.pitch.size() >= 3;
      const int rows = keep_pitch ? 3 : 2, n = static_cast<int>(g.pitch.size());
      auto limits = [&](int j) {
        const auto& Jd = d.joints[static_cast<size_t>(j)];
        const double range = Jd.upper - Jd.lower;
        return std::isfinite(range) ? std::pair{Jd.lower + 0.05 * range, Jd.upper - 0.05 * range} : std::pair{-M_PI, M_PI};
      };
      Eigen::VectorXd x;
      Eigen::VectorXd r(rows);
      auto residual = [&] {
        q.joints = x;
        m.update(data, q, Eigen::VectorXd::Zero(m.nv()));
        const Eigen::Vector3d foot = m.bodyPlacement(data, f.body) * g.sole;
        r[0] = (foot - g.hip).dot(fwd);
        r[1] = foot.dot(up) - foot_z;
        if (keep_pitch) {
          r[2] = 0.0;
          for (int k = 0; k < n; ++k) {
            const int j = g.pitch[static_cast<size_t>(k)];
            r[2] += g.sign[static_cast<size_t>(k)] * (x[j] - out[j]);
          }
        }
      };
      // Gauss-Newton on the pitch joints (the hip's origin does not move with them), steps of at
      // most 0.3 rad, inside 5 % of each joint's range.
      Eigen::MatrixXd J(3, m.nv());
      auto solve = [&]() {
        residual();
        for (int it = 0; it < 100; ++it) {
          if (r.norm() < 1e-5) return true;
          m.pointJacobian(data, frame, g.sole, J);
          Eigen::MatrixXd A(rows, n);
          for (int k = 0; k < n; ++k) {
            const Eigen::Vector3d c = J.col(m.jointVelocityOffset() + g.pitch[static_cast<size_t>(k)]);
            A(0, k) = c.dot(fwd);
            A(1, k) = c.dot(up);
            if (keep_pitch) A(2, k) = g.sign[static_cast<size_t>(k)];
          }
          Eigen::VectorXd step = A.transpose() * (A * A.transpose() + 1e-6 * Eigen::MatrixXd::Identity(rows, rows)).ldlt().solve(r);
          if (step.cwiseAbs().maxCoeff() > 0.3) step *= 0.3 / step.cwiseAbs().maxCoeff();
          for (int k = 0; k < n; ++k) {
            const int j = g.pitch[static_cast<size_t>(k)];
            const auto [lo, hi] = limits(j);
            x[j] = std::clamp(x[j] - step[k], lo, hi);
          }
          residual();
        }
        return r.norm() < 1e-5;
      };
      // A straight leg bends its knee (the second pitch joint) either way: both are tried, and the
      // knee nearer the centre of mass (fore and aft) is kept, as quadrupeds stand.
      std::vector<Eigen::VectorXd> found;
      const bool straight = height > 0.97 * g.reach;
      for (const double kick : straight ? std::vector<double>{0.3, -0.3} : std::vector<double>{0.0}) {
        x = out;
        const auto [lo, hi] = limits(g.pitch[1]);
        x[g.pitch[1]] = std::clamp(x[g.pitch[1]] + kick, lo, hi);
        if (solve()) found.push_back(x);
      }
      // A bent leg whose descent ends on a joint's limit (a knee whose range stops short of
      // straight) starts again from the knee bent further, then less: the first that reaches wins.
      for (const double kick : {0.3, 0.6, -0.3, -0.6}) {
        if (straight || !found.empty()) break;
        x = out;
        const auto [lo, hi] = limits(g.pitch[1]);
        x[g.pitch[1]] = std::clamp(x[g.pitch[1]] + kick, lo, hi);
        if (solve()) found.push_back(x);
      }
      if (found.empty()) {
        all_bent = false;
        continue;
      }
      auto inward = [&](const Eigen::VectorXd& v) {
        q.joints = v;
        m.update(data, q, Eigen::VectorXd::Zero(m.nv()));
        return std::abs((m.bodyPlacement(data, d.joints[static_cast<size_t>(g.pitch[1])].child_link).translation() - L.com).dot(fwd));
      };
      x = found[0];
      if (found.size() > 1 && inward(found[1]) < inward(found[0]) - 1e-6) x = found[1];
      const bool off = std::abs(offset) > std::max(0.01, 0.1 * height);
      const std::string stretch = num(100.0 * height / g.reach, 3) + " % of its reach";
      const std::string why = off ? f.surface + " " + num(std::abs(offset), 3) + " m " + (offset > 0.0 ? "ahead of" : "behind") +
                                        " its hip" + (bend ? ", its leg at " + stretch : "")
                                  : f.surface + "'s leg at " + stretch;
      for (int k = 0; k < n; ++k) {
        const int j = g.pitch[static_cast<size_t>(k)];
        if (std::abs(x[j] - out[j]) < 1e-9) continue;
        moved.push_back(d.joints[static_cast<size_t>(j)].name + ": " + num(out[j]) + " put " + why + "; taken as " + num(x[j], 6) +
                        " (the foot under the hip" +
                        (bend ? ", the leg at " + num(100.0 * (g.hip.dot(up) - foot_z) / g.reach, 3) + " % of its reach)" : ")"));
      }
      for (int k = 0; k < n; ++k) out[g.pitch[static_cast<size_t>(k)]] = x[g.pitch[static_cast<size_t>(k)]];
    }
    return all_bent;
  };
  // A leg that cannot bring its foot under the hip at its height (a knee whose range stops short
  // of straight) needs the hips lower: then every foot goes to the common height of legs at
  // kStretch of their reach. If that fails too, only the point feet are bent, or none.
  std::optional<double> all_z;
  for (const Leg& g : legs) {
    const double z = g.hip.dot(up) - std::min((g.hip - g.foot_world).dot(up), kStretch * g.reach);
    if (!all_z || z > *all_z) all_z = z;
  }
  Eigen::VectorXd out = posture;
  bool placed = place(common_z, false, moved, out);
  for (int attempt = 0; !placed && attempt < 2; ++attempt) {
    moved.clear();
    out = posture;
    placed = attempt == 0 ? place(all_z, true, moved, out) : place(std::nullopt, false, moved, out);
  }
  posture = out;
  return moved;
}

}  // namespace

InitResult initRobot(const InitOptions& o) {
  InitResult result;
  if (o.out_dir.empty()) throw InputError("--out", "give the folder to write the draft to");
  const fs::path final_dir = fs::absolute(o.out_dir).lexically_normal();
  {
    std::error_code ec;
    if (fs::exists(final_dir, ec) && !(fs::is_directory(final_dir, ec) && fs::is_empty(final_dir, ec))) {
      throw InputError(o.out_dir, "exists and is not an empty folder: robot init writes a new folder (give another --out)");
    }
  }
  model::LoadOptions lo;
  lo.strict = o.strict;
  lo.package_paths = o.package_paths;
  lo.require_meshes = !o.allow_missing_meshes;

  // Meshes are read once (the base's guess and the draft read the same ones).
  MeshCache meshes;
  if (o.mimic != "coupled" && o.mimic != "locked") throw InputError("--mimic", "expected coupled or locked, found '" + o.mimic + "'");
  const model::MimicMode mimic = o.mimic == "locked" ? model::MimicMode::Locked : model::MimicMode::Coupled;
  model::RobotDescription probe = model::loadUrdfOnly(o.urdf, model::BaseType::FreeFlyer, lo, mimic);
  const UpAxisChoice up = chooseMeshUpAxis(probe, meshes);
  probe.mesh_up_axis_from_file = up.apply;
  // The base type: as given, or fixed when the root is a `world` link, else legs decide.
  model::BaseType base = model::BaseType::FreeFlyer;
  std::string base_note;
  if (o.base == "fixed") {
    base = model::BaseType::Fixed;
  } else if (o.base.empty()) {
    if (lower(probe.urdf_root) == "world") {
      base = model::BaseType::Fixed;
      base_note = "the URDF's root link is 'world'";
    } else {
      ProblemList ignored(o.urdf);
      const RobotLayout probe_layout = analyseLayout(probe, neutralPosture(probe).q, ignored, &meshes);
      base = probe_layout.legged ? model::BaseType::FreeFlyer : model::BaseType::Fixed;
    }
  } else if (o.base != "free_flyer") {
    throw InputError("--base", "expected free_flyer or fixed, found '" + o.base + "'");
  }
  model::RobotDescription d = base == model::BaseType::FreeFlyer ? std::move(probe) : model::loadUrdfOnly(o.urdf, base, lo, mimic);
  d.mesh_up_axis_from_file = up.apply;
  for (const auto& w : d.warnings) result.warnings.push_back(w);

  ProblemList problems(o.srdf.empty() ? o.urdf : o.srdf);
  std::optional<Srdf> srdf;
  if (!o.srdf.empty()) srdf = readSrdf(o.srdf, d, problems, o.srdf_skip_unknown);
  problems.throwIfErrors();
  std::vector<Posture> postures;
  if (srdf) postures = srdfPostures(d, *srdf);
  if (postures.empty()) postures.push_back(neutralPosture(d));
  const Posture& posture = choosePosture(postures, o.posture, o.srdf);
  for (const auto& p : postures) {
    for (const auto& c : p.clamped) result.warnings.push_back("posture '" + p.name + "': " + c);
  }
  if (srdf) {
    for (const auto& n : srdf->notes) result.warnings.push_back(n);
  }

  ProblemList mesh_problems(o.urdf);
  RobotLayout L = analyseLayout(d, posture.q, mesh_problems, &meshes);
  mesh_problems.throwIfErrors();
  // An arm joint exactly at a limit in the posture (a straight elbow on its stop) goes 25 % of its
  // range inside: a reach that starts there cannot move the hand every way with the arm, takes
  // the motion from the legs and trunk and folds the robot (docs/model.md). The layout is
  // analysed again in the moved posture.
  {
    Posture& chosen = postures[static_cast<size_t>(&posture - postures.data())];
    std::vector<std::string> moved;
    for (const auto& a : L.arms) {
      for (const int j : armJoints(d, a)) {
        const auto& J = d.joints[static_cast<size_t>(j)];
        const double range = J.upper - J.lower, v = chosen.q[j];
        const double tol = 1e-9 + 1e-6 * (std::isfinite(range) ? range : 0.0);
        if (std::isfinite(range) && range > 0.0 && (std::abs(v - J.lower) <= tol || std::abs(v - J.upper) <= tol)) {
          const double w = std::abs(v - J.lower) <= tol ? J.lower + 0.25 * range : J.upper - 0.25 * range;
          chosen.q[j] = w;
          moved.push_back(J.name + ": at its limit " + num(v) + " (the arm starts stretched or folded on a stop), taken as " + num(w) +
                          " (25 % of its range inside)");
        }
      }
    }
    if (!moved.empty()) {
      for (const auto& m : moved) result.warnings.push_back("posture '" + chosen.name + "': " + m);
      ProblemList again(o.urdf);
      L = analyseLayout(d, chosen.q, again, &meshes);
      again.throwIfErrors();
    }
  }
  // A drafted zero posture's legs under their hips (not a posture the SRDF gives).
  if (posture.given < 0) {
    Posture& chosen = postures[static_cast<size_t>(&posture - postures.data())];
    const Eigen::VectorXd before = chosen.q;
    const std::vector<std::string> moved = feetUnderHips(d, L, chosen.q);
    // The moved legs must stand as before: the same feet on the ground (a foot lifted, or a leg
    // taken for an arm, would change the robot the draft describes); otherwise the posture stays.
    std::optional<RobotLayout> moved_layout;
    if (!moved.empty()) {
      ProblemList again(o.urdf);
      moved_layout = analyseLayout(d, chosen.q, again, &meshes);
      std::vector<int> was, now;
      for (const auto& f : L.feet) was.push_back(f.body);
      for (const auto& f : moved_layout->feet) now.push_back(f.body);
      std::sort(was.begin(), was.end());
      std::sort(now.begin(), now.end());
      if (was != now || again.hasErrors()) {
        chosen.q = before;
        moved_layout.reset();
        std::string why;
        if (again.hasErrors()) {
          why = "the moved posture could not be analysed (";
          for (const auto& e : again.errors()) why += (why.back() == '(' ? "" : "; ") + e.text();
          why += ")";
        } else if (was.size() != now.size()) {
          why = "bringing them under their hips put " + std::to_string(now.size()) + " feet on the ground instead of " +
                std::to_string(was.size());
        } else {
          why = "bringing them under their hips put other links on the ground than the drafted feet";
        }
        result.warnings.push_back("posture '" + chosen.name + "': the legs were left as drafted: " + why +
                                  " (give a standing posture: --posture, an SRDF)");
      }
    }
    if (moved_layout) {
      chosen.source += "; then the legs brought under their hips (each moved joint says why)";
      for (const auto& m : moved) {
        result.warnings.push_back("posture '" + chosen.name + "': " + m);
        const std::string joint = m.substr(0, m.find(": ") + 1);
        chosen.clamped.erase(std::remove_if(chosen.clamped.begin(), chosen.clamped.end(),
                                            [&](const std::string& c) { return c.compare(0, joint.size(), joint) == 0; }),
                             chosen.clamped.end());
        chosen.clamped.push_back(m);
      }
      L = std::move(*moved_layout);
    }
  }
  for (const auto& w : mesh_problems.warnings()) result.warnings.push_back(w.text());
  if (!base_note.empty()) L.base_reason = base_note;
  if (posture.given >= 0 && 2 * posture.given < static_cast<int>(d.joints.size())) {
    result.warnings.push_back("posture '" + posture.name + "' (the SRDF's) gives " + std::to_string(posture.given) + " of the " +
                              std::to_string(d.joints.size()) +
                              " joints; the others are at 0: is it a state of one group only? "
                              "(another --posture, or complete it in the data file)");
  }
  for (const auto& w : armSingularities(d, L, posture.name)) result.warnings.push_back(w);
  for (const auto& w : armsThatCannotHold(d, L)) result.warnings.push_back(w);
  for (const auto& w : L.warnings) result.warnings.push_back("posture '" + posture.name + "': " + w);
  if (d.base == model::BaseType::FreeFlyer && L.feet.size() < 2) {
    throw InputError(o.urdf, "the robot has a floating base but no two chains reach the ground in posture '" + posture.name + "' (" +
                                 L.base_reason +
                                 "): robot init cannot place its feet; give --base fixed for a robot welded to the world, or "
                                 "another --posture");
  }
  const Draft dr = draft(d, L, posture, postures, o, final_dir, srdf ? &*srdf : nullptr, up);

  // Written into a temporary folder beside DIR, checked by loading it, then renamed to DIR.
  const fs::path tmp = final_dir.parent_path() / ("." + final_dir.filename().string() + ".partial-" + std::to_string(::getpid()));
  std::error_code ec;
  fs::remove_all(tmp, ec);
  fs::create_directories(tmp, ec);
  if (ec) throw InputError(final_dir.parent_path().string(), "cannot create a folder there: " + ec.message());
  try {
    writeFile(tmp / dr.robot_file, dr.data);
    writeFile(tmp / "stand.yaml", dr.stand);
    if (!dr.reach.empty()) writeFile(tmp / "reach.yaml", dr.reach);
    if (!dr.base.empty()) writeFile(tmp / "base.yaml", dr.base);
    if (!dr.lift.empty()) writeFile(tmp / "lift_foot.yaml", dr.lift);
    // The drafts must load (a failure here is a defect of robot init, named as such).
    for (const char* f : {"stand.yaml", "reach.yaml", "base.yaml", "lift_foot.yaml"}) {
      if (!fs::exists(tmp / f)) continue;
      try {
        cases::loadCase((tmp / f).string());
      } catch (const InputError& e) {
        throw std::runtime_error(std::string("robot init drafted a case that does not load (a defect of robot init): ") + e.what());
      }
    }
    if (fs::exists(final_dir)) fs::remove(final_dir);
    fs::rename(tmp, final_dir);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
  result.files.push_back((final_dir / dr.robot_file).string());
  result.files.push_back((final_dir / "stand.yaml").string());
  if (!dr.reach.empty()) result.files.push_back((final_dir / "reach.yaml").string());
  if (!dr.base.empty()) result.files.push_back((final_dir / "base.yaml").string());
  if (!dr.lift.empty()) result.files.push_back((final_dir / "lift_foot.yaml").string());
  result.summary = dr.summary;
  for (const auto& w : dr.warnings) result.warnings.push_back(w);
  return result;
}

}  // namespace lexdyn::robot
