#include "lexdyn/model/robot_description.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_ranges.hpp"
#include "lexdyn/common/input_text.hpp"
#include "lexdyn/common/yaml_strict.hpp"

#include <Eigen/Eigenvalues>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

namespace lexdyn::model {

namespace {

constexpr const char* kDataFormat = "lexdyn-robot-data/1";

std::string readText(const std::string& path, const char* what) { return readTextFile(path, what); }

/// Size guards of a URDF: element nesting (TinyXML and urdfdom recurse on it), links and joints
/// (the tree is walked recursively and the name checks are quadratic).
constexpr int kMaxLinks = 1000;
constexpr int kMaxJoints = 1000;

// Names become trace channel names and file keys: no whitespace, commas or quotes.
bool validName(const std::string& n) {
  return !n.empty() && n.find_first_of(" \t\r\n,\"'") == std::string::npos;
}

std::string fmt(double v) { return formatNumber(v); }

// ---------------------------------------------------------------------------------------------
// URDF structure as found in the file (TinyXML pass): names, line numbers, file order.
// ---------------------------------------------------------------------------------------------
struct XmlLink {
  std::string name;
  int line = 0;
};
struct XmlJoint {
  std::string name, type, parent, child;
  int line = 0;
  bool has_mimic = false;
};

struct XmlIndex {
  std::string robot_name;
  std::vector<XmlLink> links;
  std::vector<XmlJoint> joints;
};

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
        throw InputError(file + ":" + std::to_string(line), "elements are nested more than " + std::to_string(limit) +
                                                               " deep (a URDF needs 4: robot, link, inertial, origin)");
      }
    }
  }
}

// A URDF number attribute as urdfdom will read it, checked first so that errors name the file,
// the line and the attribute: `count` whitespace-separated finite numbers, each within
// [lo, hi]. Absent attributes are urdfdom's business (defaults or its own errors).
std::vector<double> urdfNumbers(const TiXmlElement* e, const char* attr, int count, double lo, double hi, const char* unit,
                                const std::string& file, const std::string& owner) {
  std::vector<double> out;
  const char* raw = e ? e->Attribute(attr) : nullptr;
  if (!raw) return out;
  const std::string where = file + ":" + std::to_string(e->Row());
  const std::string what = owner + ": <" + std::string(e->Value()) + " " + attr + "=\"" + raw + "\">: ";
  std::istringstream in{std::string(raw)};
  std::string tok;
  while (in >> tok) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() + tok.size() || errno == ERANGE || !std::isfinite(v)) {
      throw InputError(where, what + "expected finite numbers, found '" + tok + "'");
    }
    if (!(v >= lo && v <= hi)) {
      throw InputError(where, what + "expected values in [" + fmt(lo) + ", " + fmt(hi) + "]" + (*unit ? std::string(" ") + unit : "") +
                                  ", found " + tok);
    }
    out.push_back(v);
  }
  if (static_cast<int>(out.size()) != count) {
    throw InputError(where, what + "expected " + std::to_string(count) + " number" + (count > 1 ? "s" : "") + ", found " +
                                std::to_string(out.size()));
  }
  return out;
}

void checkOrigin(const TiXmlElement* parent, const std::string& file, const std::string& owner) {
  const TiXmlElement* o = parent ? parent->FirstChildElement("origin") : nullptr;
  urdfNumbers(o, "xyz", 3, -ranges::kMaxLength_m, ranges::kMaxLength_m, "m", file, owner);
  urdfNumbers(o, "rpy", 3, -ranges::kMaxAngle_rad, ranges::kMaxAngle_rad, "rad", file, owner);
}

