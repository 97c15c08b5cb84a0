// posture (equality, nj rows): PD (pd.hpp, eq. 55/61) on every joint towards a reference
// posture (the WLS baseline's posture task, paper sec. IX). Same rows as joint_position with all
// joints in model order. Target d.target = the posture (nj); initial target: `target`, or the
// named posture `posture` of the robot data file, or (neither) the joints at the first compute().
#pragma once

#include "lexdyn/tasks/pd.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct PostureParams {
  Eigen::VectorXd target;  ///< nj values; empty: see `posture`
  std::string posture;     ///< a named posture of the data file (exclusive with target); empty: hold
  PdGains gains;
};

class PostureTask : public TaskModel {
 public:
  PostureTask(std::string name, const model::RobotModel& model, const PostureParams& params = {});

  int rows() const override { return nj_; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool hasFunction() const override { return true; }
  bool supports(Domain) const override { return true; }
  int targetSize() const override { return nj_; }
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;

  /// A and J: the joint velocity unit rows (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Back to the initial target (or to holding at the next compute() when there is none).
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

  const Pd& gains() const { return pd_; }

 private:
  int nv_ = 0, nj_ = 0, offset_ = 0;
  std::vector<int> joints_;  ///< 0..nj-1
  Eigen::VectorXd initial_target_;
  Pd pd_;
};

}  // namespace lexdyn::tasks
