// The controllers a case can run (docs/cases.md, "Controllers"): one enum, one spelling each.
// Case files and trace headers carry the spelling, code carries the enum.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lexdyn::records {

enum class ControllerType {
  PostureServo,  ///< "posture_servo": the joint servos hold a posture (plus periodic motions)
  Lexdyn,        ///< "lexdyn": the hierarchical whole-body controller
};

/// Every controller with its file spelling, in declaration order: the one table the functions
/// below read.
inline constexpr std::pair<ControllerType, const char*> kControllerTypes[] = {
    {ControllerType::PostureServo, "posture_servo"},
    {ControllerType::Lexdyn, "lexdyn"},
};

/// The file spelling: "posture_servo", "lexdyn".
inline const char* toString(ControllerType t) {
  for (const auto& [type, name] : kControllerTypes) {
    if (type == t) return name;
  }
  return "?";
}

/// Every spelling, in declaration order (a reader's choices).
inline std::vector<std::string> controllerTypeNames() {
  std::vector<std::string> out;
  for (const auto& entry : kControllerTypes) out.push_back(entry.second);
  return out;
}

/// The controller a spelling names; nullopt for any other text.
inline std::optional<ControllerType> parseControllerType(std::string_view text) {
  for (const auto& [type, name] : kControllerTypes) {
    if (text == name) return type;
  }
  return std::nullopt;
}

}  // namespace lexdyn::records
