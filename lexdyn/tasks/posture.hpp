// posture (equality, nj rows): PD (pd.hpp, eq. 55/61) on every joint towards a reference
// posture (the WLS baseline's posture task, paper sec. IX). Same rows as joint_position with all
// joints in model order. Target d.target = the posture (nj); initial target: `target`, or the
// named posture `posture` of the robot data file, or (neither) the joints at the first compute().
#pragma once

#include "lexdyn/tasks/joint_position.hpp"

namespace lexdyn::tasks {

struct PostureParams {
  Eigen::VectorXd target;  ///< nj values; empty: see `posture`
  std::string posture;     ///< a named posture of the data file (exclusive with target); empty: hold
  PdGains gains;
};

class PostureTask : public JointTrackingTask {
 public:
  PostureTask(std::string name, const model::RobotModel& model, const PostureParams& params = {});
};

}  // namespace lexdyn::tasks
