// The controllers a case can run (docs/cases.md, "Controllers"): one enum, one spelling each.
// Case files and trace headers carry the spelling, code carries the enum.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lexdyn::records {

enum class ControllerType {
  PostureServo,  ///< "posture_servo": the joint servos hold a posture (plus periodic motions)
  Lexdyn,        ///< "lexdyn": the hierarchical whole-body controller
};

/// The file spelling: "posture_servo", "lexdyn".
inline const char* toString(ControllerType t) { return t == ControllerType::Lexdyn ? "lexdyn" : "posture_servo"; }

/// Every spelling, in declaration order (a reader's choices).
inline std::vector<std::string> controllerTypeNames() { return {"posture_servo", "lexdyn"}; }

/// The controller a spelling names; nullopt for any other text.
inline std::optional<ControllerType> parseControllerType(std::string_view text) {
  if (text == "posture_servo") return ControllerType::PostureServo;
  if (text == "lexdyn") return ControllerType::Lexdyn;
  return std::nullopt;
}

}  // namespace lexdyn::records
