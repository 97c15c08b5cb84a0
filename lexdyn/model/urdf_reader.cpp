// The URDF pass of loading a robot. Two readings of the file:
//  1. TinyXML: structure, names, line numbers, file order, and every number lexdyn reads checked
//     with its line and attribute (urdfdom's own messages name neither the file nor the line);
//     what URDF itself ignores or leaves open is read the ecosystem's way, with a warning.
//  2. urdfdom, on the document with what URDF ignores removed (a fixed joint's axis, limits,
//     mimic), for the values; its messages are captured into the problem list.
// Then the bodies: links merged by fixed (and locked mimic) joints are lumped, and validity is
// checked on the lumped bodies, which are what Simbody and the controller see.
#include "lexdyn/model/detail/urdf_reader.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/common/input_text.hpp"
#include "lexdyn/model/inertia.hpp"
#include "lexdyn/model/resource_path.hpp"

#include <Eigen/Eigenvalues>
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <algorithm>
#include <map>
#include <set>
#include <sstream>

namespace lexdyn::model::detail {

namespace {

constexpr int kMaxLinks = 1000;
constexpr int kMaxJoints = 1000;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool validName(const std::string& n) { return !n.empty() && n.find_first_of(" \t\r\n,\"'") == std::string::npos; }
std::string fmt(double v) { return formatNumber(v); }
std::string at(const std::string& file, int line) { return line > 0 ? file + ":" + std::to_string(line) : file; }
std::string at(const std::string& file, const TiXmlElement* e) { return at(file, e ? e->Row() : 0); }
std::string attr(const TiXmlElement* e, const char* name) {
  const char* v = e ? e->Attribute(name) : nullptr;
  return v ? v : "";
}

// ---------------------------------------------------------------------------------------------
// Text-level guards
// ---------------------------------------------------------------------------------------------

// The deepest element nesting of an XML text and the line where it passes `limit`, found by a
// scan of the tags (comments, CDATA, processing instructions and declarations skipped), before
// any parser recurses on it: a URDF nested 100000 elements deep overflows the parsers' stacks.
void requireShallowXml(const std::string& text, const std::string& file, int limit) {
  int depth = 0, line = 1;
  const size_t n = text.size();
  auto skipTo = [&](size_t i, const char* end) {
    const size_t e = text.find(end, i);
    const size_t stop = e == std::string::npos ? n : e + std::char_traits<char>::length(end);
    for (size_t k = i; k < stop; ++k) line += text[k] == '\n';
    return stop;
  };
  for (size_t i = 0; i < n;) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (c != '<') {
      ++i;
      continue;
    }
    if (text.compare(i, 4, "<!--") == 0) {
      i = skipTo(i, "-->");
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      i = skipTo(i, "]]>");
    } else if (i + 1 < n && (text[i + 1] == '?' || text[i + 1] == '!')) {
      i = skipTo(i, ">");
    } else if (i + 1 < n && text[i + 1] == '/') {
      if (depth > 0) --depth;
      i = skipTo(i, ">");
    } else {
      const size_t start = i;
      i = skipTo(i, ">");
      const bool self_closing = i >= 2 && i - 2 > start && text[i - 2] == '/';
      if (!self_closing && ++depth > limit) {
        throw InputError(at(file, line), "elements are nested more than " + std::to_string(limit) +
                                             " deep (a URDF needs 4: robot, link, inertial, origin)");
      }
    }
  }
}

// A xacro file (ROS's XML macro language) is not a URDF: it must be expanded first. Generated
// URDFs keep the xmlns:xacro attribute and xacro in comments; only a xacro element (or the file
// name) says that the file was not expanded.
const TiXmlElement* firstXacroElement(const TiXmlElement* e) {
  if (std::string(e->Value()).rfind("xacro:", 0) == 0) return e;
  for (const TiXmlElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    if (const TiXmlElement* x = firstXacroElement(c)) return x;
  }
  return nullptr;
}

void refuseXacro(const TiXmlElement* robot, const std::string& file) {
  const TiXmlElement* x = firstXacroElement(robot);
  const bool named = file.size() >= 6 && file.compare(file.size() - 6, 6, ".xacro") == 0;
  if (x || named) {
    throw InputError(at(file, x ? x->Row() : robot->Row()),
                     std::string(x ? "<" + std::string(x->Value()) + ">: " : "") +
                         "this is a xacro file (ROS's XML macros), not a URDF: expand it first, e.g. `xacro " + file +
                         " > robot.urdf` where ROS's xacro package is installed, and give lexdyn the expanded file (many "
                         "description packages also ship an expanded .urdf beside the xacro)");
  }
}

// ---------------------------------------------------------------------------------------------
// Numbers, checked before urdfdom reads them
// ---------------------------------------------------------------------------------------------

// A URDF number attribute as urdfdom will read it: `count` whitespace-separated finite numbers,
// each within [lo, hi]. Absent: returns false and records nothing (urdfdom's default applies).
// Bad: records the error and returns false.
bool urdfNumbers(const TiXmlElement* e, const char* name, int count, double lo, double hi, const char* unit, const std::string& file,
                 const std::string& owner, ProblemList& problems, std::vector<double>* out = nullptr) {
  const char* raw = e ? e->Attribute(name) : nullptr;
  if (!raw) return false;
  const std::string where = at(file, e);
  const std::string what = owner + ": <" + std::string(e->Value()) + " " + name + "=\"" + raw + "\">: ";
  std::istringstream in{std::string(raw)};
  std::string tok;
  std::vector<double> values;
  while (in >> tok) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() + tok.size() || errno == ERANGE || !std::isfinite(v)) {
      problems.error(where, what + "expected finite numbers, found '" + tok + "'");
      return false;
    }
    if (!(v >= lo && v <= hi)) {
      problems.error(where, what + "expected values in [" + fmt(lo) + ", " + fmt(hi) + "]" + (*unit ? std::string(" ") + unit : "") +
                                ", found " + tok);
      return false;
    }
    values.push_back(v);
  }
  if (static_cast<int>(values.size()) != count) {
    problems.error(where, what + "expected " + std::to_string(count) + " number" + (count > 1 ? "s" : "") + ", found " +
                              std::to_string(values.size()));
    return false;
  }
  if (out) *out = values;
  return true;
}

void checkOrigin(const TiXmlElement* parent, const std::string& file, const std::string& owner, ProblemList& problems) {
  const TiXmlElement* o = parent ? parent->FirstChildElement("origin") : nullptr;
  urdfNumbers(o, "xyz", 3, -ranges::kMaxLength_m, ranges::kMaxLength_m, "m", file, owner, problems);
  urdfNumbers(o, "rpy", 3, -ranges::kMaxAngle_rad, ranges::kMaxAngle_rad, "rad", file, owner, problems);
}

constexpr double kAnyNumber = std::numeric_limits<double>::max();

// ---------------------------------------------------------------------------------------------
// The document's structure
// ---------------------------------------------------------------------------------------------
struct XmlLink {
  std::string name;
  int line = 0;
  TiXmlElement* e = nullptr;
};
struct XmlJoint {
  std::string name, type, parent, child;
  int line = 0;
  TiXmlElement* e = nullptr;
  bool has_mimic = false;
};
struct XmlIndex {
  std::string robot_name;
  std::vector<XmlLink> links;
  std::vector<XmlJoint> joints;
  std::string root;
  int lineOfLink(const std::string& name) const {
    for (const auto& l : links) {
      if (l.name == name) return l.line;
    }
    return 0;
  }
};

bool supportedType(const std::string& t) { return t == "revolute" || t == "continuous" || t == "prismatic" || t == "fixed"; }

