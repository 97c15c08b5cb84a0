#include "lexdyn/model/robot_description.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/input_text.hpp"
#include "lexdyn/common/problems.hpp"
#include "lexdyn/common/yaml_strict.hpp"
#include "lexdyn/model/detail/data_file.hpp"
#include "lexdyn/model/detail/urdf_reader.hpp"

namespace lexdyn::model {

Eigen::Matrix3d rotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
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
int RobotDescription::parentBody(int b) const {
  const LinkDescription& l = links.at(static_cast<size_t>(b));
  if (l.parent_joint >= 0) return joints[static_cast<size_t>(l.parent_joint)].parent_link;
  if (l.parent_coupled >= 0) return coupled_joints[static_cast<size_t>(l.parent_coupled)].parent_link;
  return -1;
}
const Eigen::Isometry3d& RobotDescription::jointOrigin(int b) const {
  static const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const LinkDescription& l = links.at(static_cast<size_t>(b));
  if (l.parent_joint >= 0) return joints[static_cast<size_t>(l.parent_joint)].origin;
  if (l.parent_coupled >= 0) return coupled_joints[static_cast<size_t>(l.parent_coupled)].origin;
  return identity;
}
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

void keepWarnings(RobotDescription& d, const ProblemList& problems) {
  for (const Problem& p : problems.warnings()) d.warnings.push_back(p.text());
}

}  // namespace

RobotDescription parseRobotDescription(const std::string& urdf_text, const std::string& urdf_name, const std::string& data_text,
                                       const std::string& data_name, const LoadOptions& options) {
  RobotDescription d;
  d.urdf_path = urdf_name;
  d.data_path = data_name;
  d.strict = options.strict;
  ProblemList problems(urdf_name, options.strict);
  // The data file is parsed first (a YAML syntax error stops here), its base type and mimic
  // policy read; the URDF's problems and the data file's are then listed together.
  const yaml::Node data_root = yaml::loadString(data_text, data_name);
  BaseType base = BaseType::FreeFlyer;
  problems.attempt([&] { base = detail::readBaseType(data_root); });
  d.base = base;
  const detail::MimicPolicy mimic = detail::readMimicPolicy(data_root, problems);
  LoadOptions with_paths = options;  // the data file's package_path after the caller's
  for (const std::string& p : detail::readPackagePaths(data_root, problems)) with_paths.package_paths.push_back(p);
  detail::readUrdf(urdf_text, urdf_name, base, mimic, with_paths, d, problems);
  detail::readDataFile(d, data_root, problems);
  problems.attempt([&] { detail::narrowCoupledMasters(d, problems); });
  detail::noteUnspecifiedLimits(d, problems);
  problems.throwIfErrors();
  keepWarnings(d, problems);
  return d;
}

RobotDescription loadRobotDescription(const std::string& urdf_path, const std::string& data_path, const LoadOptions& options) {
  const std::string urdf_text = readTextFile(urdf_path, "URDF");
  const std::string data_text = readTextFile(data_path, "robot data");
  return parseRobotDescription(urdf_text, urdf_path, data_text, data_path, options);
}

RobotDescription loadUrdfOnly(const std::string& urdf_path, BaseType base, const LoadOptions& options, MimicMode mimic_mode) {
  const std::string urdf_text = readTextFile(urdf_path, "URDF");
  RobotDescription d;
  d.urdf_path = urdf_path;
  d.base = base;
  d.strict = options.strict;
  ProblemList problems(urdf_path, options.strict);
  detail::MimicPolicy mimic;
  mimic.mode = mimic_mode;
  mimic.given = mimic_mode == MimicMode::Locked;  // asked for: no note that a data file could say it
  detail::readUrdf(urdf_text, urdf_path, base, mimic, options, d, problems);
  detail::narrowCoupledMasters(d, problems);
  detail::noteUnspecifiedLimits(d, problems);
  problems.throwIfErrors();
  keepWarnings(d, problems);
  return d;
}

}  // namespace lexdyn::model
