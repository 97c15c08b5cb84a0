// The check types: a registry of name -> {parser, evaluator, unit, flags}. Each type has its own
// params struct (CheckSpec::params) and keeps its parser and its evaluator in one file
// (sim_checks, task_checks, joint_checks, contact_checks, health_checks); builtinChecks() lists
// them, one line per type. Adding a type: docs/architecture.md, "Adding a check type".
//
// Parsers read a case file's `checks` entry against a CheckContext: plain data about the case
// (robot, lexdyn controller, methods) that the case loader fills, so that harness/checks does not
// depend on harness/cases.
#pragma once

#include "harness/checks/checks.hpp"
#include "harness/records/controller_type.hpp"
#include "lexdyn/common/yaml_strict.hpp"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lexdyn::checks {

/// What a check's parser may ask about the case.
struct CheckContext {
  records::ControllerType controller = records::ControllerType::PostureServo;
  double control_period_s = 0.0;
  // The robot.
  std::vector<std::string> frames;
  std::vector<std::string> surfaces;  ///< contact surfaces of the robot data file (simulator side)
  struct Joint {
    std::string name;
    double effort_limit = 0.0;  ///< URDF effort limit (N m or N); <= 0: none
  };
  std::vector<Joint> joints;
  // The lexdyn controller.
  struct Contact {
    std::string name;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< in the contact frame
    double friction = 0.0;
    bool has_sensor = false;              ///< a linked force/torque sensor
    std::vector<Eigen::Vector3d> points;  ///< in the contact frame
  };
  std::vector<Contact> contacts;
  struct Task {
    std::string name;
    std::string type;
    bool has_gains = false;  ///< a task with PD gains (kp, kv)
    double kp = 0.0;
    std::optional<double> kv;  ///< absent: 2 sqrt(kp)
  };
  std::vector<Task> tasks;
  struct Method {
    std::string name;                 ///< bfgs, ah, gn, wls
    bool has_hierarchy = false;       ///< the case defines its hierarchy
    std::vector<std::string> tasks;   ///< the tasks its hierarchy uses
    std::vector<std::string> levels;  ///< its levels' names
  };
  std::vector<Method> methods;  ///< every method of the controller, in order

  bool lexdyn() const { return controller == records::ControllerType::Lexdyn; }
  std::vector<std::string> methodNames() const;
  /// The methods the case has a hierarchy for.
  std::vector<std::string> caseMethods() const;
  const Method* findMethod(const std::string& name) const;
  const Task* findTask(const std::string& name) const;
  const Contact* findContact(const std::string& name) const;
  std::vector<std::string> jointNames() const;

  /// Readers of references, failing at the node with the valid names where there are few.
  std::string frame(const yaml::Node& n) const;    ///< a robot frame
  std::string surface(const yaml::Node& n) const;  ///< a robot contact surface
  /// Joint name patterns ('*' any run of characters; at least one, each matching a joint): the
  /// joints they match, in the robot's order of first match.
  std::vector<std::string> jointPatterns(const yaml::Node& n) const;
  /// A list of task names (at least one, each a task of the controller).
  std::vector<std::string> taskNames(const yaml::Node& n) const;
  /// A method of the controller the case has a hierarchy for.
  std::string method(const yaml::Node& n) const;
  /// Every task must be in the hierarchy of every method in `methods` (its channels are not
  /// recorded otherwise); fails at `at`.
  void requireTasksInHierarchies(const yaml::Node& at, const std::vector<std::string>& tasks,
                                 const std::vector<std::string>& methods) const;
};

/// Glob match with '*' only.
bool globMatch(const std::string& pattern, const std::string& text);
/// "a, b, c" (for messages listing the valid names).
std::string joinNames(const std::vector<std::string>& v);
/// The name `n` holds, one of `names`; otherwise fails at n: "unknown KIND 'X' (LIST: a, b)".
std::string knownName(const yaml::Node& n, const std::vector<std::string>& names, const std::string& kind, const std::string& list);
/// The elements of a sequence of at least one; otherwise fails at n: "expected at least one WHAT".
std::vector<yaml::Node> atLeastOne(const yaml::Node& n, const std::string& what);

