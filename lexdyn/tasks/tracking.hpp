// Base of the PD tasks that track a target (pd.hpp, eq. 55/61): com, position, orientation,
// joint_position, posture. Every row is an equality, engaged at every tick. The target
// d.target is the initial target given at construction, then the one given to setTarget(); a
// task without an initial target holds the value its function has at the first compute()
// (holdTarget()). reset() goes back to the initial target, or to holding.
#pragma once

#include "lexdyn/tasks/pd.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

class TrackingTask : public TaskModel {
 public:
  int rows() const override { return rows_; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool hasFunction() const override { return true; }
  bool supports(Domain) const override { return true; }
  int targetSize() const override { return target_size_; }
  /// Finite values.
  void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const override;

  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  /// Back to the initial target (or to holding at the next compute() when there is none).
  void reset(TaskData& d) const override;

  const Pd& gains() const { return pd_; }

 protected:
  /// `rows`: the size of the task function; `target_size`: the size of d.target.
  TrackingTask(std::string name, const model::RobotModel& model, int rows, int target_size);

  /// Checks the target (checkTarget()) and keeps it as the initial target.
  void setInitialTarget(const Eigen::Ref<const Eigen::VectorXd>& target);
  /// createData() with a data type D derived from TaskData: the layout's nv checked, every row
  /// engaged, then reset().
  template <class D>
  std::unique_ptr<D> makeTrackingData(const ContactLayout& layout) const {
    requireLayoutNv(layout, nv_);
    auto d = makeData<D>(layout, true);
    reset(*d);
    return d;
  }
  /// While d has no target (none initial, none set): d.target = `value`, the task function's
  /// value now, which the task then holds. Allocation-free.
  static void holdTarget(TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& value);

  int nv_ = 0;
  Pd pd_;

 private:
  int rows_ = 0, target_size_ = 0;
  Eigen::VectorXd initial_target_;  ///< empty: none (hold)
};

}  // namespace lexdyn::tasks