// A single-number attribute checked against (lo, hi] or [lo, hi]: `positive` says which; the
// error names the element's line, its owner and the attribute.
void urdfPositive(const TiXmlElement* e, const char* attr, const char* label, double lo, double hi, const char* unit,
                  const std::string& file, const std::string& owner) {
  const std::vector<double> v = urdfNumbers(e, attr, 1, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                                            unit, file, owner);
  if (v.empty()) return;
  const std::string where = file + ":" + std::to_string(e->Row());
  if (!(v[0] > 0.0)) throw InputError(where, owner + ": " + label + " must be > 0, found " + fmt(v[0]));
  if (v[0] < lo || v[0] > hi) {
    throw InputError(where, owner + ": " + label + " must be in [" + fmt(lo) + ", " + fmt(hi) + "] " + unit + ", found " + fmt(v[0]));
  }
}

// The numbers and elements lexdyn reads from a URDF (mass properties, joint types, placements,
// axes, limits), checked before urdfdom reads them so that an error names the file, the line,
// the link or joint and the attribute (urdfdom's own messages name neither the file nor the line).
void checkUrdfNumbers(const TiXmlElement* robot, const std::string& file) {
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const std::string owner = std::string("link '") + (e->Attribute("name") ? e->Attribute("name") : "") + "'";
    const TiXmlElement* in = e->FirstChildElement("inertial");
    if (!in) continue;
    const std::string where = file + ":" + std::to_string(in->Row());
    checkOrigin(in, file, owner);
    const TiXmlElement* mass = in->FirstChildElement("mass");
    if (!mass || !mass->Attribute("value")) throw InputError(where, owner + ": <inertial> needs <mass value=\"...\"/>");
    const std::vector<double> m = urdfNumbers(mass, "value", 1, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                                              "kg", file, owner);
    const std::string mwhere = file + ":" + std::to_string(mass->Row());
    if (m[0] < 0.0) throw InputError(mwhere, owner + ": mass must be > 0, found " + fmt(m[0]));
    if (m[0] > ranges::kMaxLinkMass_kg || (m[0] > 0.0 && m[0] < ranges::kMinLinkMass_kg)) {
      throw InputError(mwhere, owner + ": mass must be in [" + fmt(ranges::kMinLinkMass_kg) + ", " + fmt(ranges::kMaxLinkMass_kg) +
                                   "] kg (or 0 for a massless fixed part), found " + fmt(m[0]));
    }
    const TiXmlElement* inertia = in->FirstChildElement("inertia");
    if (!inertia) throw InputError(where, owner + ": <inertial> needs <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=.../>");
    for (const char* a : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
      if (!inertia->Attribute(a)) throw InputError(file + ":" + std::to_string(inertia->Row()), owner + ": <inertia> has no " + a + " attribute");
      urdfNumbers(inertia, a, 1, -ranges::kMaxPrincipalInertia_kgm2, ranges::kMaxPrincipalInertia_kgm2, "kg m^2", file, owner);
    }
  }
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const std::string owner = std::string("joint '") + (e->Attribute("name") ? e->Attribute("name") : "") + "'";
    const std::string where = file + ":" + std::to_string(e->Row());
    const std::string type = e->Attribute("type") ? e->Attribute("type") : "";
    if (type != "revolute" && type != "continuous" && type != "prismatic" && type != "fixed") {
      throw InputError(where, owner + ": type '" + type + "' is not supported (revolute, continuous, prismatic, fixed)");
    }
    checkOrigin(e, file, owner);
    const TiXmlElement* axis = e->FirstChildElement("axis");
    const std::vector<double> a = urdfNumbers(axis, "xyz", 3, -ranges::kMaxLength_m, ranges::kMaxLength_m, "", file, owner);
    if (!a.empty() && std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) < 1e-6) {
      throw InputError(file + ":" + std::to_string(axis->Row()), owner + ": <axis> must be a non-zero vector (norm >= 1e-6)");
    }
    const TiXmlElement* lim = e->FirstChildElement("limit");
    if (type == "fixed") continue;
    if (!lim) throw InputError(where, owner + ": a <limit effort=... velocity=...> element is required");
    urdfNumbers(lim, "lower", 1, -ranges::kMaxJointLimit, ranges::kMaxJointLimit, "(rad or m)", file, owner);
    urdfNumbers(lim, "upper", 1, -ranges::kMaxJointLimit, ranges::kMaxJointLimit, "(rad or m)", file, owner);
    urdfPositive(lim, "effort", "effort limit", ranges::kMinEffortLimit, ranges::kMaxEffortLimit, "N m or N", file, owner);
    urdfPositive(lim, "velocity", "velocity limit", ranges::kMinVelocityLimit, ranges::kMaxVelocityLimit, "rad/s or m/s", file, owner);
  }
}

