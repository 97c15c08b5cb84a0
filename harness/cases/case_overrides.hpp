// Case overrides: `lexdyn-harness run CASE --set PATH=VALUE ...` changes any value of a case by
// its key path before the case is read (docs/cases.md, "Overrides"). The overrides act on the
// YAML document, so an overridden case is validated exactly as a file holding the same values,
// and the effective case can be written out as one file (effectiveCaseText) that reproduces the
// run on its own.
//
// Key paths: keys joined by '.', sequence elements by index or by name: `duration_s`,
// `controller.tasks[right_hand].gains.kp` (or `controller.tasks.right_hand.gains.kp`),
// `controller.tasks[9].target[1]`, `sim.servo.gains[*ARM_JOINT7].kp` (an element is named by its
// `name`, or by its `match` for the servo gain groups). VALUE is YAML: `0.5`, `bfgs`, `[0.4, -2,
// 2]`, `{kp: 1}`. A key that a reader accepts may be set even when the file leaves it out; a path
// that does not exist is an error naming the nearest valid paths.
#pragma once

#include <string>
#include <vector>

namespace lexdyn::cases {

struct Override {
  std::string path;   ///< as given
  std::string value;  ///< YAML text
  /// How errors name it ("--set PATH=VALUE" by default; "--method" for `run --method`).
  std::string label;
};

/// Parses "PATH=VALUE" (the first '=' splits). Throws InputError naming `label_prefix`.
Override parseOverride(const std::string& arg, const std::string& label_prefix = "--set");

/// "PATH=VALUE" of each override, for summaries and reproducer commands.
std::string overrideText(const Override& o);

}  // namespace lexdyn::cases
