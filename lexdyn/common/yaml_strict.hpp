// Strict reading of YAML data files (robot data files, case files).
//
// Every value is read through a `yaml::Node`, which remembers the file and the key path it
// came from ("cases/stand.yaml:12: sim.contact.stiffness"), so that every error names the file,
// the line and the field. Mappings are read through `yaml::StrictMap`, which refuses unknown
// and duplicate keys. Numbers must be plain (unquoted) finite scalars, strings must be scalars,
// booleans must be `true` or `false`.
//
// This header includes yaml-cpp. It is used by the loaders of lexdyn/model and harness/cases;
// it is not part of the controller's per-tick API.
#pragma once

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <vector>

namespace lexdyn::yaml {

/// A YAML node with its origin (file and key path).
class Node {
 public:
  Node(YAML::Node node, std::string file, std::string path);

  /// "file:line: path" (line is 1-based; omitted when unknown).
  std::string where() const;
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& raw() const { return node_; }

  bool isMap() const { return node_.IsMap(); }
  bool isSequence() const { return node_.IsSequence(); }
  bool isScalar() const { return node_.IsScalar(); }
  bool isNull() const { return node_.IsNull(); }

  /// Throws lexdyn::InputError(where(), what).
  [[noreturn]] void fail(const std::string& what) const;

  double asDouble() const;             ///< plain finite number
  double asPositiveDouble() const;     ///< > 0
  double asNonNegativeDouble() const;  ///< >= 0
  /// A plain finite number in [lo, hi]; the error names the range and `unit` (e.g. "s", "m").
  double asDoubleIn(double lo, double hi, const std::string& unit = "") const;
  /// A plain integer in [lo, hi].
  int asIntIn(int lo, int hi) const;
  int asInt() const;             ///< plain integer
  bool asBool() const;           ///< true / false
  std::string asString() const;  ///< any scalar, non-empty
  /// A sequence of exactly `n` numbers.
  Eigen::VectorXd asVector(int n) const;
  /// A sequence of any length >= min_size of numbers.
  Eigen::VectorXd asVectorAnySize(int min_size = 0) const;
  Eigen::Vector3d asVector3() const;
  /// A sequence of exactly `n` numbers, each in [lo, hi] (errors name the element).
  Eigen::VectorXd asVectorIn(int n, double lo, double hi, const std::string& unit = "") const;
  Eigen::Vector3d asVector3In(double lo, double hi, const std::string& unit = "") const;
  /// One of `choices` (error lists them).
  std::string asEnum(const std::vector<std::string>& choices) const;

  /// Sequence access.
  int size() const;  ///< requires a sequence
  Node operator[](int i) const;
  std::vector<Node> elements() const;  ///< requires a sequence (an empty one is fine)

  /// Mapping entries in file order (keys must be unique scalars). A mapping read this way has
  /// free keys: it is recorded as "path.*" by an alive KeyRecorder.
  std::vector<std::pair<std::string, Node>> entries() const;

 private:
  friend class StrictMap;
  std::vector<std::pair<std::string, Node>> entriesOf() const;
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

/// Loads a YAML file; throws InputError naming the file (and line) when it cannot be read, is
/// not text (lexdyn/common/input_text.hpp) or cannot be parsed (also: nesting deeper than
/// yaml-cpp's limit). The top-level node must be a mapping.
Node loadFile(const std::string& path);
/// Parses YAML text; `file` is used in messages only.
Node loadString(const std::string& text, const std::string& file);

/// Reads a mapping strictly: every key must be consumed by required()/optional(), and
/// finish() throws on any key that was not (listing the keys that are allowed).
class StrictMap {
 public:
  explicit StrictMap(const Node& node);
  Node required(const std::string& key);
  std::optional<Node> optional(const std::string& key);
  bool has(const std::string& key) const;
  /// Throws on unknown keys. Call after all reads.
  void finish() const;
  const Node& node() const { return node_; }

 private:
  Node node_;
  std::vector<std::string> keys_;     // file order
  std::vector<std::string> allowed_;  // every key asked for
  std::vector<bool> used_;
};

/// Records the key paths that StrictMap readers ask for while it is alive (one per thread):
/// the keys a reader accepts, present in the file or not, in Node::path() form
/// ("controller.tasks[9].gains.kp"). Case overrides use it to tell a valid absent key from a
/// misspelt one.
class KeyRecorder {
 public:
  KeyRecorder();
  ~KeyRecorder();
  KeyRecorder(const KeyRecorder&) = delete;
  KeyRecorder& operator=(const KeyRecorder&) = delete;
  const std::vector<std::string>& paths() const { return paths_; }
  /// Called by StrictMap; a no-op when no recorder is alive on this thread.
  static void record(const std::string& path);

 private:
  std::vector<std::string> paths_;
  KeyRecorder* previous_ = nullptr;
};

}  // namespace lexdyn::yaml