// Names, references and the tree. Problems of one element do not stop the others; the tree is
// checked once every element is read.
void indexElements(TiXmlElement* robot, const std::string& file, XmlIndex& idx, ProblemList& problems) {
  std::map<std::string, int> link_line;
  for (TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const std::string n = attr(e, "name");
    if (n.empty()) {
      problems.error(at(file, e), "<link> without a name");
      continue;
    }
    if (!validName(n)) {
      problems.error(at(file, e), "link name '" + n + "' contains whitespace, a comma or a quote");
      continue;
    }
    if (link_line.count(n)) {
      problems.error(at(file, e), "duplicate link '" + n + "' (first defined on line " + std::to_string(link_line[n]) + ")");
      continue;
    }
    link_line[n] = e->Row();
    idx.links.push_back({n, e->Row(), e});
  }
  if (link_line.empty()) problems.fatal(file, "the URDF defines no <link>");

  std::map<std::string, int> joint_line;
  for (TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    XmlJoint j;
    j.line = e->Row();
    j.e = e;
    const std::string where = at(file, j.line);
    j.name = attr(e, "name");
    if (j.name.empty()) {
      problems.error(where, "<joint> without a name");
      continue;
    }
    if (!validName(j.name)) {
      problems.error(where, "joint name '" + j.name + "' contains whitespace, a comma or a quote");
      continue;
    }
    if (joint_line.count(j.name)) {
      problems.error(where, "duplicate joint '" + j.name + "' (first defined on line " + std::to_string(joint_line[j.name]) + ")");
      continue;
    }
    joint_line[j.name] = j.line;
    const char* t = e->Attribute("type");
    if (!t) {
      problems.error(where, "joint '" + j.name + "' has no type");
      continue;
    }
    j.type = t;
    const TiXmlElement* p = e->FirstChildElement("parent");
    const TiXmlElement* c = e->FirstChildElement("child");
    bool ok = true;
    if (!p || !p->Attribute("link")) {
      problems.error(where, "joint '" + j.name + "' has no <parent link=...>");
      ok = false;
    }
    if (!c || !c->Attribute("link")) {
      problems.error(where, "joint '" + j.name + "' has no <child link=...>");
      ok = false;
    }
    if (!ok) continue;
    j.parent = attr(p, "link");
    j.child = attr(c, "link");
    if (!link_line.count(j.parent)) {
      problems.error(at(file, p), "joint '" + j.name + "': parent link '" + j.parent + "' is not defined");
      ok = false;
    }
    if (!link_line.count(j.child)) {
      problems.error(at(file, c), "joint '" + j.name + "': child link '" + j.child + "' is not defined");
      ok = false;
    }
    if (ok && j.parent == j.child) {
      problems.error(where, "joint '" + j.name + "' connects link '" + j.parent + "' to itself");
      ok = false;
    }
    if (!supportedType(j.type) && j.type != "floating") {
      problems.error(where, "joint '" + j.name + "': type '" + j.type +
                                "' is not supported (revolute, continuous, prismatic, fixed; floating only from a massless root link)");
    }
    j.has_mimic = e->FirstChildElement("mimic") != nullptr;
    if (ok) idx.joints.push_back(j);
  }
  problems.throwIfErrors();

  // Tree: every link has at most one parent joint, exactly one root, no cycle.
  std::map<std::string, const XmlJoint*> parent_of;
  for (const auto& j : idx.joints) {
    auto it = parent_of.find(j.child);
    if (it != parent_of.end()) {
      problems.error(at(file, j.line), "link '" + j.child + "' is the child of two joints ('" + it->second->name + "' and '" + j.name +
                                           "'); a URDF must be a tree");
      continue;
    }
    parent_of[j.child] = &j;
  }
  problems.throwIfErrors();
  std::vector<std::string> roots;
  for (const auto& l : idx.links) {
    if (!parent_of.count(l.name)) roots.push_back(l.name);
  }
  if (roots.size() != 1) {
    std::string list;
    for (const auto& r : roots) list += (list.empty() ? "" : ", ") + r;
    problems.fatal(file, "expected exactly one root link, found " + std::to_string(roots.size()) +
                             (roots.empty() ? " (the joints form a cycle)" : ": " + list));
  }
  idx.root = roots[0];
  // Every link reachable from the root: a cycle of joints detached from the tree leaves one root
  // but links no walk from it reaches (and urdfdom would build a cycle of shared pointers).
  std::map<std::string, std::vector<const XmlJoint*>> children_of;
  for (const auto& j : idx.joints) children_of[j.parent].push_back(&j);
  std::set<std::string> reached{idx.root};
  std::vector<std::string> stack{idx.root};
  while (!stack.empty()) {
    const std::string l = stack.back();
    stack.pop_back();
    for (const XmlJoint* j : children_of[l]) {
      if (reached.insert(j->child).second) stack.push_back(j->child);
    }
  }
  for (const auto& l : idx.links) {
    if (!reached.count(l.name)) {
      const XmlJoint* j = parent_of.at(l.name);
      problems.error(at(file, j->line), "link '" + l.name + "' is not connected to the root link '" + idx.root + "': its joint '" +
                                            j->name + "' hangs it from '" + j->parent +
                                            "', and the joints form a cycle there; a URDF must be a tree");
    }
  }
  problems.throwIfErrors();
}

// ---------------------------------------------------------------------------------------------
// Numbers of links and joints, and the elements URDF ignores
// ---------------------------------------------------------------------------------------------
void checkLinkNumbers(const XmlLink& l, const std::string& file, ProblemList& problems) {
  const std::string owner = "link '" + l.name + "'";
  const TiXmlElement* in = l.e->FirstChildElement("inertial");
  if (!in) return;
  checkOrigin(in, file, owner, problems);
  const TiXmlElement* mass = in->FirstChildElement("mass");
  if (!mass || !mass->Attribute("value")) {
    problems.error(at(file, in), owner + ": <inertial> needs <mass value=\"...\"/>");
  } else {
    std::vector<double> m;
    if (urdfNumbers(mass, "value", 1, -kAnyNumber, kAnyNumber, "kg", file, owner, problems, &m)) {
      if (m[0] < 0.0) {
        problems.error(at(file, mass), owner + ": mass must be > 0, found " + fmt(m[0]));
      } else if (m[0] > ranges::kMaxLinkMass_kg || (m[0] > 0.0 && m[0] < ranges::kMinLinkMass_kg)) {
        problems.error(at(file, mass), owner + ": mass must be in [" + fmt(ranges::kMinLinkMass_kg) + ", " + fmt(ranges::kMaxLinkMass_kg) +
                                           "] kg (or 0 for a massless fixed part), found " + fmt(m[0]));
      }
    }
  }
  const TiXmlElement* inertia = in->FirstChildElement("inertia");
  if (!inertia) {
    problems.error(at(file, in), owner + ": <inertial> needs <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=.../>");
    return;
  }
  for (const char* a : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
    if (!inertia->Attribute(a)) {
      problems.error(at(file, inertia), owner + ": <inertia> has no " + a + " attribute");
      continue;
    }
    urdfNumbers(inertia, a, 1, -ranges::kMaxPrincipalInertia_kgm2, ranges::kMaxPrincipalInertia_kgm2, "kg m^2", file, owner, problems);
  }
}

// The geometry numbers urdfdom reads (it refuses a file whose shapes it cannot read).
void checkGeometryNumbers(const XmlLink& l, const std::string& file, ProblemList& problems) {
  const std::string owner = "link '" + l.name + "'";
  for (const char* kind : {"visual", "collision"}) {
    for (const TiXmlElement* v = l.e->FirstChildElement(kind); v; v = v->NextSiblingElement(kind)) {
      checkOrigin(v, file, owner, problems);
      const TiXmlElement* g = v->FirstChildElement("geometry");
      const TiXmlElement* s = g ? g->FirstChildElement() : nullptr;
      if (!s) {
        problems.error(at(file, v), owner + ": <" + kind + "> needs a <geometry> with a box, sphere, cylinder or mesh");
        continue;
      }
      const std::string shape = s->Value();
      const double L = ranges::kMaxLength_m;
      if (shape == "box") {
        if (!s->Attribute("size")) problems.error(at(file, s), owner + ": <box> needs size=\"x y z\"");
        urdfNumbers(s, "size", 3, 0.0, L, "m", file, owner, problems);
      } else if (shape == "sphere") {
        if (!s->Attribute("radius")) problems.error(at(file, s), owner + ": <sphere> needs radius=\"...\"");
        urdfNumbers(s, "radius", 1, 0.0, L, "m", file, owner, problems);
      } else if (shape == "cylinder" || shape == "capsule") {
        if (!s->Attribute("radius") || !s->Attribute("length"))
          problems.error(at(file, s), owner + ": <" + shape + "> needs radius and length");
        urdfNumbers(s, "radius", 1, 0.0, L, "m", file, owner, problems);
        urdfNumbers(s, "length", 1, 0.0, L, "m", file, owner, problems);
      } else if (shape == "mesh") {
        if (attr(s, "filename").empty()) problems.error(at(file, s), owner + ": <mesh> needs filename=\"...\"");
        urdfNumbers(s, "scale", 3, -L, L, "", file, owner, problems);
      } else {
        problems.error(at(file, s), owner + ": unknown geometry <" + shape + "> (box, sphere, cylinder, mesh)");
      }
    }
  }
}

