// The case file as a YAML document: key paths, overrides, and the effective case
// (case_overrides.hpp). Internal to the harness (includes yaml-cpp); the case loader and the
// sweep driver use it.
#pragma once

#include "harness/cases/case_overrides.hpp"

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace lexdyn::cases::doc {

/// The keys a case reader asks for, as recorded while reading the case (yaml::KeyRecorder), in
/// Node::path() form; "P.*" marks a mapping P whose keys are free (joint names, methods).
struct Schema {
  std::vector<std::string> keys;
  bool knows(const std::string& canonical) const;
};

/// A key path resolved against a document.
struct Resolved {
  std::string canonical;  ///< Node::path() form: controller.tasks[9].gains.kp
  std::string display;    ///< elements by name where they have one: controller.tasks[right_hand].gains.kp
  bool exists = false;    ///< false: a valid key the document leaves out (it is created on set)
  YAML::Node node;        ///< the value when it exists
};

/// Resolves `path` (any accepted spelling) in `root`. Throws InputError(where, ...) for a path
/// that is neither in the document nor a key the schema accepts, naming the nearest valid paths.
Resolved resolve(const YAML::Node& root, const std::string& path, const Schema& schema, const std::string& where);

/// Sets the value at `path` (creating absent keys the schema accepts). Returns the resolution.
Resolved set(YAML::Node& root, const std::string& path, const YAML::Node& value, const Schema& schema, const std::string& where);

/// Parses an override's VALUE (YAML text); InputError naming the override.
YAML::Node parseValue(const Override& o);

/// The display path of a canonical path of `root` (elements named where they have a name).
std::string displayPath(const YAML::Node& root, const std::string& canonical);

/// The document of a case file with its overrides applied, and the schema of the case's
/// readers (recorded by reading the file as it is). Throws InputError.
struct Document {
  std::string file;
  YAML::Node root;  ///< overrides applied (a deep copy of the file's tree)
  Schema schema;
  std::vector<Override> overrides;
  std::vector<std::string> canonical;  ///< per override, its canonical path
};

/// If `e` is an error at a path an override set (or below it), the same error naming the
/// override instead of the file line (whose text the override replaced).
std::string relabel(const Document& d, const std::string& where);

/// Emits a document as YAML text (block style where the file used it).
std::string emit(const YAML::Node& root);

}  // namespace lexdyn::cases::doc
