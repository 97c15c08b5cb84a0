// `lexdyn-harness robot init`: from a URDF (and its SRDF) to a drafted data file and cases that
// run (docs/model.md, "Bringing your own robot"). Every value the URDF does not carry is guessed
// from its kinematics and geometry, and the comment beside it in the drafted file says where it
// came from.
#pragma once

#include "lexdyn/model/robot_description.hpp"

#include <string>
#include <vector>

namespace lexdyn::robot {

struct InitOptions {
  std::string urdf;
  std::string srdf;                ///< optional
  bool srdf_skip_unknown = false;  ///< drop an SRDF state's joints the URDF lacks (else an error)
  std::string out_dir;             ///< must not exist, or be empty
  std::vector<std::string> package_paths;
  std::string base;     ///< "free_flyer", "fixed" or "" (guess)
  std::string posture;  ///< the SRDF state to stand in ("" for the best one)
  bool strict = false;
  bool allow_missing_meshes = false;  ///< a mesh that cannot be found is a warning, not an error
  std::string mimic = "coupled";      ///< the URDF's <mimic> joints: coupled | locked (at the posture)
  double control_period_s = 0.005;
};

struct InitResult {
  std::vector<std::string> files;     ///< written, in DIR
  std::vector<std::string> summary;   ///< what was found and guessed, one line each
  std::vector<std::string> warnings;  ///< the loader's and the drafting's
};

/// Drafts DIR/<robot>.yaml, DIR/stand.yaml and (for a robot with two arms and legs, or one
/// fixed-base arm) DIR/reach.yaml. Writes into a temporary folder renamed to DIR at the end:
/// nothing is left in DIR when it fails. Throws lexdyn::InputError (every problem of the inputs).
InitResult initRobot(const InitOptions& options);

}  // namespace lexdyn::robot