// What a fixed joint carries that URDF ignores (an axis, limits, a mimic, dynamics), removed before
// urdfdom reads the document (urdfdom refuses the limits of a fixed joint when incomplete).
// Returns the names of the elements removed, but for an `<axis xyz="0 0 0"/>`, which exporters
// write on every fixed joint (nothing is lost by ignoring it), unless `strict` (whose older rules
// refuse it too).
std::vector<std::string> stripFixedJointExtras(TiXmlElement* e, bool strict) {
  std::vector<std::string> removed;
  for (const char* name : {"axis", "limit", "mimic", "dynamics", "safety_controller", "calibration"}) {
    while (TiXmlElement* c = e->FirstChildElement(name)) {
      bool zero_axis = false;
      if (!strict && std::string(name) == "axis" && c->Attribute("xyz")) {
        std::istringstream in(c->Attribute("xyz"));
        double x = 1.0, y = 1.0, z = 1.0;
        std::string rest;
        zero_axis = static_cast<bool>(in >> x >> y >> z) && !(in >> rest) && x == 0.0 && y == 0.0 && z == 0.0;
      }
      if (!zero_axis) removed.push_back(name);
      e->RemoveChild(c);
    }
  }
  return removed;
}

void checkJointNumbers(const XmlJoint& j, const std::string& file, ProblemList& problems) {
  const std::string owner = "joint '" + j.name + "'";
  checkOrigin(j.e, file, owner, problems);
  if (j.type == "fixed" || j.type == "floating") return;  // nothing else of theirs is read
  const TiXmlElement* axis = j.e->FirstChildElement("axis");
  std::vector<double> a;
  if (urdfNumbers(axis, "xyz", 3, -ranges::kMaxLength_m, ranges::kMaxLength_m, "", file, owner, problems, &a) &&
      std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) < 1e-6) {
    problems.error(at(file, axis), owner + ": <axis> must be a non-zero vector (norm >= 1e-6)");
  }
  const TiXmlElement* lim = j.e->FirstChildElement("limit");
  if (!lim) {
    if (j.type != "continuous") {
      problems.error(at(file, j.line), owner + ": a <limit effort=... velocity=...> element is required (URDF requires <limit> on " +
                                           j.type + " joints; urdfdom and ROS refuse the file too)");
    }
    return;
  }
  urdfNumbers(lim, "lower", 1, -ranges::kMaxJointLimit, ranges::kMaxJointLimit, "(rad or m)", file, owner, problems);
  urdfNumbers(lim, "upper", 1, -ranges::kMaxJointLimit, ranges::kMaxJointLimit, "(rad or m)", file, owner, problems);
  for (const auto& [name, label, lo, hi, unit] :
       {std::tuple<const char*, const char*, double, double, const char*>{"effort", "effort limit", ranges::kMinEffortLimit,
                                                                          ranges::kMaxEffortLimit, "N m or N"},
        {"velocity", "velocity limit", ranges::kMinVelocityLimit, ranges::kMaxVelocityLimit, "rad/s or m/s"}}) {
    if (!lim->Attribute(name)) {
      problems.error(at(file, lim), owner + ": <limit> has no " + name + " attribute (URDF requires it; urdfdom refuses the file too)");
      continue;
    }
    std::vector<double> v;
    if (!urdfNumbers(lim, name, 1, -kAnyNumber, kAnyNumber, unit, file, owner, problems, &v)) continue;
    if (v[0] < 0.0) {
      problems.error(at(file, lim), owner + ": " + label + " must be > 0, found " + fmt(v[0]));
    } else if (v[0] > 0.0 && (v[0] < lo || v[0] > hi)) {
      problems.error(at(file, lim),
                     owner + ": " + label + " must be in [" + fmt(lo) + ", " + fmt(hi) + "] " + unit + ", found " + fmt(v[0]));
    }
  }
  if (const TiXmlElement* m = j.e->FirstChildElement("mimic")) {
    if (attr(m, "joint").empty()) problems.error(at(file, m), owner + ": <mimic> needs joint=\"...\"");
    urdfNumbers(m, "multiplier", 1, -1e3, 1e3, "", file, owner, problems);
    urdfNumbers(m, "offset", 1, -ranges::kMaxJointLimit, ranges::kMaxJointLimit, "(rad or m)", file, owner, problems);
  }
}

// urdfdom's own messages (console_bridge), captured while it parses.
class CapturedMessages : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) lines.push_back(text);
  }
  std::vector<std::string> lines;
};

urdf::ModelInterfaceSharedPtr parseWithUrdfdom(const TiXmlDocument& doc, const std::string& file, ProblemList& problems) {
  TiXmlPrinter printer;
  doc.Accept(&printer);
  CapturedMessages captured;
  console_bridge::useOutputHandler(&captured);
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(printer.CStr());
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    std::string said;
    for (const std::string& l : captured.lines) said += (said.empty() ? "" : "; ") + l;
    problems.fatal(file, "urdfdom could not read the file" + (said.empty() ? std::string() : ": " + said));
  }
  return model;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond quat(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  X.linear() = quat.normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return X;
}

// ---------------------------------------------------------------------------------------------
// Mass properties
// ---------------------------------------------------------------------------------------------
struct MassProps {
  double mass = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< about the CoM
};

