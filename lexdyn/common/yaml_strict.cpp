#include "lexdyn/common/yaml_strict.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_text.hpp"

#include <yaml-cpp/depthguard.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace lexdyn::yaml {

namespace {

std::string joinKey(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

std::string describe(const YAML::Node& n) {
  if (!n.IsDefined()) return "nothing";
  switch (n.Type()) {
    case YAML::NodeType::Null:
      return "null";
    case YAML::NodeType::Scalar:
      return "'" + n.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "an undefined node";
  }
}

std::string joinList(const std::vector<std::string>& items) {
  std::string s;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i) s += ", ";
    s += items[i];
  }
  return s;
}

// A plain (unquoted) scalar has tag "?" in yaml-cpp; quoted scalars have tag "!".
bool isPlainScalar(const YAML::Node& n) { return n.IsScalar() && n.Tag() != "!"; }

}  // namespace

namespace {
thread_local KeyRecorder* t_recorder = nullptr;
}  // namespace

KeyRecorder::KeyRecorder() : previous_(t_recorder) { t_recorder = this; }
KeyRecorder::~KeyRecorder() { t_recorder = previous_; }
void KeyRecorder::record(const std::string& path) {
  if (t_recorder) t_recorder->paths_.push_back(path);
}

Node::Node(YAML::Node node, std::string file, std::string path) : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

std::string Node::where() const {
  std::string w = file_;
  const YAML::Mark m = node_.IsDefined() ? node_.Mark() : YAML::Mark::null_mark();
  if (!m.is_null() && m.line >= 0) w += ":" + std::to_string(m.line + 1);
  if (!path_.empty()) w += ": " + path_;
  return w;
}

void Node::fail(const std::string& what) const { throw InputError(where(), what); }

double Node::asDouble() const {
  if (!isPlainScalar(node_)) fail("expected a number, found " + describe(node_));
  const std::string& s = node_.Scalar();
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) {
    fail("expected a finite number, found '" + s + "'");
  }
  return v;
}

double Node::asPositiveDouble() const {
  const double v = asDouble();
  if (!(v > 0.0)) fail("expected a number > 0, found " + node_.Scalar());
  return v;
}

double Node::asNonNegativeDouble() const {
  const double v = asDouble();
  if (!(v >= 0.0)) fail("expected a number >= 0, found " + node_.Scalar());
  return v;
}

namespace {
std::string fmtRange(double v) { return formatNumber(v); }
}  // namespace

double Node::asDoubleIn(double lo, double hi, const std::string& unit) const {
  const double v = asDouble();
  if (!(v >= lo && v <= hi)) {
    fail("expected a number in [" + fmtRange(lo) + ", " + fmtRange(hi) + "]" + (unit.empty() ? "" : " " + unit) + ", found " +
         node_.Scalar());
  }
  return v;
}

int Node::asIntIn(int lo, int hi) const {
  const int v = asInt();
  if (v < lo || v > hi) {
    fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], found " + node_.Scalar());
  }
  return v;
}

int Node::asInt() const {
  if (!isPlainScalar(node_)) fail("expected an integer, found " + describe(node_));
  const std::string& s = node_.Scalar();
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || v < -2147483647L || v > 2147483647L) {
    fail("expected an integer, found '" + s + "'");
  }
  return static_cast<int>(v);
}

bool Node::asBool() const {
  if (isPlainScalar(node_)) {
    const std::string& s = node_.Scalar();
    if (s == "true") return true;
    if (s == "false") return false;
  }
  fail("expected true or false, found " + describe(node_));
}

std::string Node::asString() const {
  if (!node_.IsScalar() || node_.Scalar().empty()) {
    fail("expected a non-empty string, found " + describe(node_));
  }
  return node_.Scalar();
}

Eigen::VectorXd Node::asVectorAnySize(int min_size) const {
  if (!node_.IsSequence()) fail("expected a sequence of numbers, found " + describe(node_));
  const int n = static_cast<int>(node_.size());
  if (n < min_size) {
    fail("expected at least " + std::to_string(min_size) + " numbers, found " + std::to_string(n));
  }
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = (*this)[i].asDouble();
  return v;
}

Eigen::VectorXd Node::asVector(int n) const {
  if (!node_.IsSequence()) {
    fail("expected a sequence of " + std::to_string(n) + " numbers, found " + describe(node_));
  }
  if (static_cast<int>(node_.size()) != n) {
    fail("expected " + std::to_string(n) + " numbers, found " + std::to_string(node_.size()));
  }
  return asVectorAnySize(n);
}