XmlIndex indexUrdf(const std::string& text, const std::string& file) {
  requireShallowXml(text, file, ranges::kMaxXmlDepth);
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw InputError(file, "the URDF file is empty");
  if (doc.Error()) {
    throw InputError(file + (doc.ErrorRow() > 0 ? ":" + std::to_string(doc.ErrorRow()) : std::string()),
                     std::string("XML syntax error: ") + doc.ErrorDesc());
  }
  const TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot") {
    throw InputError(file, std::string("expected a <robot> root element, found ") +
                               (robot ? "<" + std::string(robot->Value()) + ">" : std::string("no element")));
  }
  XmlIndex idx;
  if (const char* n = robot->Attribute("name")) idx.robot_name = n;
  if (idx.robot_name.empty()) throw InputError(file + ":" + std::to_string(robot->Row()), "<robot> has no name");
  int n_links = 0, n_joints = 0;
  for (const TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    if (++n_links > kMaxLinks) throw InputError(file + ":" + std::to_string(e->Row()), "more than " + std::to_string(kMaxLinks) + " links (size guard)");
  }
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    if (++n_joints > kMaxJoints) throw InputError(file + ":" + std::to_string(e->Row()), "more than " + std::to_string(kMaxJoints) + " joints (size guard)");
  }
  checkUrdfNumbers(robot, file);

  for (const TiXmlElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const char* n = e->Attribute("name");
    const std::string where = file + ":" + std::to_string(e->Row());
    if (!n || !*n) throw InputError(where, "<link> without a name");
    if (!validName(n)) throw InputError(where, std::string("link name '") + n + "' contains whitespace, a comma or a quote");
    for (const auto& l : idx.links) {
      if (l.name == n) {
        throw InputError(where, std::string("duplicate link '") + n + "' (first defined on line " +
                                    std::to_string(l.line) + ")");
      }
    }
    idx.links.push_back({n, e->Row()});
  }
  if (idx.links.empty()) throw InputError(file, "the URDF defines no <link>");

  auto linkExists = [&](const std::string& name) {
    for (const auto& l : idx.links) {
      if (l.name == name) return true;
    }
    return false;
  };

  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    XmlJoint j;
    j.line = e->Row();
    const std::string where = file + ":" + std::to_string(j.line);
    const char* n = e->Attribute("name");
    if (!n || !*n) throw InputError(where, "<joint> without a name");
    j.name = n;
    if (!validName(j.name)) throw InputError(where, "joint name '" + j.name + "' contains whitespace, a comma or a quote");
    for (const auto& o : idx.joints) {
      if (o.name == j.name) {
        throw InputError(where, "duplicate joint '" + j.name + "' (first defined on line " +
                                    std::to_string(o.line) + ")");
      }
    }
    const char* t = e->Attribute("type");
    if (!t) throw InputError(where, "joint '" + j.name + "' has no type");
    j.type = t;
    const TiXmlElement* p = e->FirstChildElement("parent");
    const TiXmlElement* c = e->FirstChildElement("child");
    if (!p || !p->Attribute("link")) throw InputError(where, "joint '" + j.name + "' has no <parent link=...>");
    if (!c || !c->Attribute("link")) throw InputError(where, "joint '" + j.name + "' has no <child link=...>");
    j.parent = p->Attribute("link");
    j.child = c->Attribute("link");
    if (!linkExists(j.parent)) {
      throw InputError(file + ":" + std::to_string(p->Row()),
                       "joint '" + j.name + "': parent link '" + j.parent + "' is not defined");
    }
    if (!linkExists(j.child)) {
      throw InputError(file + ":" + std::to_string(c->Row()),
                       "joint '" + j.name + "': child link '" + j.child + "' is not defined");
    }
    if (j.parent == j.child) throw InputError(where, "joint '" + j.name + "' connects link '" + j.parent + "' to itself");
    j.has_mimic = e->FirstChildElement("mimic") != nullptr;
    idx.joints.push_back(j);
  }

  // Tree: every link has at most one parent joint, exactly one root, no cycle.
  std::map<std::string, const XmlJoint*> parent_of;
  for (const auto& j : idx.joints) {
    auto it = parent_of.find(j.child);
    if (it != parent_of.end()) {
      throw InputError(file + ":" + std::to_string(j.line),
                       "link '" + j.child + "' is the child of two joints ('" + it->second->name +
                           "' and '" + j.name + "'); a URDF must be a tree");
    }
    parent_of[j.child] = &j;
  }
  std::vector<std::string> roots;
  for (const auto& l : idx.links) {
    if (!parent_of.count(l.name)) roots.push_back(l.name);
  }
  if (roots.size() != 1) {
    std::string list;
    for (const auto& r : roots) list += (list.empty() ? "" : ", ") + r;
    throw InputError(file, "expected exactly one root link, found " + std::to_string(roots.size()) +
                               (roots.empty() ? " (the joints form a cycle)" : ": " + list));
  }
  // Every link reachable from the root: a cycle of joints detached from the tree leaves one root
  // but links no walk from it reaches (and urdfdom would build a cycle of shared pointers).
  std::map<std::string, std::vector<const XmlJoint*>> children_of;
  for (const auto& j : idx.joints) children_of[j.parent].push_back(&j);
  std::map<std::string, bool> reached{{roots[0], true}};
  std::vector<std::string> stack{roots[0]};
  while (!stack.empty()) {
    const std::string l = stack.back();
    stack.pop_back();
    for (const XmlJoint* j : children_of[l]) {
      if (!reached[j->child]) {
        reached[j->child] = true;
        stack.push_back(j->child);
      }
    }
  }
  for (const auto& l : idx.links) {
    if (!reached[l.name]) {
      const XmlJoint* j = parent_of.at(l.name);
      throw InputError(file + ":" + std::to_string(j->line),
                       "link '" + l.name + "' is not connected to the root link '" + roots[0] + "': its joint '" + j->name +
                           "' hangs it from '" + j->parent + "', and the joints form a cycle there; a URDF must be a tree");
    }
  }
  return idx;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond quat(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  X.linear() = quat.normalized().toRotationMatrix();
  X.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return X;
}