// Lumps `add` (given in the frame X_body_add relative to the body) into `body`.
void lump(MassProps& body, const MassProps& add, const Eigen::Isometry3d& X_body_add) {
  if (add.mass == 0.0) return;
  const double m = body.mass + add.mass;
  const Eigen::Vector3d c_add = X_body_add * add.com;
  const Eigen::Vector3d com = (body.mass * body.com + add.mass * c_add) / m;
  auto shifted = [](const Eigen::Matrix3d& I, double mass, const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(I + mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  const Eigen::Matrix3d I_add = X_body_add.linear() * add.inertia * X_body_add.linear().transpose();
  body.inertia = shifted(body.inertia, body.mass, body.com - com) + shifted(I_add, add.mass, c_add - com);
  body.com = com;
  body.mass = m;
}

// One link's mass properties in its own frame, as the file gives them. Their validity is judged on
// the lumped bodies (checkBodies); a link's own impossible inertia is noted (an error in strict mode).
MassProps linkMassProps(const urdf::Link& link, const std::string& where, bool lumped, ProblemList& problems) {
  MassProps mp;
  if (!link.inertial || link.inertial->mass == 0.0) return mp;
  const urdf::Inertial& in = *link.inertial;
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const InertiaCheck c = checkInertia(I);
  const std::string owner = "link '" + link.name + "'";
  if (problems.strict() && c.kind != InertiaClass::Valid) {
    problems.error(where, owner + ": inertia " +
                              (c.kind == InertiaClass::Zero ? std::string("is zero (mass ") + fmt(in.mass) + " kg)"
                                                            : "is not physically possible: " + c.problem) +
                              " (refused in strict mode)");
  } else if (lumped && c.kind == InertiaClass::Impossible) {
    problems.warning(where, owner + ": its own inertia is not physically possible (" + c.problem +
                                "); it is lumped into its parent body, which is checked instead");
  } else if (lumped && c.kind == InertiaClass::Zero) {
    problems.warning(where, owner + ": mass " + fmt(in.mass) + " kg with a zero inertia: lumped as a point mass at its <inertial> origin");
  }
  if (c.kind == InertiaClass::Zero) I.setZero();
  const Eigen::Isometry3d X = toIsometry(in.origin);
  mp.mass = in.mass;
  mp.com = X.translation();
  mp.inertia = X.linear() * (0.5 * (I + I.transpose())) * X.linear().transpose();
  return mp;
}

// The transform of a one-dof joint at q (revolute about / prismatic along `axis`).
Eigen::Isometry3d jointMotion(JointType type, const Eigen::Vector3d& axis, double q) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  if (type == JointType::Revolute) {
    X.linear() = Eigen::AngleAxisd(q, axis).toRotationMatrix();
  } else {
    X.translation() = q * axis;
  }
  return X;
}

// ---------------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------------
void readGeometry(const XmlLink& l, int body, const Eigen::Isometry3d& X_body_link, const std::string& file,
                  const std::vector<std::string>& search, const LoadOptions& options, RobotDescription& d, ProblemList& problems) {
  for (const char* kind : {"visual", "collision"}) {
    for (const TiXmlElement* v = l.e->FirstChildElement(kind); v; v = v->NextSiblingElement(kind)) {
      const TiXmlElement* s = v->FirstChildElement("geometry")->FirstChildElement();
      GeometryDescription g;
      g.collision = std::string(kind) == "collision";
      g.link = body;
      g.urdf_link = l.name;
      g.urdf_line = s->Row();
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      if (const TiXmlElement* o = v->FirstChildElement("origin")) {
        std::vector<double> xyz, rpy;
        if (urdfNumbers(o, "xyz", 3, -kAnyNumber, kAnyNumber, "", file, "", problems, &xyz))
          X.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        if (urdfNumbers(o, "rpy", 3, -kAnyNumber, kAnyNumber, "", file, "", problems, &rpy))
          X.linear() = rotationFromRpy(Eigen::Vector3d(rpy[0], rpy[1], rpy[2]));
      }
      g.placement = X_body_link * X;
      const std::string shape = s->Value();
      std::vector<double> v3, v1;
      if (shape == "box") {
        g.type = GeometryType::Box;
        if (urdfNumbers(s, "size", 3, -kAnyNumber, kAnyNumber, "", file, "", problems, &v3)) g.size = Eigen::Vector3d(v3[0], v3[1], v3[2]);
      } else if (shape == "sphere") {
        g.type = GeometryType::Sphere;
        if (urdfNumbers(s, "radius", 1, -kAnyNumber, kAnyNumber, "", file, "", problems, &v1)) g.radius = v1[0];
      } else if (shape == "cylinder" || shape == "capsule") {
        g.type = GeometryType::Cylinder;
        if (urdfNumbers(s, "radius", 1, -kAnyNumber, kAnyNumber, "", file, "", problems, &v1)) g.radius = v1[0];
        if (urdfNumbers(s, "length", 1, -kAnyNumber, kAnyNumber, "", file, "", problems, &v1)) g.length = v1[0];
      } else {
        g.type = GeometryType::Mesh;
        g.mesh_uri = attr(s, "filename");
        if (urdfNumbers(s, "scale", 3, -kAnyNumber, kAnyNumber, "", file, "", problems, &v3))
          g.scale = Eigen::Vector3d(v3[0], v3[1], v3[2]);
        const ResolvedResource r = resolveResource(g.mesh_uri, file, search);
        g.mesh_path = r.path;
        if (r.path.empty()) {
          const std::string msg = "link '" + l.name + "': <" + std::string(kind) + "> mesh '" + g.mesh_uri + "' not found: " + r.searched;
          if (options.require_meshes) {
            problems.error(at(file, s),
                           msg + (r.package_found ? " (the package is there without the file; --allow-missing-meshes goes on without it)"
                                                  : " (give --package-path, or --allow-missing-meshes to go on without it)"));
          } else {
            problems.warning(at(file, s), msg + " (not needed by the dynamics; robot init, robot check and the replay need it)");
          }
        }
      }
      d.geometries.push_back(g);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The bodies
// ---------------------------------------------------------------------------------------------
// A coupled mimic joint: its independent master (a mimic of a mimic composed down to it).
struct Coupling {
  std::string master;
  double multiplier = 1.0, offset = 0.0;
  int line = 0;
};

struct TreeBuilder {
  const XmlIndex& idx;
  const urdf::ModelInterface& model;
  const std::string& file;
  const BaseType base;
  const MimicPolicy& mimic;
  const LoadOptions& options;
  RobotDescription& d;
  ProblemList& problems;
  std::vector<std::string> search;
  std::vector<MassProps> body_mass;
  std::map<std::string, const XmlLink*> xml_link;
  std::map<std::string, const XmlJoint*> xml_joint;
  std::map<std::string, double> locked;     // mimic joint -> locked value
  std::map<std::string, Coupling> coupled;  // coupled mimic joint -> its master

  const urdf::Link& link(const std::string& name) const {
    auto it = model.links_.find(name);
    LEXDYN_ALWAYS_ASSERT(it != model.links_.end() && it->second, "urdfdom lost link " + name);
    return *it->second;
  }
  const urdf::Joint& joint(const std::string& name) const {
    auto it = model.joints_.find(name);
    LEXDYN_ALWAYS_ASSERT(it != model.joints_.end() && it->second, "urdfdom lost joint " + name);
    return *it->second;
  }
  std::string whereLink(const std::string& name) const { return at(file, idx.lineOfLink(name)); }

  // Strict mode: a link that is a body of its own (moving, or the free-flyer base) has mass itself,
  // not only through the links lumped into it.
  void strictOwnMass(const std::string& name) {
    if (!problems.strict()) return;
    const urdf::Link& l = link(name);
    if (!l.inertial) {
      problems.error(whereLink(name), "link '" + name + "' has no <inertial> (a moving body needs mass > 0; refused in strict mode)");
    } else if (!(l.inertial->mass > 0.0)) {
      problems.error(whereLink(name), "link '" + name + "': mass must be > 0, found 0 (a moving body; refused in strict mode)");
    }
  }

  void addFrameAndGeometry(const std::string& link_name, int body, const Eigen::Isometry3d& X_body_link) {
    FrameDescription f;
    f.name = link_name;
    f.link = body;
    f.placement = X_body_link;
    d.frames.push_back(f);
    readGeometry(*xml_link.at(link_name), body, X_body_link, file, search, options, d, problems);
  }

  // A moving joint's type, axis and limits, read the ecosystem's way.
  JointDescription movingJoint(const XmlJoint& xj, const urdf::Joint& uj, int body, const Eigen::Isometry3d& X_body_joint) {
    JointDescription jd;
    jd.name = xj.name;
    jd.urdf_line = xj.line;
    jd.parent_link = body;
    jd.origin = X_body_joint;
    jd.type = uj.type == urdf::Joint::PRISMATIC ? JointType::Prismatic : JointType::Revolute;
    const Eigen::Vector3d axis(uj.axis.x, uj.axis.y, uj.axis.z);
    jd.axis = axis.norm() > 0.0 ? axis.normalized() : Eigen::Vector3d::UnitX();
    jd.continuous = uj.type == urdf::Joint::CONTINUOUS;
    if (jd.continuous) {
      jd.lower = -kInf;
      jd.upper = kInf;
    } else {
      const TiXmlElement* lim = xj.e->FirstChildElement("limit");
      const bool given = lim && (lim->Attribute("lower") || lim->Attribute("upper"));
      jd.lower = uj.limits->lower;
      jd.upper = uj.limits->upper;
      if (!given && jd.lower == 0.0 && jd.upper == 0.0) {
        jd.lower = -kInf;
        jd.upper = kInf;
      } else if (jd.lower == 0.0 && jd.upper == 0.0 && !problems.strict()) {
        // lower="0" upper="0": what CAD exporters write for "not set"; read as no limits (the
        // joint is listed with those without a range; strict mode refuses it).
        jd.lower = -kInf;
        jd.upper = kInf;
      } else if (!(jd.lower < jd.upper)) {
        problems.error(at(file, xj.line),
                       "joint '" + xj.name + "': expected limit lower < upper, found lower=" + fmt(jd.lower) + " upper=" + fmt(jd.upper));
      }
    }
    jd.effort_limit = uj.limits ? uj.limits->effort : 0.0;
    jd.velocity_limit = uj.limits ? uj.limits->velocity : 0.0;
    if (!(jd.effort_limit > 0.0)) jd.effort_limit = kInf;
    if (!(jd.velocity_limit > 0.0)) jd.velocity_limit = kInf;
    return jd;
  }

  // Depth-first, pre-order; siblings in file order. A fixed joint (or a locked mimic joint) merges
  // its child link into the current body (mass lumped, link kept as a frame).
  void visit(const std::string& link_name, int body, const Eigen::Isometry3d& X_body_link) {
    for (const auto& xj : idx.joints) {
      if (xj.parent != link_name) continue;
      const urdf::Joint& uj = joint(xj.name);
      const Eigen::Isometry3d X_body_joint = X_body_link * toIsometry(uj.parent_to_joint_origin_transform);
      if (uj.type == urdf::Joint::FIXED || locked.count(xj.name)) {
        Eigen::Isometry3d X_body_child = X_body_joint;
        if (locked.count(xj.name)) {
          const Eigen::Vector3d axis(uj.axis.x, uj.axis.y, uj.axis.z);
          X_body_child = X_body_joint * jointMotion(uj.type == urdf::Joint::PRISMATIC ? JointType::Prismatic : JointType::Revolute,
                                                    axis.norm() > 0.0 ? axis.normalized() : Eigen::Vector3d::UnitX(), locked.at(xj.name));
        }
        lump(body_mass[static_cast<size_t>(body)], linkMassProps(link(xj.child), whereLink(xj.child), true, problems), X_body_child);
        d.links[static_cast<size_t>(body)].merged_links.push_back(xj.child);
        addFrameAndGeometry(xj.child, body, X_body_child);
        visit(xj.child, body, X_body_child);
        continue;
      }
      JointDescription jd = movingJoint(xj, uj, body, X_body_joint);
      if (coupled.count(xj.name)) {
        // A coupled mimic joint: a body of its own, not a model joint (its master is resolved once
        // every joint is read).
        CoupledJointDescription cj;
        cj.name = jd.name;
        cj.type = jd.type;
        cj.parent_link = body;
        cj.origin = jd.origin;
        cj.axis = jd.axis;
        cj.lower = jd.lower;
        cj.upper = jd.upper;
        cj.velocity_limit = jd.velocity_limit;
        cj.multiplier = coupled.at(xj.name).multiplier;
        cj.offset = coupled.at(xj.name).offset;
        cj.urdf_line = xj.line;
        const int child_body = static_cast<int>(d.links.size());
        cj.child_link = child_body;
        LinkDescription ld;
        ld.name = xj.child;
        ld.parent_coupled = static_cast<int>(d.coupled_joints.size());
        ld.urdf_line = idx.lineOfLink(xj.child);
        d.links.push_back(ld);
        d.coupled_joints.push_back(cj);
        strictOwnMass(xj.child);
        body_mass.push_back(linkMassProps(link(xj.child), whereLink(xj.child), false, problems));
        addFrameAndGeometry(xj.child, child_body, Eigen::Isometry3d::Identity());
        visit(xj.child, child_body, Eigen::Isometry3d::Identity());
        continue;
      }
      const int child_body = static_cast<int>(d.links.size());
      jd.child_link = child_body;
      LinkDescription ld;
      ld.name = xj.child;
      ld.parent_joint = static_cast<int>(d.joints.size());
      ld.urdf_line = idx.lineOfLink(xj.child);
      d.links.push_back(ld);
      d.joints.push_back(jd);
      strictOwnMass(xj.child);
      body_mass.push_back(linkMassProps(link(xj.child), whereLink(xj.child), false, problems));
      addFrameAndGeometry(xj.child, child_body, Eigen::Isometry3d::Identity());
      visit(xj.child, child_body, Eigen::Isometry3d::Identity());
    }
  }
};

// The joints URDF reads as mimics and the value each locked one is held at.
void readMimics(const XmlIndex& idx, const urdf::ModelInterface& model, const std::string& file, const MimicPolicy& policy,
                RobotDescription& d, ProblemList& problems, std::map<std::string, double>& locked,
                std::map<std::string, Coupling>& coupled) {
  std::map<std::string, const XmlJoint*> by_name;
  for (const auto& j : idx.joints) by_name[j.name] = &j;
  for (const auto& xj : idx.joints) {
    if (!xj.has_mimic) continue;
    if (xj.type == "fixed") continue;  // stripped (and noted) with the fixed joints' other extras
    const urdf::Joint& uj = *model.joints_.at(xj.name);
    if (!uj.mimic) continue;
    const TiXmlElement* m = xj.e->FirstChildElement("mimic");
    MimicDescription md;
    md.joint = xj.name;
    md.master = uj.mimic->joint_name;
    md.multiplier = uj.mimic->multiplier;
    md.offset = uj.mimic->offset;
    md.urdf_line = m ? m->Row() : xj.line;
    md.mode = policy.mode;
    auto master = by_name.find(md.master);
    if (master == by_name.end() || master->second->type == "fixed" || master->second->type == "floating") {
      problems.error(at(file, md.urdf_line),
                     "joint '" + xj.name + "': <mimic joint=\"" + md.master + "\"> names " +
                         (master == by_name.end() ? "no joint of the URDF" : "a " + master->second->type + " joint"));
      continue;
    }
    d.mimics.push_back(md);
  }
  // Cycles (a mimic of a mimic of ... itself): an error naming the cycle; its joints are no
  // mimics from here on (so that the chains below end).
  {
    std::map<std::string, const MimicDescription*> of;
    for (const auto& md : d.mimics) of[md.joint] = &md;
    std::set<std::string> cyclic;
    for (const auto& md : d.mimics) {
      std::vector<std::string> path{md.joint};
      std::string cur = md.master;
      while (of.count(cur) && std::find(path.begin(), path.end(), cur) == path.end() && !cyclic.count(cur)) {
        path.push_back(cur);
        cur = of.at(cur)->master;
      }
      if (cur != md.joint) continue;  // ends at an independent joint (or joins another's cycle)
      std::string text;
      for (const auto& j : path) text += "'" + j + "' -> ";
      problems.error(at(file, md.urdf_line), "joint '" + md.joint + "': its <mimic> joints form a cycle (" + text + "'" + md.joint +
                                                 "'): one of them must be independent");
      for (const auto& j : path) cyclic.insert(j);
    }
    d.mimics.erase(std::remove_if(d.mimics.begin(), d.mimics.end(), [&](const MimicDescription& m) { return cyclic.count(m.joint) > 0; }),
                   d.mimics.end());
  }
  // Locked values: the master's value in the posture (0 when none), through chains of mimics.
  std::function<double(const std::string&, int)> valueOf = [&](const std::string& joint, int depth) -> double {
    for (const auto& md : d.mimics) {
      if (md.joint == joint) {
        LEXDYN_ALWAYS_ASSERT(depth <= static_cast<int>(d.mimics.size()), "mimic chain longer than the mimics: a cycle was not caught");
        return md.multiplier * valueOf(md.master, depth + 1) + md.offset;
      }
    }
    auto it = policy.master_values.find(joint);
    const urdf::Joint& uj = *model.joints_.at(joint);
    double v = it != policy.master_values.end() ? it->second : 0.0;
    if (uj.type != urdf::Joint::CONTINUOUS && uj.limits && uj.limits->lower < uj.limits->upper) {
      v = std::min(std::max(v, uj.limits->lower), uj.limits->upper);
    }
    return v;
  };
  // Coupled: composed down to the independent master.
  std::function<Coupling(const std::string&, int)> composed = [&](const std::string& joint, int depth) -> Coupling {
    for (const auto& md : d.mimics) {
      if (md.joint != joint) continue;
      LEXDYN_ALWAYS_ASSERT(depth <= static_cast<int>(d.mimics.size()), "mimic chain longer than the mimics: a cycle was not caught");
      Coupling inner = composed(md.master, depth + 1);
      return {inner.master, md.multiplier * inner.multiplier, md.multiplier * inner.offset + md.offset, md.urdf_line};
    }
    return {joint, 1.0, 0.0, 0};
  };
  for (auto& md : d.mimics) {
    if (md.mode != MimicMode::Coupled) continue;
    Coupling c = composed(md.joint, 0);
    c.line = md.urdf_line;
    coupled[md.joint] = c;
  }
  // One warning per master: "joints 'a' (locked at x), 'b' (at y) mimic 'm' ...".
  std::vector<std::string> masters;
  std::map<std::string, std::string> locked_text;
  std::map<std::string, int> first_line;
  for (auto& md : d.mimics) {
    if (md.mode != MimicMode::Locked) continue;
    double v = valueOf(md.joint, 0);
    const urdf::Joint& uj = *model.joints_.at(md.joint);
    std::string clamped;
    if (uj.type != urdf::Joint::CONTINUOUS && uj.limits && uj.limits->lower < uj.limits->upper &&
        (v < uj.limits->lower || v > uj.limits->upper)) {
      const double c = std::min(std::max(v, uj.limits->lower), uj.limits->upper);
      clamped = ", clamped into its limits from " + fmt(v);
      v = c;
    }
    md.locked_value = v;
    locked[md.joint] = v;
    d.locked_joints.push_back({md.joint, v, "mimic"});
    if (!locked_text.count(md.master)) {
      masters.push_back(md.master);
      first_line[md.master] = md.urdf_line;
    }
    std::string& t = locked_text[md.master];
    t += std::string(t.empty() ? "" : ", ") + "'" + md.joint + "' (x " + fmt(md.multiplier) +
         (md.offset != 0.0 ? " + " + fmt(md.offset) : "") + ": locked at " + fmt(v) + clamped + ")";
  }
  for (const std::string& m : masters) {
    const std::string source = policy.posture.empty() ? "'" + m + "' at " + fmt(valueOf(m, 0))
                                                      : "'" + m + "' at " + fmt(valueOf(m, 0)) + " in posture '" + policy.posture + "'";
    const std::string what = "mimic joints of '" + m + "': " + locked_text[m] + "; from " + source;
    problems.warning(at(file, first_line[m]), what);
  }
}

// Coupled mimic joints: one note per master (once the locking is done), a warning without the
// data file's `mimic` (strict: an error).
void noteCoupled(const std::string& file, const MimicPolicy& policy, const std::map<std::string, Coupling>& coupled,
                 ProblemList& problems) {
  std::vector<std::string> coupled_masters;
  std::map<std::string, std::string> coupled_text;
  std::map<std::string, int> coupled_line;
  for (const auto& [joint, c] : coupled) {
    if (!coupled_text.count(c.master)) {
      coupled_masters.push_back(c.master);
      coupled_line[c.master] = c.line;
    }
    std::string& t = coupled_text[c.master];
    t += std::string(t.empty() ? "" : ", ") + "'" + joint + "' = " + fmt(c.multiplier) + " q" +
         (c.offset != 0.0 ? " + " + fmt(c.offset) : "");
  }
  for (const std::string& m : coupled_masters) {
    const std::string what = "mimic joints coupled to '" + m + "' (q its coordinate): " + coupled_text[m] +
                             "; they move with it in the controller's model and in the simulator";
    if (policy.given) {
      problems.warning(at(file, coupled_line[m]), what);
    } else {
      problems.lenient(at(file, coupled_line[m]), what + " (`mimic: {mode: locked}` in the data file holds them at the posture instead)");
    }
  }
}

// What each body's joint moves at q = 0: the composite inertia of the joint's subtree about its
// axis (the mass matrix's diagonal there; kg for a prismatic joint), and for the root the smallest
// principal moment of the whole robot about its centre of mass.
std::vector<double> jointInertias(const RobotDescription& d) {
  const size_t nb = d.links.size();
  std::vector<Eigen::Isometry3d> X(nb, Eigen::Isometry3d::Identity());
  for (size_t b = 1; b < nb; ++b) X[b] = X[static_cast<size_t>(d.parentBody(static_cast<int>(b)))] * d.jointOrigin(static_cast<int>(b));
  // Subtree mass, first moment and inertia about the world origin (children after parents).
  std::vector<double> m(nb, 0.0);
  std::vector<Eigen::Vector3d> h(nb, Eigen::Vector3d::Zero());
  std::vector<Eigen::Matrix3d> I(nb, Eigen::Matrix3d::Zero());
  for (size_t b = nb; b-- > 0;) {
    const LinkDescription& L = d.links[b];
    const Eigen::Vector3d c = X[b] * L.com;
    const Eigen::Matrix3d R = X[b].linear();
    m[b] += L.mass;
    h[b] += L.mass * c;
    I[b] += R * L.inertia * R.transpose() + L.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    if (b > 0) {
      const size_t p = static_cast<size_t>(d.parentBody(static_cast<int>(b)));
      m[p] += m[b];
      h[p] += h[b];
      I[p] += I[b];
    }
  }
  // Inertia about a point o from the one about the origin: I_o = I_0 - m (|c|^2 1 - c c^T) + m (|c - o|^2 1 - (c - o)(c - o)^T).
  auto about = [&](size_t b, const Eigen::Vector3d& o) {
    if (!(m[b] > 0.0)) return Eigen::Matrix3d(I[b]);
    const Eigen::Vector3d c = h[b] / m[b], r = c - o;
    return Eigen::Matrix3d(I[b] - m[b] * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose()) +
                           m[b] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose()));
  };
  std::vector<double> out(nb, 0.0);
  {
    const Eigen::Vector3d c = m[0] > 0.0 ? Eigen::Vector3d(h[0] / m[0]) : Eigen::Vector3d::Zero();
    const Eigen::Matrix3d Ic = about(0, c);
    out[0] = m[0] > 0.0
                 ? Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (Ic + Ic.transpose()), Eigen::EigenvaluesOnly).eigenvalues()[0]
                 : 0.0;
  }
  for (size_t b = 1; b < nb; ++b) {
    const LinkDescription& L = d.links[b];
    const Eigen::Vector3d axis = L.parent_joint >= 0 ? d.joints[static_cast<size_t>(L.parent_joint)].axis
                                                     : d.coupled_joints[static_cast<size_t>(L.parent_coupled)].axis;
    const JointType type = L.parent_joint >= 0 ? d.joints[static_cast<size_t>(L.parent_joint)].type
                                               : d.coupled_joints[static_cast<size_t>(L.parent_coupled)].type;
    const Eigen::Vector3d a = X[b].linear() * axis;
    out[b] = type == JointType::Prismatic ? m[b] : a.dot(about(b, X[b].translation()) * a);
  }
  return out;
}

constexpr double kNegligibleInertiaChange = 0.05;

std::string bodyName(const LinkDescription& l) {
  std::string s = "'" + l.name + "'";
  if (!l.merged_links.empty()) {
    s += " (with";
    for (size_t k = 0; k < l.merged_links.size(); ++k) s += (k ? ", '" : " '") + l.merged_links[k] + "'";
    s += ")";
  }
  return s;
}

// Validity on the bodies Simbody and the controller see (after lumping). An inertia that is
// impossible by rounding noise, or by an amount negligible for the dynamics (5 % of what the
// body's joint moves), is projected to the nearest physical one with a warning; a joint that moves
// nothing with mass or inertia, or a robot with none, is an error.
void checkBodies(RobotDescription& d, BaseType base, const std::string& file, const std::vector<int>& link_lines, ProblemList& problems) {
  const std::vector<double> moved = jointInertias(d);
  for (size_t b = 0; b < d.links.size(); ++b) {
    LinkDescription& l = d.links[b];
    const std::string where = at(file, link_lines[b]);
    const InertiaCheck c = checkInertia(l.inertia);
    if (b == 0 && base == BaseType::Fixed) {
      // Welded to the world: its inertia never enters the dynamics; Simbody still needs a physical one.
      if (c.kind == InertiaClass::Noise || c.kind == InertiaClass::Impossible) {
        l.inertia = projectInertia(l.inertia);
        problems.warning(where, "body " + bodyName(l) + " (welded to the world): inertia with " + c.problem +
                                    ": projected to the nearest physical one (it does not move)");
      } else if (c.kind == InertiaClass::Zero) {
        l.inertia.setZero();
      }
      continue;
    }
    if (c.kind == InertiaClass::Zero) {
      l.inertia.setZero();  // below 1e-12 kg m^2: exactly a point mass (no denormal noise reaches Simbody)
      if (l.mass > 0.0 && !problems.strict()) {
        problems.warning(where, "body " + bodyName(l) + ": mass " + fmt(l.mass) + " kg with a zero inertia: a point mass");
      }
    }
    if (c.kind != InertiaClass::Noise && c.kind != InertiaClass::Impossible) continue;
    const Eigen::Matrix3d P = projectInertia(l.inertia);
    const double change = (P - l.inertia).cwiseAbs().maxCoeff();
    const bool negligible = change <= kNegligibleInertiaChange * moved[b];
    if (c.kind == InertiaClass::Impossible && !negligible) {
      problems.error(where, "body " + bodyName(l) + ": inertia is not physically possible: " + c.problem + "; the correction (" +
                                formatNumber(change, 3) + " kg m^2) is not negligible against the " + fmt(moved[b]) +
                                " kg m^2 its joint moves");
      continue;
    }
    if (problems.strict() && l.merged_links.empty()) continue;  // the link's own error says it
    problems.lenient(
        where, "body " + bodyName(l) + ": inertia with " + c.problem + ", taken as " +
                   (c.kind == InertiaClass::Noise
                        ? "rounding noise"
                        : "negligible (" + formatNumber(change, 3) + " kg m^2 against the " + fmt(moved[b]) + " kg m^2 its joint moves)") +
                   ": projected to the nearest physical inertia, principal moments " + formatMoments(checkInertia(P).moments) + " kg m^2");
    l.inertia = P;
  }
  if (base == BaseType::FreeFlyer && !(moved[0] >= ranges::kMinPrincipalInertia_kgm2)) {
    problems.error(at(file, link_lines[0]), "the free-flyer robot (base " + bodyName(d.links[0]) + ") has " +
                                                (d.totalMass() > 0.0 ? "a singular inertia about its centre of mass" : "no mass") +
                                                ": a floating robot needs mass and a positive inertia");
  }
  for (size_t b = 1; b < d.links.size(); ++b) {
    if (d.links[b].parent_joint < 0) {
      // A coupled body: the simulator's tree moves it on a mobilizer of its own, which must move
      // something (the reduced model would not mind; the tree's mass matrix would be singular).
      const CoupledJointDescription& C = d.coupled_joints[static_cast<size_t>(d.links[b].parent_coupled)];
      if (!(moved[b] >= ranges::kMinPrincipalInertia_kgm2)) {
        problems.error(at(file, C.urdf_line),
                       "mimic joint '" + C.name + "' moves nothing with mass or inertia about its " +
                           (C.type == JointType::Prismatic ? "direction" : "axis") + " (link '" + d.links[b].name +
                           "' and everything after it: " + fmt(moved[b]) + (C.type == JointType::Prismatic ? " kg" : " kg m^2") +
                           "); the simulator's coupled mechanism would be singular: give those links mass and inertia, "
                           "or hold the mimic joints (`mimic: {mode: locked}` in the data file)");
      }
      continue;
    }
    const JointDescription& J = d.joints[static_cast<size_t>(d.links[b].parent_joint)];
    if (!(moved[b] >= ranges::kMinPrincipalInertia_kgm2)) {
      problems.error(at(file, J.urdf_line), "joint '" + J.name + "' moves nothing with mass or inertia about its " +
                                                (J.type == JointType::Prismatic ? "direction" : "axis") + " (link '" + d.links[b].name +
                                                "' and everything after it: " + fmt(moved[b]) +
                                                (J.type == JointType::Prismatic ? " kg" : " kg m^2") +
                                                "); the dynamics would be singular: give those links mass and inertia");
    }
  }
}

// Moving joints whose whole subtree is massless (finger joints of hands described without mass):
// they move nothing the dynamics sees, so they are locked at 0 (clamped into their limits) like a
// locked mimic joint, with a warning; an error in strict mode.
void lockMasslessJoints(const XmlIndex& idx, const urdf::ModelInterface& model, const std::string& file, ProblemList& problems,
                        std::map<std::string, double>& locked, RobotDescription& d) {
  if (problems.strict()) return;          // strict mode: such a link is refused where its body is built
  std::map<std::string, double> subtree;  // link -> mass of the link and everything below it
  std::function<double(const std::string&)> massBelow = [&](const std::string& link) {
    auto it = subtree.find(link);
    if (it != subtree.end()) return it->second;
    const urdf::Link& l = *model.links_.at(link);
    double m = l.inertial ? l.inertial->mass : 0.0;
    for (const auto& j : idx.joints) {
      if (j.parent == link) m += massBelow(j.child);
    }
    subtree[link] = m;
    return m;
  };
  std::vector<std::string> names;
  for (const auto& j : idx.joints) {
    if (j.type == "fixed" || j.type == "floating" || locked.count(j.name) || massBelow(j.child) > 0.0) continue;
    const urdf::Joint& uj = *model.joints_.at(j.name);
    double v = 0.0;
    if (uj.type != urdf::Joint::CONTINUOUS && uj.limits && uj.limits->lower < uj.limits->upper) {
      v = std::min(std::max(v, uj.limits->lower), uj.limits->upper);
    }
    locked[j.name] = v;
    d.locked_joints.push_back({j.name, v, "massless"});
    names.push_back(j.name);
  }
  if (!names.empty()) {
    std::string list;
    for (size_t k = 0; k < names.size() && k < 8; ++k) list += (k ? ", '" : "'") + names[k] + "'";
    if (names.size() > 8) list += " and " + std::to_string(names.size() - 8) + " more";
    problems.warning(file, std::to_string(names.size()) + " moving joint(s) (" + list +
                               ") move only massless links: locked (at 0, or the limit nearest to it), as fixed joints; "
                               "the dynamics has no use for them");
  }
}

// Each coupled joint's master as a model joint.
void resolveCoupledMasters(RobotDescription& d, const std::map<std::string, Coupling>& coupled) {
  for (auto& cj : d.coupled_joints) {
    const Coupling& c = coupled.at(cj.name);
    cj.master = d.findJoint(c.master);
    LEXDYN_ALWAYS_ASSERT(cj.master >= 0, "coupled joint " + cj.name + ": its master " + c.master + " is not a model joint");
  }
}

}  // namespace