Eigen::Vector3d Node::asVector3() const { return asVector(3); }

Eigen::VectorXd Node::asVectorIn(int n, double lo, double hi, const std::string& unit) const {
  asVector(n);  // shape and numbers first
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = (*this)[i].asDoubleIn(lo, hi, unit);
  return v;
}

Eigen::Vector3d Node::asVector3In(double lo, double hi, const std::string& unit) const { return asVectorIn(3, lo, hi, unit); }

std::string Node::asEnum(const std::vector<std::string>& choices) const {
  const std::string s = asString();
  for (const auto& c : choices) {
    if (c == s) return s;
  }
  fail("expected one of {" + joinList(choices) + "}, found '" + s + "'");
}

int Node::size() const {
  if (!node_.IsSequence()) fail("expected a sequence, found " + describe(node_));
  return static_cast<int>(node_.size());
}

Node Node::operator[](int i) const {
  if (!node_.IsSequence()) fail("expected a sequence, found " + describe(node_));
  return Node(node_[static_cast<size_t>(i)], file_, path_ + "[" + std::to_string(i) + "]");
}

std::vector<Node> Node::elements() const {
  std::vector<Node> out;
  const int n = size();
  out.reserve(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) out.push_back((*this)[i]);
  return out;
}

std::vector<std::pair<std::string, Node>> Node::entries() const {
  KeyRecorder::record(joinKey(path_, "*"));
  return entriesOf();
}

std::vector<std::pair<std::string, Node>> Node::entriesOf() const {
  if (!node_.IsMap()) fail("expected a mapping, found " + describe(node_));
  std::vector<std::pair<std::string, Node>> out;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    if (!it->first.IsScalar()) {
      Node(it->first, file_, path_).fail("mapping keys must be plain strings");
    }
    const std::string key = it->first.Scalar();
    for (const auto& e : out) {
      if (e.first == key) Node(it->first, file_, joinKey(path_, key)).fail("duplicate key '" + key + "'");
    }
    out.emplace_back(key, Node(it->second, file_, joinKey(path_, key)));
  }
  return out;
}

Node loadString(const std::string& text, const std::string& file) {
  requireText(text, file, "YAML");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::DeepRecursion& e) {
    std::string where = file;
    if (!e.mark.is_null()) where += ":" + std::to_string(e.mark.line + 1);
    throw InputError(where, "YAML nesting deeper than " + std::to_string(e.depth() - 1) +
                                " levels (sequences or mappings "
                                "inside each other); case, robot and manifest files need fewer than 10");
  } catch (const YAML::Exception& e) {
    std::string where = file;
    if (!e.mark.is_null()) where += ":" + std::to_string(e.mark.line + 1);
    throw InputError(where, "YAML syntax error: " + e.msg);
  }
  Node n(root, file, "");
  if (!root.IsMap()) n.fail("expected a YAML mapping at the top level, found " + describe(root));
  return n;
}

Node loadFile(const std::string& path) { return loadString(readTextFile(path, "YAML"), path); }

StrictMap::StrictMap(const Node& node) : node_(node) {
  for (auto& e : node.entriesOf()) keys_.push_back(e.first);  // entriesOf() checks duplicates
  used_.assign(keys_.size(), false);
}

bool StrictMap::has(const std::string& key) const {
  for (const auto& k : keys_) {
    if (k == key) return true;
  }
  return false;
}

std::optional<Node> StrictMap::optional(const std::string& key) {
  allowed_.push_back(key);
  KeyRecorder::record(joinKey(node_.path(), key));
  for (size_t i = 0; i < keys_.size(); ++i) {
    if (keys_[i] == key) {
      used_[i] = true;
      return Node(node_.raw()[key], node_.file(), joinKey(node_.path(), key));
    }
  }
  return std::nullopt;
}

Node StrictMap::required(const std::string& key) {
  auto n = optional(key);
  if (!n) node_.fail("missing required key '" + key + "'");
  return *n;
}

void StrictMap::finish() const {
  for (size_t i = 0; i < keys_.size(); ++i) {
    if (!used_[i]) {
      Node(node_.raw()[keys_[i]], node_.file(), joinKey(node_.path(), keys_[i]))
          .fail("unknown key '" + keys_[i] + "' (allowed here: " + joinList(allowed_) + ")");
    }
  }
}

}  // namespace lexdyn::yaml