// Mass properties of one URDF link in its own frame (about its CoM, link axes).
struct MassProps {
  double mass = 0.0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

// Checks that an inertia about the CoM is symmetric positive definite and physically possible
// (triangle inequalities on the principal moments). Returns an empty string when fine.
std::string inertiaProblem(const Eigen::Matrix3d& I) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(I);
  const Eigen::Vector3d ev = es.eigenvalues();
  if (!(ev.minCoeff() > 0.0)) {
    return "is not positive definite (principal moments " + fmt(ev[0]) + ", " + fmt(ev[1]) + ", " +
           fmt(ev[2]) + " kg m^2)";
  }
  if (ev.minCoeff() < ranges::kMinPrincipalInertia_kgm2 || ev.maxCoeff() > ranges::kMaxPrincipalInertia_kgm2) {
    return "has principal moments " + fmt(ev[0]) + ", " + fmt(ev[1]) + ", " + fmt(ev[2]) + " kg m^2, outside [" +
           fmt(ranges::kMinPrincipalInertia_kgm2) + ", " + fmt(ranges::kMaxPrincipalInertia_kgm2) + "]";
  }
  const double tol = 1e-12 * ev.maxCoeff();
  if (ev[0] + ev[1] < ev[2] - tol) {
    return "is not physically possible: principal moments " + fmt(ev[0]) + ", " + fmt(ev[1]) + ", " +
           fmt(ev[2]) + " kg m^2 violate the triangle inequality";
  }
  return {};
}