void readUrdf(const std::string& text, const std::string& file, BaseType base, const MimicPolicy& mimic, const LoadOptions& options,
              RobotDescription& d, ProblemList& problems) {
  problems.attempt([&] { requireText(text, file, "URDF"); });
  problems.throwIfErrors();
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) problems.fatal(file, "the URDF file is empty");
  try {
    requireShallowXml(text, file, ranges::kMaxXmlDepth);
  } catch (const InputError& e) {
    problems.fatal(e.where(), e.detail());
  }
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error()) {
    problems.fatal(doc.ErrorRow() > 0 ? at(file, doc.ErrorRow()) : file, std::string("XML syntax error: ") + doc.ErrorDesc());
  }
  TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot") {
    problems.fatal(file, std::string("expected a <robot> root element, found ") +
                             (robot ? "<" + std::string(robot->Value()) + ">" : std::string("no element")));
  }
  try {
    refuseXacro(robot, file);
  } catch (const InputError& e) {
    problems.fatal(e.where(), e.detail());
  }
  XmlIndex idx;
  idx.robot_name = attr(robot, "name");
  if (idx.robot_name.empty()) problems.fatal(at(file, robot), "<robot> has no name");
  int n_links = 0, n_joints = 0;
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    if (++n_links > kMaxLinks) problems.fatal(at(file, e), "more than " + std::to_string(kMaxLinks) + " links (size guard)");
  }
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    if (++n_joints > kMaxJoints) problems.fatal(at(file, e), "more than " + std::to_string(kMaxJoints) + " joints (size guard)");
  }

  indexElements(robot, file, idx, problems);
  for (const auto& l : idx.links) {
    checkLinkNumbers(l, file, problems);
    checkGeometryNumbers(l, file, problems);
  }
  std::vector<std::string> fixed_with_extras;
  for (auto& j : idx.joints) {
    checkJointNumbers(j, file, problems);
    if (j.type == "fixed") {
      const std::vector<std::string> removed = stripFixedJointExtras(j.e, problems.strict());
      if (!removed.empty()) {
        fixed_with_extras.push_back(j.name);
        if (problems.strict()) {
          std::string list;
          for (const auto& r : removed) list += (list.empty() ? "<" : ", <") + r + ">";
          problems.lenient(at(file, j.line), "fixed joint '" + j.name + "' has " + list + " (URDF ignores them on a fixed joint)");
        }
      }
    }
  }
  // A floating joint: only from a massless root (a `world` link), making its child the base.
  for (const auto& j : idx.joints) {
    if (j.type != "floating") continue;
    const TiXmlElement* root_inertial = nullptr;
    for (const auto& l : idx.links) {
      if (l.name == idx.root) root_inertial = l.e->FirstChildElement("inertial");
    }
    if (j.parent != idx.root || root_inertial) {
      problems.error(at(file, j.line), "joint '" + j.name +
                                           "': a floating joint is read only from a massless root link (a `world` link) to the robot's "
                                           "base; use the data file's `base: free_flyer` instead");
    } else if (base != BaseType::FreeFlyer) {
      problems.error(at(file, j.line),
                     "joint '" + j.name + "' is a floating joint from '" + j.parent + "': the data file must say `base: free_flyer`");
    }
  }
  problems.throwIfHardErrors();
  {
    std::vector<std::string> with_dynamics;
    for (const auto& j : idx.joints) {
      if (j.type == "fixed") continue;
      const TiXmlElement* dyn = j.e->FirstChildElement("dynamics");
      if (dyn &&
          (std::strtod(attr(dyn, "damping").c_str(), nullptr) != 0.0 || std::strtod(attr(dyn, "friction").c_str(), nullptr) != 0.0)) {
        with_dynamics.push_back(j.name);
      }
    }
    if (!with_dynamics.empty()) {
      std::string names;
      for (size_t k = 0; k < with_dynamics.size() && k < 8; ++k) names += (k ? ", '" : "'") + with_dynamics[k] + "'";
      if (with_dynamics.size() > 8) names += " and " + std::to_string(with_dynamics.size() - 8) + " more";
      problems.warning(file, std::to_string(with_dynamics.size()) + " joint(s) (" + names +
                                 ") give <dynamics damping/friction>: not modelled (the simulated joints have their servos' damping only)");
    }
  }
  if (!fixed_with_extras.empty() && !problems.strict()) {
    std::string names;
    for (size_t k = 0; k < fixed_with_extras.size() && k < 8; ++k) names += (k ? ", '" : "'") + fixed_with_extras[k] + "'";
    if (fixed_with_extras.size() > 8) names += " and " + std::to_string(fixed_with_extras.size() - 8) + " more";
    problems.warning(file, std::to_string(fixed_with_extras.size()) + " fixed joint" + (fixed_with_extras.size() > 1 ? "s" : "") + " (" +
                               names + ") carry <axis>, <limit>, <mimic> or <dynamics>: ignored, as URDF does on a fixed joint");
  }

  const urdf::ModelInterfaceSharedPtr model = parseWithUrdfdom(doc, file, problems);

  d.urdf_root = idx.root;
  std::string root = idx.root;
  for (const auto& j : idx.joints) {
    if (j.type == "floating") {
      root = j.child;
      problems.warning(at(file, j.line), "floating joint '" + j.name + "' from the massless root '" + j.parent + "': '" + j.child +
                                             "' is the free-flyer base ('" + j.parent + "' is the world)");
    }
  }

  TreeBuilder t{
      idx, *model, file, base, mimic, options, d, problems, packageSearchPath(options.package_paths, options.use_ros_package_path),
      {},  {},     {},   {},   {}};
  for (const auto& l : idx.links) t.xml_link[l.name] = &l;
  for (const auto& j : idx.joints) t.xml_joint[j.name] = &j;
  readMimics(idx, *model, file, mimic, d, problems, t.locked, t.coupled);
  lockMasslessJoints(idx, *model, file, problems, t.locked, d);
  // A coupled joint locked (it moves only massless links), or whose master is locked, is locked.
  for (auto it = t.coupled.begin(); it != t.coupled.end();) {
    if (t.locked.count(it->first)) {
      it = t.coupled.erase(it);
    } else if (t.locked.count(it->second.master)) {
      double v = it->second.multiplier * t.locked.at(it->second.master) + it->second.offset;
      const urdf::Joint& uj = *model->joints_.at(it->first);
      if (uj.type != urdf::Joint::CONTINUOUS && uj.limits && uj.limits->lower < uj.limits->upper) {
        v = std::min(std::max(v, uj.limits->lower), uj.limits->upper);  // as a locked mimic is
      }
      t.locked[it->first] = v;
      d.locked_joints.push_back(LockedJointDescription{it->first, v, "mimic of a locked joint"});
      it = t.coupled.erase(it);
    } else {
      ++it;
    }
  }
  noteCoupled(file, mimic, t.coupled, problems);
  problems.throwIfHardErrors();

  {
    LinkDescription r;
    r.name = root;
    r.urdf_line = idx.lineOfLink(root);
    d.links.push_back(r);
    if (base == BaseType::FreeFlyer) t.strictOwnMass(root);
    t.body_mass.push_back(linkMassProps(t.link(root), t.whereLink(root), false, problems));
    t.addFrameAndGeometry(root, 0, Eigen::Isometry3d::Identity());
  }
  t.visit(root, 0, Eigen::Isometry3d::Identity());
  resolveCoupledMasters(d, t.coupled);

  for (size_t b = 0; b < d.links.size(); ++b) {
    d.links[b].mass = t.body_mass[b].mass;
    d.links[b].com = t.body_mass[b].com;
    d.links[b].inertia = t.body_mass[b].inertia;
  }
  std::vector<int> link_lines;
  for (const auto& l : d.links) link_lines.push_back(l.urdf_line);
  checkBodies(d, base, file, link_lines, problems);
  d.name = idx.robot_name;
}

