// `lexdyn-harness robot check`: what a user checks before trusting a model (docs/model.md,
// "Bringing your own robot"): mass, height, the centre of mass against the support polygon in
// the posture, the contact points in the world, the joint table (limits, effort, servo gains,
// the posture's margin to its limits), mimic couplings and locked joints, every warning; and a
// picture of the robot in its posture (three views, PNG).
#pragma once

#include <string>
#include <vector>

namespace lexdyn::robot {

struct CheckOptions {
  std::string input;  ///< a data file, a case file or a URDF
  std::string urdf;   ///< with a data file: its URDF (else its `urdf` key)
  std::vector<std::string> package_paths;
  std::string posture;  ///< the posture to show ("" : the case's, else the first)
  std::string png;      ///< the picture ("": <input folder>/<robot>_posture.png; "-": none)
  bool strict = false;
};

struct CheckReport {
  std::string text;  ///< the report, as printed
  std::string png;   ///< the picture written ("" when none)
  int warnings = 0;
  bool com_inside = true;  ///< legged robots: the CoM above the support polygon
};

/// Loads the robot and reports on it. Throws lexdyn::InputError for bad input (every problem).
CheckReport checkRobot(const CheckOptions& options);

}  // namespace lexdyn::robot
