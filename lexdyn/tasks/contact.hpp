// contact (equality, 6 rows): keeps the frame of a contact of the ContactLayout at the pose it
// had when the contact was made (paper sec. IX, "geometric contact constraints"). Rows 0-2: PD
// (pd.hpp, eq. 55/61) on the frame origin's position (J = linear rows of the frame Jacobian,
// Jdot u = the linear frame bias); rows 3-5: PD on its orientation with e = log(R_d R^T) and the
// re-centred rotation-vector function of orientation.hpp (J = angular rows).
//
// The held pose (p_d, R_d) is captured at the first compute() at which the contact is active
// after having been inactive (or at the very first compute()). While the contact is inactive
// the rows are void (A = 0, lower = upper = 0, engaged = 0, J = 0). The task has no runtime
// target (setTarget throws); the held pose is in ContactTaskData.
#pragma once

#include "lexdyn/tasks/pd.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct ContactTaskParams {
  std::string contact;       ///< a contact of the ContactLayout (its frame is the task frame)
  PdGains gains{100.0, {}};  ///< kp default 100 /s^2 (kv 20 /s): stiff, our choice
};

struct ContactTaskData : TaskData {
  bool holding = false;                                    ///< the pose below is captured and held
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      ///< p_d, world, m
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< R_d
};

class ContactTask : public TaskModel {
 public:
  ContactTask(std::string name, const model::RobotModel& model, const ContactLayout& layout, const ContactTaskParams& params);

  /// 6 (the frame's position and orientation), or 3 for a point contact (ContactSpec::point:
  /// the contact point's position).
  int rows() const override { return point_ ? 3 : 6; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool hasFunction() const override { return true; }
  bool geometric() const override { return true; }
  bool supports(Domain) const override { return true; }

  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Forgets the held pose (captured again at the next compute() with the contact active).
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  /// Position Hessian of the frame origin, or of a point contact's point (rows 0-2), and
  /// orientation Hessian (rows 3-5); nothing while the contact is inactive.
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  int contactIndex() const { return contact_; }
  model::FrameId frame() const { return frame_; }
  const Pd& gains() const { return pd_; }

 private:
  int nv_ = 0, ng_ = 0;
  int contact_ = -1;
  model::FrameId frame_ = -1;
  int body_ = -1;
  bool point_ = false;
  Eigen::Vector3d point_in_frame_ = Eigen::Vector3d::Zero();  ///< a point contact's point
  Pd pd_;
};

}  // namespace lexdyn::tasks