/// What a parser gets: the entry (common keys already read), the case, and the spec to fill
/// (limit, params).
struct CheckReader {
  yaml::StrictMap& map;
  const CheckContext& context;
  CheckSpec& spec;
  /// The methods the check applies to: its `methods`, or every method the case has (lexdyn).
  std::vector<std::string> methods;

  /// A `KEY: task` entry: a task of the controller in the hierarchy of every method of the check.
  std::string task(const std::string& key);
  /// A `KEY: [tasks]` entry, the same for each.
  std::vector<std::string> tasks(const std::string& key);
  /// An optional number: `key` read by `read` (e.g. &yaml::Node::asNonNegativeDouble), or
  /// `fallback` when absent.
  double number(const std::string& key, double fallback, double (yaml::Node::*read)() const);
  /// Optional `joints` patterns (default: every joint).
  std::vector<std::string> joints();
  /// The `contact` key: a controller contact. With `source` (then read as the optional key
  /// `source`, computed | sensed, default computed), a sensor is needed for `sensed`; without,
  /// always.
  const CheckContext::Contact& contact(std::string* source);
};

using CheckParser = void (*)(CheckReader& reader);
struct CheckType;
using CheckMaker = std::unique_ptr<Check> (*)(const CheckSpec& spec, const CheckType& type);

/// Flags of a check type.
enum CheckFlags : unsigned {
  kSimulatorChannels = 0,         ///< reads the simulator's channels (any controller)
  kControllerChannels = 1u << 0,  ///< reads the lexdyn controller's channels: needs it; has to_s
  kBoundsBelow = 1u << 1,         ///< passes when value >= limit (margin: value - limit)
  kMachineDependent = 1u << 2,    ///< a wall-clock measurement: decides only when asked
};

struct CheckType {
  std::string name;
  std::string unit;    ///< of the value (an evaluator may name a finer one, e.g. N m for torques)
  unsigned flags = 0;  ///< CheckFlags
  CheckParser parse = nullptr;
  CheckMaker make = nullptr;

  bool readsController() const { return (flags & kControllerChannels) != 0; }
  bool boundsBelow() const { return (flags & kBoundsBelow) != 0; }
  bool machineDependent() const { return (flags & kMachineDependent) != 0; }
};

/// The evaluator factory of a Check class constructed from (spec, type).
template <class C>
std::unique_ptr<Check> makeEvaluator(const CheckSpec& spec, const CheckType& type) {
  return std::make_unique<C>(spec, type);
}

class CheckRegistry {
 public:
  /// Adds a type; aborts on a duplicate name or a type without parser or evaluator.
  void add(CheckType type);
  const CheckType* find(const std::string& name) const;  ///< nullptr when unknown
  /// The type named; InputError(where, "unknown check type 'X' (known: ...)") when unknown.
  const CheckType& get(const std::string& name, const std::string& where) const;
  const std::vector<std::string>& names() const { return names_; }  ///< in registration order
  const std::vector<CheckType>& types() const { return types_; }

 private:
  std::vector<CheckType> types_;
  std::vector<std::string> names_;
};

/// The built-in check types.
const CheckRegistry& builtinChecks();

/// Reads one `checks` entry: the common keys (type, name, from_s, methods; to_s for the
/// controller's checks), then the type's own. InputError naming the file, line and key path.
CheckSpec readCheck(const yaml::Node& node, const CheckContext& context, const CheckRegistry& registry = builtinChecks());

/// The evaluator of a check of a type of `registry`.
std::unique_ptr<Check> makeCheck(const CheckSpec& spec, const CheckRegistry& registry);

/// Reads a method comparison (a `comparisons` entry, task_checks.cpp).
ComparisonSpec readComparison(const yaml::Node& node, const CheckContext& context);

}  // namespace lexdyn::checks