MassProps linkMassProps(const urdf::Link& link, const std::string& where, bool required) {
  MassProps mp;
  if (!link.inertial) {
    if (required) throw InputError(where, "link '" + link.name + "' has no <inertial> (a moving body needs mass > 0)");
    return mp;
  }
  const urdf::Inertial& in = *link.inertial;
  if (!std::isfinite(in.mass) || in.mass < 0.0) {
    throw InputError(where, "link '" + link.name + "': mass must be > 0, found " + fmt(in.mass));
  }
  if (in.mass == 0.0) {
    if (required) throw InputError(where, "link '" + link.name + "': mass must be > 0, found 0");
    return mp;
  }
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  if (!I.allFinite()) throw InputError(where, "link '" + link.name + "': inertia has a non-finite entry");
  const std::string problem = inertiaProblem(I);
  if (!problem.empty()) throw InputError(where, "link '" + link.name + "': inertia " + problem);
  const Eigen::Isometry3d X = toIsometry(in.origin);
  mp.mass = in.mass;
  mp.com = X.translation();
  mp.inertia = X.linear() * I * X.linear().transpose();
  return mp;
}

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


}  // namespace

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Index of the first item named n, -1 when none is.
template <class T>
static int indexOfName(const std::vector<T>& items, const std::string& n) {
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

int RobotDescription::findLink(const std::string& n) const { return indexOfName(links, n); }
int RobotDescription::findJoint(const std::string& n) const { return indexOfName(joints, n); }
int RobotDescription::findFrame(const std::string& n) const { return indexOfName(frames, n); }
int RobotDescription::findCapsule(const std::string& n) const { return indexOfName(capsules, n); }
// "a, b, c": the names of `items` (name_of(item) gives one), for messages.
template <class T, class NameOf>
static std::string knownNames(const std::vector<T>& items, NameOf name_of) {
  std::string known;
  for (const T& item : items) known += (known.empty() ? "" : ", ") + name_of(item);
  return known;
}
int RobotDescription::jointIndex(const std::string& n) const {
  const int j = findJoint(n);
  if (j >= 0) return j;
  const std::string known = knownNames(joints, [](const JointDescription& J) { return J.name; });
  throw InputError(urdf_path, "unknown joint '" + n + "' (joints: " + known + ")");
}
int RobotDescription::frameIndex(const std::string& n) const {
  const int f = findFrame(n);
  if (f >= 0) return f;
  const std::string known = knownNames(frames, [](const FrameDescription& F) { return F.name; });
  throw InputError(data_path, "unknown frame '" + n + "' (frames: " + known + ")");
}
const Eigen::VectorXd& RobotDescription::posture(const std::string& n) const {
  for (const auto& p : postures) {
    if (p.first == n) return p.second;
  }
  const std::string known = knownNames(postures, [](const std::pair<std::string, Eigen::VectorXd>& p) { return p.first; });
  throw InputError(data_path, "unknown posture '" + n + "' (postures: " + known + ")");
}
double RobotDescription::totalMass() const {
  double m = 0.0;
  for (const auto& l : links) m += l.mass;
  return m;
}

namespace {

// ---------------------------------------------------------------------------------------------
// URDF -> bodies and joints
// ---------------------------------------------------------------------------------------------
void buildTree(RobotDescription& d, const XmlIndex& idx, const urdf::ModelInterface& urdf_model,
               const std::string& file, BaseType base) {
  auto lineOfLink = [&](const std::string& name) {
    for (const auto& l : idx.links) {
      if (l.name == name) return l.line;
    }
    return 0;
  };
  auto whereLink = [&](const std::string& name) { return file + ":" + std::to_string(lineOfLink(name)); };

  std::string root_name;
  {
    std::map<std::string, bool> is_child;
    for (const auto& j : idx.joints) is_child[j.child] = true;
    for (const auto& l : idx.links) {
      if (!is_child.count(l.name)) root_name = l.name;
    }
  }

  std::vector<MassProps> body_mass;
  auto getLink = [&](const std::string& name) -> const urdf::Link& {
    auto it = urdf_model.links_.find(name);
    LEXDYN_ALWAYS_ASSERT(it != urdf_model.links_.end() && it->second, "urdfdom lost link " + name);
    return *it->second;
  };
  auto getJoint = [&](const std::string& name) -> const urdf::Joint& {
    auto it = urdf_model.joints_.find(name);
    LEXDYN_ALWAYS_ASSERT(it != urdf_model.joints_.end() && it->second, "urdfdom lost joint " + name);
    return *it->second;
  };

  // The root body.
  {
    LinkDescription root;
    root.name = root_name;
    d.links.push_back(root);
    const bool required = (base == BaseType::FreeFlyer);
    body_mass.push_back(linkMassProps(getLink(root_name), whereLink(root_name), required));
    FrameDescription f;
    f.name = root_name;
    f.link = 0;
    d.frames.push_back(f);
  }

  // Depth-first, pre-order; siblings in file order. A fixed joint merges its child link into
  // the current body (mass lumped, link kept as a frame).
  std::function<void(const std::string&, int, const Eigen::Isometry3d&)> visit =
      [&](const std::string& link, int body, const Eigen::Isometry3d& X_body_link) {
        for (const auto& xj : idx.joints) {
          if (xj.parent != link) continue;
          const urdf::Joint& uj = getJoint(xj.name);
          const std::string where = file + ":" + std::to_string(xj.line);
          if (xj.has_mimic) throw InputError(where, "joint '" + xj.name + "': <mimic> joints are not supported");
          const Eigen::Isometry3d X_body_joint = X_body_link * toIsometry(uj.parent_to_joint_origin_transform);
          if (!X_body_joint.matrix().allFinite()) throw InputError(where, "joint '" + xj.name + "': non-finite <origin>");
          if (uj.type == urdf::Joint::FIXED) {
            lump(body_mass[static_cast<size_t>(body)],
                 linkMassProps(getLink(xj.child), whereLink(xj.child), false), X_body_joint);
            d.links[static_cast<size_t>(body)].merged_links.push_back(xj.child);
            FrameDescription f;
            f.name = xj.child;
            f.link = body;
            f.placement = X_body_joint;
            d.frames.push_back(f);
            visit(xj.child, body, X_body_joint);
            continue;
          }
          JointDescription jd;
          jd.name = xj.name;
          jd.urdf_line = xj.line;
          jd.parent_link = body;
          jd.origin = X_body_joint;
          switch (uj.type) {
            case urdf::Joint::REVOLUTE: jd.type = JointType::Revolute; break;
            case urdf::Joint::CONTINUOUS: jd.type = JointType::Revolute; break;
            case urdf::Joint::PRISMATIC: jd.type = JointType::Prismatic; break;
            default:
              throw InputError(where, "joint '" + xj.name + "': type '" + xj.type +
                                          "' is not supported (revolute, continuous, prismatic, fixed)");
          }
          const Eigen::Vector3d axis(uj.axis.x, uj.axis.y, uj.axis.z);
          if (!axis.allFinite() || axis.norm() < 1e-9) {
            throw InputError(where, "joint '" + xj.name + "': <axis> must be a non-zero vector");
          }
          jd.axis = axis.normalized();
          if (!uj.limits) {
            throw InputError(where, "joint '" + xj.name + "': a <limit effort=... velocity=...> element is required");
          }
          if (uj.type == urdf::Joint::CONTINUOUS) {
            jd.lower = -std::numeric_limits<double>::infinity();
            jd.upper = std::numeric_limits<double>::infinity();
          } else {
            jd.lower = uj.limits->lower;
            jd.upper = uj.limits->upper;
            if (!std::isfinite(jd.lower) || !std::isfinite(jd.upper) || !(jd.lower < jd.upper)) {
              throw InputError(where, "joint '" + xj.name + "': expected limit lower < upper, found lower=" +
                                          fmt(jd.lower) + " upper=" + fmt(jd.upper));
            }
          }
          jd.effort_limit = uj.limits->effort;
          jd.velocity_limit = uj.limits->velocity;
          if (!(jd.effort_limit > 0.0) || !std::isfinite(jd.effort_limit)) {
            throw InputError(where, "joint '" + xj.name + "': effort limit must be > 0, found " + fmt(jd.effort_limit));
          }
          if (!(jd.velocity_limit > 0.0) || !std::isfinite(jd.velocity_limit)) {
            throw InputError(where, "joint '" + xj.name + "': velocity limit must be > 0, found " +
                                        fmt(jd.velocity_limit));
          }
          const int child_body = static_cast<int>(d.links.size());
          jd.child_link = child_body;
          LinkDescription ld;
          ld.name = xj.child;
          ld.parent_joint = static_cast<int>(d.joints.size());
          d.links.push_back(ld);
          d.joints.push_back(jd);
          body_mass.push_back(linkMassProps(getLink(xj.child), whereLink(xj.child), true));
          FrameDescription f;
          f.name = xj.child;
          f.link = child_body;
          d.frames.push_back(f);
          visit(xj.child, child_body, Eigen::Isometry3d::Identity());
        }
      };
  visit(root_name, 0, Eigen::Isometry3d::Identity());

  for (size_t b = 0; b < d.links.size(); ++b) {
    const MassProps& mp = body_mass[b];
    LinkDescription& l = d.links[b];
    l.mass = mp.mass;
    l.com = mp.com;
    l.inertia = mp.inertia;
    const bool needs_mass = (b > 0) || base == BaseType::FreeFlyer;
    if (needs_mass) {
      if (!(mp.mass > 0.0)) {
        throw InputError(whereLink(l.name), "link '" + l.name + "' moves but has no mass (mass must be > 0)");
      }
      const std::string problem = inertiaProblem(mp.inertia);
      if (!problem.empty()) {
        throw InputError(whereLink(l.name), "link '" + l.name + "' (with merged fixed links): inertia " + problem);
      }
    }
  }
}

}  // namespace

namespace {

// ---------------------------------------------------------------------------------------------
// Data file
// ---------------------------------------------------------------------------------------------
void readDataFile(RobotDescription& d, const yaml::Node& root, const std::string& urdf_robot_name) {
  yaml::StrictMap top(root);
  const yaml::Node format = top.required("format");
  if (format.asString() != kDataFormat) {
    format.fail(std::string("expected '") + kDataFormat + "', found '" + format.asString() + "'");
  }
  const yaml::Node robot = top.required("robot");
  if (robot.asString() != urdf_robot_name) {
    robot.fail("the URDF describes robot '" + urdf_robot_name + "', this data file is for '" +
               robot.asString() + "'");
  }
  d.name = urdf_robot_name;
  // base is read by the caller before the tree is built.
  top.required("base");
  if (auto g = top.optional("gravity")) {
    d.gravity = g->asVector3();
    if (!(d.gravity.norm() <= ranges::kMaxGravity_mps2)) g->fail("expected |gravity| <= " + fmt(ranges::kMaxGravity_mps2) + " m/s^2, found " + fmt(d.gravity.norm()));
  }
  if (auto mu = top.optional("friction_coefficient")) {
    d.friction_coefficient = mu->asPositiveDouble();
    if (d.friction_coefficient > ranges::kMaxFriction) mu->fail("expected a friction coefficient in (0, " + fmt(ranges::kMaxFriction) + "], found " + fmt(d.friction_coefficient));
  }

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

  // f(m) for each entry m (a map) of the list `key` when the file has it; an entry's unknown
  // keys are refused once f has read it.
  auto forEachEntry = [&top](const char* key, const auto& f) {
    if (auto list = top.optional(key)) {
      for (const yaml::Node& n : list->elements()) {
        yaml::StrictMap m(n);
        f(m);
        m.finish();
      }
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
    d.frames.push_back(f);
  });

  forEachEntry("contact_surfaces", [&](yaml::StrictMap& m) {
    ContactSurfaceDescription s;
    s.name = newName(m, d.contact_surfaces, "contact surface");
    s.frame = lookupFrame(m.required("frame"));
    const yaml::Node pts = m.required("points");
    if (pts.size() < 1) pts.fail("a contact surface needs at least one point");
    for (const yaml::Node& p : pts.elements()) s.points.push_back(p.asVector3In(-ranges::kMaxLength_m, ranges::kMaxLength_m, "m"));
    d.contact_surfaces.push_back(s);
  });
  if (!d.contact_surfaces.empty() && !top.has("friction_coefficient")) {
    root.fail("friction_coefficient is required when contact_surfaces are given");
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

  if (auto pairs = top.optional("collision_pairs")) {
    yaml::StrictMap m(*pairs);
    const yaml::Node di = m.required("interaction_distance");
    const yaml::Node ds = m.required("safety_distance");
    d.collision_interaction_distance = di.asPositiveDouble();
    d.collision_safety_distance = ds.asNonNegativeDouble();
    if (d.collision_interaction_distance > ranges::kMaxLength_m) di.fail("expected at most " + fmt(ranges::kMaxLength_m) + " m");
    if (!(d.collision_safety_distance < d.collision_interaction_distance)) {
      ds.fail("safety_distance must be smaller than interaction_distance");
    }
    const yaml::Node list = m.required("pairs");
    for (const yaml::Node& pn : list.elements()) {
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
    }
    m.finish();
  }

  if (auto postures = top.optional("postures")) {
    for (const auto& [pname, pn] : postures->entries()) {
      Eigen::VectorXd q = Eigen::VectorXd::Constant(static_cast<int>(d.joints.size()),
                                                    std::numeric_limits<double>::quiet_NaN());
      for (const auto& [jname, vn] : pn.entries()) {
        const int j = d.findJoint(jname);
        if (j < 0) vn.fail("unknown joint '" + jname + "'");
        const double v = vn.asDouble();
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
      d.postures.emplace_back(pname, q);
    }
  }
  top.finish();
}

}  // namespace

RobotDescription parseRobotDescription(const std::string& urdf_text, const std::string& urdf_name,
                                       const std::string& data_text, const std::string& data_name) {
  RobotDescription d;
  d.urdf_path = urdf_name;
  d.data_path = data_name;

  requireText(urdf_text, urdf_name, "URDF");
  const XmlIndex idx = indexUrdf(urdf_text, urdf_name);
  const yaml::Node data_root = yaml::loadString(data_text, data_name);

  // The base type is needed to build the tree (a fixed root may be massless).
  BaseType base = BaseType::FreeFlyer;
  {
    if (!data_root.raw()["base"]) {
      data_root.fail("missing required key 'base' (free_flyer or fixed)");
    }
    const yaml::Node b(data_root.raw()["base"], data_name, "base");
    base = b.asEnum({"free_flyer", "fixed"}) == "fixed" ? BaseType::Fixed : BaseType::FreeFlyer;
  }
  d.base = base;

  urdf::ModelInterfaceSharedPtr urdf_model = urdf::parseURDF(urdf_text);
  if (!urdf_model) {
    throw InputError(urdf_name, "urdfdom could not parse the file (its messages are printed above)");
  }
  buildTree(d, idx, *urdf_model, urdf_name, base);
  readDataFile(d, data_root, idx.robot_name);
  return d;
}

RobotDescription loadRobotDescription(const std::string& urdf_path, const std::string& data_path) {
  const std::string urdf_text = readText(urdf_path, "URDF");
  const std::string data_text = readText(data_path, "robot data");
  return parseRobotDescription(urdf_text, urdf_path, data_text, data_path);
}

}  // namespace lexdyn::model
