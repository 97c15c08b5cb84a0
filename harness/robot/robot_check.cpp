#include "harness/robot/robot_check.hpp"

#include "harness/cases/case_file.hpp"
#include "harness/robot/robot_layout.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/problems.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/model/inertia.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#ifndef LEXDYN_SOURCE_DIR
#define LEXDYN_SOURCE_DIR "."
#endif

namespace lexdyn::robot {

namespace fs = std::filesystem;

namespace {

std::string num(double v, int digits = 4) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return formatNumber(std::abs(v) < 1e-12 ? 0.0 : v, digits);
}

std::string pad(const std::string& s, size_t w) { return s.size() >= w ? s + " " : s + std::string(w - s.size(), ' '); }

struct Loaded {
  model::RobotDescription d;
  std::string posture_name;
  std::string data_path;  // "" for a URDF alone
};

Loaded load(const CheckOptions& o) {
  model::LoadOptions lo;
  lo.strict = o.strict;
  lo.package_paths = o.package_paths;
  Loaded r;
  const std::string ext = fs::path(o.input).extension().string();
  if (ext == ".urdf" || ext == ".xml" || ext == ".xacro") {
    r.d = model::loadUrdfOnly(o.input, model::BaseType::FreeFlyer, lo);
    return r;
  }
  const yaml::Node root = yaml::loadFile(o.input);
  if (root.raw()["format"] && root.raw()["format"].IsScalar() && root.raw()["format"].Scalar() == "lexdyn-robot-data/1") {
    std::string urdf = o.urdf;
    if (urdf.empty() && root.raw()["urdf"] && root.raw()["urdf"].IsScalar()) {
      urdf = (fs::path(o.input).parent_path() / root.raw()["urdf"].Scalar()).lexically_normal().string();
    }
    if (urdf.empty() && root.raw()["robot"] && root.raw()["robot"].IsScalar()) {
      const fs::path beside = fs::path(o.input).parent_path() / (root.raw()["robot"].Scalar() + ".urdf");
      if (fs::is_regular_file(beside)) urdf = beside.string();
    }
    if (urdf.empty()) throw InputError(o.input, "a data file without an `urdf` key: give its URDF with --urdf FILE");
    r.d = model::loadRobotDescription(urdf, o.input, lo);
    r.data_path = o.input;
    return r;
  }
  const cases::CaseSpec spec = cases::loadCase(o.input);
  r.d = model::loadRobotDescription(spec.urdf_path, spec.data_path, spec.robot_options);
  r.data_path = spec.data_path;
  r.posture_name = spec.initial_state.posture;
  return r;
}

// The picture: three views of the robot's geometry outlines, skeleton, contact points, CoM and
// support polygon, drawn by harness/scripts/robot_view.py (matplotlib).
std::string drawPicture(const model::RobotDescription& d, const RobotLayout& L, const std::vector<Eigen::Vector3d>& contacts,
                        const std::vector<Eigen::Vector2d>& poly, double ground,
                        const std::vector<std::pair<std::string, Eigen::Isometry3d>>& frames, const std::string& title,
                        const std::string& png) {
  using nlohmann::json;
  json j;
  j["title"] = title;
  auto p3 = [&](const Eigen::Vector3d& p) { return json::array({p.x(), p.y(), p.z() - ground}); };
  json views = json::array();
  const int axes[3][2] = {{1, 2}, {0, 2}, {0, 1}};  // front (y, z), side (x, z), top (x, y)
  for (int v = 0; v < 3; ++v) {
    json polys = json::array();
    for (const auto& pts : L.geometry_points) {
      if (pts.empty()) continue;
      std::vector<Eigen::Vector2d> flat;
      for (const auto& p : pts) flat.emplace_back(p[axes[v][0]], p[axes[v][1]] - (axes[v][1] == 2 ? ground : 0.0));
      json poly_j = json::array();
      for (const auto& q : convexHull(flat)) poly_j.push_back(json::array({q.x(), q.y()}));
      polys.push_back(poly_j);
    }
    views.push_back(polys);
  }
  j["outlines"] = views;
  json bones = json::array();
  for (size_t b = 1; b < L.body_pose.size(); ++b) {
    const int parent = d.parentBody(static_cast<int>(b));
    bones.push_back(json::array({p3(L.body_pose[static_cast<size_t>(parent)].translation()), p3(L.body_pose[b].translation())}));
  }
  j["bones"] = bones;
  json pts = json::array();
  for (const auto& c : contacts) pts.push_back(p3(c));
  j["contacts"] = pts;
  json pj = json::array();
  for (const auto& q : poly) pj.push_back(json::array({q.x(), q.y()}));
  j["support"] = pj;
  j["com"] = p3(L.com);
  // The data file's frames (soles, grasp points, sensors): origin and x, z axes (a tenth of the
  // robot's height long).
  json fj = json::array();
  const double len = 0.1 * std::max(L.height, 0.1);
  for (const auto& [name, X] : frames) {
    fj.push_back(
        {{"name", name}, {"p", p3(X.translation())}, {"x", p3(X * Eigen::Vector3d(len, 0, 0))}, {"z", p3(X * Eigen::Vector3d(0, 0, len))}});
  }
  j["frames"] = fj;
  j["forward"] = L.forward.x() < 0.0 ? -1 : 1;
  const fs::path json_path = fs::path(png).string() + ".json";
  {
    std::ofstream out(json_path);
    out << j.dump();
    if (!out) throw InputError(json_path.string(), "cannot write");
  }
  const std::string script = std::string(LEXDYN_SOURCE_DIR) + "/harness/scripts/robot_view.py";
  const std::string cmd = "/usr/bin/python3 '" + script + "' '" + json_path.string() + "' '" + png + "' 2>&1";
  std::FILE* p = ::popen(cmd.c_str(), "r");
  std::string said;
  if (p) {
    char buf[256];
    while (std::fgets(buf, sizeof(buf), p)) said += buf;
    const int status = ::pclose(p);
    std::error_code ec;
    fs::remove(json_path, ec);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return png;
  }
  return "(no picture: " + (said.empty() ? std::string("cannot run ") + script : said) + ")";
}

}  // namespace