void narrowCoupledMasters(RobotDescription& d, ProblemList& problems) {
  const std::string& file = d.urdf_path;
  for (const auto& cj : d.coupled_joints) {
    JointDescription& M = d.joints[static_cast<size_t>(cj.master)];
    const std::string where = at(file, cj.urdf_line);
    if (cj.multiplier == 0.0) {
      if (cj.offset < cj.lower || cj.offset > cj.upper) {
        problems.error(where, "joint '" + cj.name + "' (a mimic of '" + M.name + "' with multiplier 0) is held at its offset " +
                                  fmt(cj.offset) + ", outside its limits [" + fmt(cj.lower) + ", " + fmt(cj.upper) + "]");
      }
      continue;
    }
    // Its velocity: |c| qdot_M within its own limit.
    if (std::isfinite(cj.velocity_limit) && cj.velocity_limit > 0.0) {
      const double v = cj.velocity_limit / std::abs(cj.multiplier);
      if (v < M.velocity_limit) {
        problems.warning(where, "the velocity limit of '" + M.name + "' is lowered from " + fmt(M.velocity_limit) + " to " + fmt(v) +
                                    ", where its coupled joint '" + cj.name + "' stays within its own (" + fmt(cj.velocity_limit) + ")");
        M.velocity_limit = v;
      }
    }
    if (!(std::isfinite(cj.lower) && std::isfinite(cj.upper))) continue;
    double lo = (cj.lower - cj.offset) / cj.multiplier, hi = (cj.upper - cj.offset) / cj.multiplier;
    if (lo > hi) std::swap(lo, hi);
    if (lo > M.lower || hi < M.upper) {
      const double new_lo = std::max(lo, M.lower), new_hi = std::min(hi, M.upper);
      if (!(new_lo < new_hi)) {
        // Limits that contradict the coupling (a finger's limits written for the other sign of
        // its multiplier): ROS's tools never enforce a mimic joint's own limits; neither does
        // lexdyn then (strict mode refuses them).
        problems.lenient(where, "joint '" + cj.name + "' (coupled to '" + M.name + "' by " + fmt(cj.multiplier) + " q" +
                                    (cj.offset != 0.0 ? " + " + fmt(cj.offset) : "") + "): its limits [" + fmt(cj.lower) + ", " +
                                    fmt(cj.upper) + "] leave its master no range within [" + fmt(M.lower) + ", " + fmt(M.upper) +
                                    "]: they contradict the coupling and are ignored (the master's limits hold)");
        continue;
      }
      problems.warning(where, "the range of '" + M.name + "' is narrowed from [" + fmt(M.lower) + ", " + fmt(M.upper) + "] to [" +
                                  fmt(new_lo) + ", " + fmt(new_hi) + "], where its coupled joint '" + cj.name +
                                  "' stays within its own limits");
      M.lower = new_lo;
      M.upper = new_hi;
      M.continuous = false;
    }
  }
  // The data file's postures within the narrowed ranges.
  for (const auto& [pname, q] : d.postures) {
    for (const auto& cj : d.coupled_joints) {
      const JointDescription& M = d.joints[static_cast<size_t>(cj.master)];
      const double v = q[cj.master];
      if (v < M.lower - 1e-12 || v > M.upper + 1e-12) {
        problems.error(d.data_path, "posture '" + pname + "': '" + M.name + "' at " + fmt(v) + " puts its mimic joint '" + cj.name +
                                        "' at " + fmt(cj.multiplier * v + cj.offset) + ", outside its limits [" + fmt(cj.lower) + ", " +
                                        fmt(cj.upper) + "] (the master's range there: [" + fmt(M.lower) + ", " + fmt(M.upper) + "])");
      }
    }
  }
}

