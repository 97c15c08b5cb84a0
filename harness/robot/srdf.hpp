// A robot's SRDF (the semantic description of ROS's MoveIt): its groups, named group states
// (postures) and end effectors, as `robot init` uses them. Only what is read is modelled.
#pragma once

#include "lexdyn/common/problems.hpp"
#include "lexdyn/model/robot_description.hpp"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace lexdyn::robot {

struct SrdfGroup {
  std::string name;
  std::vector<std::pair<std::string, std::string>> chains;  ///< (base_link, tip_link)
  std::vector<std::string> links, joints, subgroups;
  int line = 0;
};

/// A <group_state>: joint values by name (joints of the model; the free-flyer's 7 values and the
/// joints the loader locked are dropped, with a note).
struct SrdfState {
  std::string name, group;
  std::vector<std::pair<std::string, double>> values;
  int line = 0;
};

struct SrdfEndEffector {
  std::string name, parent_link, group;
  int line = 0;
};

struct Srdf {
  std::string path;
  std::string robot_name;
  std::vector<SrdfGroup> groups;
  std::vector<SrdfState> states;
  std::vector<SrdfEndEffector> end_effectors;
  std::vector<std::string> virtual_joints;  ///< names of <virtual_joint>s (the base, usually)
  std::vector<std::string> notes;           ///< what was dropped or assumed, for the drafted files
};

/// Reads an SRDF for the robot `d`. Records every problem in `problems` (joints and links it names
/// that the URDF lacks, a state without a group, bad numbers), each with the file and line.
/// `skip_unknown`: a group state's joint the URDF lacks is dropped with a note instead.
Srdf readSrdf(const std::string& path, const model::RobotDescription& d, ProblemList& problems, bool skip_unknown = false);

}  // namespace lexdyn::robot