CheckReport checkRobot(const CheckOptions& o) {
  CheckReport rep;
  Loaded ld = load(o);
  const model::RobotDescription& d = ld.d;
  // The posture: asked for, the case's, else the first of the data file, else zero (clamped).
  Eigen::VectorXd q = Eigen::VectorXd::Zero(static_cast<int>(d.joints.size()));
  std::string posture = o.posture.empty() ? ld.posture_name : o.posture;
  if (posture.empty() && !d.postures.empty()) posture = d.postures.front().first;
  if (!posture.empty()) {
    q = d.posture(posture);
  } else {
    for (size_t j = 0; j < d.joints.size(); ++j) q[static_cast<int>(j)] = std::min(std::max(0.0, d.joints[j].lower), d.joints[j].upper);
    posture = "zero";
  }
  ProblemList problems(d.urdf_path);
  const RobotLayout L = analyseLayout(d, q, problems);

  std::ostringstream t;
  t << "robot " << d.name << "\n  URDF: " << d.urdf_path << "\n  data: " << (ld.data_path.empty() ? "(none: the URDF alone)" : ld.data_path)
    << "\n";
  const double ground = L.lowest_z;
  t << "  base: " << (d.base == model::BaseType::Fixed ? "fixed" : "free_flyer") << "; " << d.links.size() << " bodies, " << d.joints.size()
    << " joints";
  if (!d.locked_joints.empty()) t << " (+ " << d.locked_joints.size() << " locked)";
  t << "\n  mass " << num(L.mass) << " kg; height " << num(L.height, 3) << " m in posture '" << posture << "'\n";
  const bool backwards = L.forward.x() < 0.0;
  t << "  centre of mass " << num(L.com.x(), 3) << ", " << num(L.com.y(), 3) << ", " << num(L.com.z() - ground, 3)
    << " m (z above the lowest point; the base at the origin)\n"
    << "  forward: " << (backwards ? "-x" : "+x") << " of the base frame"
    << (L.sides_from == "names"
            ? (backwards ? " (the links' names put the robot's left at -y)" : " (the links' names put the robot's left at +y)")
            : " (x forward, y left, as REP 103 has it)")
    << "\n";
  if (!L.base_rotation.isIdentity(1e-12)) {
    const Eigen::AngleAxisd aa(L.base_rotation);
    t << "  the base is turned by " << num(aa.angle() * 180.0 / 3.14159265358979323846, 3)
      << " deg so that the feet stand flat (the posture tilts them; the start's equilibrium finds the same)\n";
  }

  // Contact points from the data file, in the posture.
  const model::RobotModel m(d);
  model::ModelData data = m.createData();
  model::Configuration cq = m.neutralConfiguration();
  cq.joints = q;
  cq.base_rotation = L.base_rotation;
  m.update(data, cq, Eigen::VectorXd::Zero(m.nv()));
  std::vector<Eigen::Vector3d> contacts;
  std::vector<Eigen::Vector2d> flat;
  if (!d.contact_surfaces.empty()) {
    t << "  contact points (world, posture '" << posture << "'):\n";
    for (const auto& s : d.contact_surfaces) {
      const Eigen::Isometry3d X = m.framePlacement(data, s.frame);
      t << "    " << pad(s.name, 18) << "frame " << d.frames[static_cast<size_t>(s.frame)].name
        << (s.radius > 0.0 ? " (balls of radius " + num(s.radius, 3) + " m, where they touch)" : std::string()) << ":";
      double zmin = 1e9, zmax = -1e9;
      for (const auto& p : s.points) {
        const Eigen::Vector3d w = X * p - Eigen::Vector3d(0.0, 0.0, s.radius);  // a ball's lowest point
        contacts.push_back(w);
        flat.emplace_back(w.x(), w.y());
        zmin = std::min(zmin, w.z());
        zmax = std::max(zmax, w.z());
        t << " [" << num(w.x(), 3) << ", " << num(w.y(), 3) << ", " << num(w.z() - ground, 3) << "]";
      }
      t << "\n";
      if (zmax - zmin > 0.005)
        t << "      note: its points are " << num((zmax - zmin) * 1000, 3)
          << " mm apart in height: the sole is not flat on the ground in this posture\n";
    }
    // The points on the ground (within 2 mm of the lowest) make the support polygon.
    double zlow = 1e18;
    for (const auto& c : contacts) zlow = std::min(zlow, c.z());
    flat.clear();
    int in_air = 0;
    for (const auto& c : contacts) {
      if (c.z() <= zlow + 0.002) {
        flat.emplace_back(c.x(), c.y());
      } else {
        ++in_air;
      }
    }
    const std::vector<Eigen::Vector2d> poly = convexHull(flat);
    const double margin = marginInPolygon(poly, L.com.head<2>());
    rep.com_inside = margin > 0.0;
    t << "  support polygon: " << poly.size() << " corners";
    if (in_air > 0) t << " (" << in_air << " contact point(s) more than 2 mm above the lowest: in the air, left out)";
    t << "; the centre of mass is " << num(std::abs(margin) * 1000, 3) << " mm "
      << (margin > 0 ? "inside its nearest edge" : "OUTSIDE it: the robot cannot stand in this posture") << "\n";
  }

  // Static joint torques in the posture: gravity, with the weight spread over the contact points
  // (vertical forces of least norm that balance the weight and its moments) for a floating robot.
  Eigen::VectorXd tau_static = Eigen::VectorXd::Zero(static_cast<int>(d.joints.size()));
  std::string torque_note;
  {
    Eigen::VectorXd N(m.nv());
    m.nonlinearEffects(data, N);
    Eigen::VectorXd tau_full = N;
    if (m.hasFreeFlyer() && !contacts.empty()) {
      const int np = static_cast<int>(contacts.size());
      Eigen::MatrixXd A(3, np);
      for (int i = 0; i < np; ++i)
        A.col(i) << 1.0, contacts[static_cast<size_t>(i)].y() - L.com.y(), contacts[static_cast<size_t>(i)].x() - L.com.x();
      const Eigen::Vector3d b(L.mass * m.gravity().norm(), 0.0, 0.0);
      const Eigen::VectorXd f = A.transpose() * (A * A.transpose()).completeOrthogonalDecomposition().solve(b);
      if (f.minCoeff() < 0.0) torque_note = " (some contact points would have to pull: the centre of mass is not above the support)";
      int i = 0;
      Eigen::MatrixXd J(3, m.nv());
      for (const auto& srf : d.contact_surfaces) {
        const Eigen::Matrix3d R = m.framePlacement(data, srf.frame).linear();
        for (const auto& p : srf.points) {
          m.pointJacobian(data, srf.frame, p - R.transpose() * Eigen::Vector3d(0.0, 0.0, srf.radius), J);
          tau_full -= J.transpose() * Eigen::Vector3d(0.0, 0.0, f[i++]);
        }
      }
    }
    tau_static = tau_full.tail(static_cast<int>(d.joints.size()));
  }

  // Joint table.
  std::vector<double> kp(d.joints.size(), NAN), kd(d.joints.size(), NAN);
  for (const auto& g : d.servo_gains) {
    for (size_t j = 0; j < d.joints.size(); ++j) {
      if (checks::globMatch(g.match, d.joints[j].name)) {
        kp[j] = g.kp;
        kd[j] = g.kd;
      }
    }
  }
  t << "  joints (posture '" << posture << "'; margin: to the nearer limit):\n    " << pad("joint", 26) << pad("type", 10)
    << pad("lower", 9) << pad("upper", 9) << pad("posture", 9) << pad("margin", 9) << pad("effort", 9) << pad("static", 9)
    << pad("velocity", 9) << pad("servo kp", 10) << "kd\n";
  std::vector<std::string> overloaded;
  for (size_t j = 0; j < d.joints.size(); ++j) {
    const auto& J = d.joints[j];
    const double v = q[static_cast<int>(j)];
    const double margin = std::min(v - J.lower, J.upper - v);
    t << "    " << pad(J.name, 26)
      << pad(J.continuous ? "continuous" : (J.type == model::JointType::Revolute ? "revolute" : "prismatic"), 10) << pad(num(J.lower, 3), 9)
      << pad(num(J.upper, 3), 9) << pad(num(v, 3), 9) << pad(num(margin, 3) + (margin < 0.02 && !std::isinf(margin) ? "!" : ""), 9)
      << pad(num(J.effort_limit, 3), 9);
    const double ts = tau_static[static_cast<int>(j)];
    const bool over = std::abs(ts) > J.effort_limit;
    if (over) overloaded.push_back(J.name + " (" + num(ts, 3) + " against " + num(J.effort_limit, 3) + ")");
    t << pad(num(ts, 3) + (over ? "!!" : ""), 9) << pad(num(J.velocity_limit, 3), 9) << pad(std::isnan(kp[j]) ? "-" : num(kp[j], 3), 10)
      << (std::isnan(kd[j]) ? "-" : num(kd[j], 3)) << "\n";
  }
  t << "    (!: within 0.02 of a limit; static: the joint torque that holds the posture at rest" << torque_note
    << ", !!: beyond the effort limit; inf: unspecified in the URDF, taken as unlimited)\n";
  if (!overloaded.empty()) {
    t << "  the servos cannot hold this posture: the static torque exceeds the effort limit of ";
    for (size_t k = 0; k < overloaded.size(); ++k) t << (k ? ", " : "") << overloaded[k];
    t << "\n";
  }
  if (!d.coupled_joints.empty()) {
    t << "  coupled mimic joints (each moves with its master; no coordinate of its own):\n";
    for (const auto& cj : d.coupled_joints) {
      t << "    " << pad(cj.name, 26) << "= " << num(cj.multiplier) << " x " << d.joints[static_cast<size_t>(cj.master)].name
        << (cj.offset != 0.0 ? " + " + num(cj.offset) : "") << "\n";
    }
  }
  if (!d.locked_joints.empty()) {
    t << "  locked joints (fixed by the loader; their links are lumped into their parents):\n";
    for (const auto& l : d.locked_joints) {
      t << "    " << pad(l.name, 26) << "at " << pad(num(l.value, 4), 9);
      for (const auto& mm : d.mimics) {
        if (mm.joint == l.name)
          t << "mimic: " << num(mm.multiplier) << " x " << mm.master << (mm.offset != 0.0 ? " + " + num(mm.offset) : "");
      }
      if (l.reason == "massless") t << "moves only massless links";
      t << "\n";
    }
  }
  // Bodies: mass and inertia after lumping.
  t << "  bodies (mass after lumping, principal moments):\n";
  for (const auto& l : d.links) {
    t << "    " << pad(l.name, 26) << pad(num(l.mass, 4) + " kg", 12) << model::formatMoments(model::checkInertia(l.inertia).moments)
      << " kg m^2";
    if (!l.merged_links.empty()) t << "  (+" << l.merged_links.size() << " merged)";
    t << "\n";
  }
  std::vector<std::string> warnings = d.warnings;
  for (const auto& w : problems.warnings()) warnings.push_back(w.text());
  for (const auto& w : L.warnings) warnings.push_back("posture '" + posture + "': " + w);
  rep.warnings = static_cast<int>(warnings.size());
  t << "  warnings (" << warnings.size() << "):\n";
  for (const auto& w : warnings) t << "    " << w << "\n";
  if (warnings.empty()) t << "    none\n";

  if (o.png != "-") {
    std::string png = o.png;
    if (png.empty()) png = (fs::path(o.input).parent_path() / (d.name + "_posture.png")).string();
    std::vector<std::pair<std::string, Eigen::Isometry3d>> frames;
    for (size_t f = 0; f < d.frames.size(); ++f) {
      if (!d.frames[f].from_data_file) continue;  // a link's own frame
      frames.emplace_back(d.frames[f].name, m.framePlacement(data, static_cast<model::FrameId>(f)));
    }
    rep.png = drawPicture(d, L, contacts, convexHull(flat), ground, frames, d.name + " in posture '" + posture + "'", png);
    t << "  picture: " << rep.png << "\n";
  }
  rep.text = t.str();
  return rep;
}

}  // namespace lexdyn::robot