void noteUnspecifiedLimits(const RobotDescription& d, ProblemList& problems) {
  std::vector<std::string> effort, velocity, range;
  for (const auto& j : d.joints) {
    if (std::isinf(j.effort_limit)) effort.push_back(j.name);
    if (std::isinf(j.velocity_limit)) velocity.push_back(j.name);
    if (!j.continuous && std::isinf(j.lower) && std::isinf(j.upper)) range.push_back(j.name);
  }
  auto nameList = [](const std::vector<std::string>& v) {
    std::string s;
    for (size_t k = 0; k < v.size() && k < 8; ++k) s += (k ? ", '" : "'") + v[k] + "'";
    if (v.size() > 8) s += " and " + std::to_string(v.size() - 8) + " more";
    return s;
  };
  const std::string& file = d.urdf_path;
  if (!effort.empty()) {
    problems.lenient(file, std::to_string(effort.size()) + " joint(s) with effort=\"0\" or no <limit> (" + nameList(effort) +
                               "): the effort limit is unspecified, taken as unlimited (no torque limit, no servo saturation); "
                               "give `joint_limits: {JOINT: {effort: ...}}` in the data file");
  }
  if (!velocity.empty()) {
    problems.lenient(file, std::to_string(velocity.size()) + " joint(s) with velocity=\"0\" or no <limit> (" + nameList(velocity) +
                               "): the velocity limit is unspecified, taken as unlimited; give `joint_limits: {JOINT: {velocity: ...}}` "
                               "in the data file");
  }
  if (!range.empty()) {
    problems.lenient(file, std::to_string(range.size()) + " revolute or prismatic joint(s) without lower and upper, or with both 0 (" +
                               nameList(range) +
                               "): no position limits, as for a continuous joint; give `joint_limits: {JOINT: {lower: ..., upper: ...}}`");
  }
}

}  // namespace lexdyn::model::detail
