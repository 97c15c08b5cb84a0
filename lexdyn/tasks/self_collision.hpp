// self_collision (inequality, one row per capsule pair): velocity damper (damper.hpp) on the
// surface distance d of a pair of capsules (RobotModel::capsuleDistance), J_d = n^T (J_a - J_b)
// at the witness points (n from b to a):
//   velocity domain:     J_d u(k+1) >= -xi (d - d_s) / (d_i - d_s)              when d < d_i
//   acceleration domain: J_d udot >= (-xi (d - d_s) / (d_i - d_s) - J_d u) / dt   (Jdot_d u neglected)
// otherwise the row is free (lower = -inf). Upper bounds are +inf. d.error[r] = d,
// d.engaged[r] = (d < d_i), d.J.row(r) = J_d. A free row constrains nothing whatever its
// coefficients: its J_d is not computed and its rows of J and A are zeros (with many pairs most
// are free at any tick), unless the row was active in the previous solve (TaskData::held) and
// the method reads earlier ticks' Jacobians with that solve's multipliers
// (TickContext::free_row_jacobians: LexDynBFGS's secant); its witness points and normal are
// computed.
//
// Hessian (an approximation, documented in docs/controller.md): the distance is treated as
// n^T (p_a(q) - p_b(q)) with the normal n and the witness points p_a, p_b held fixed on their
// bodies at this tick, so H_d ~= n^T H(p_a) - n^T H(p_b) (position Hessians of the two witness
// points, lexdyn::hessian::accumulatePointHessian). The terms from the normal turning and the
// witness points sliding along the capsule axes are neglected; the first derivative of this
// function equals J_d exactly.
#pragma once

#include <optional>
#include <utility>

#include "lexdyn/tasks/damper.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

struct SelfCollisionParams {
  /// Capsule name pairs; each must be a collision pair of the robot data file (either order).
  /// Empty: every pair of the data file.
  std::vector<std::pair<std::string, std::string>> pairs;
  /// d_i, d_s in m; absent: the data file's collision_pairs.interaction_distance / safety_distance.
  std::optional<double> interaction_distance, safety_distance;
  double xi = 0.5;       ///< m/s
  bool adaptive = true;  ///< gain raised to the approach speed at engagement (damper.hpp)
};

struct SelfCollisionTaskData : DamperTaskData {
  Eigen::Matrix3Xd point_a, point_b;  ///< witness points of each row in the frames of their links
  Eigen::Matrix3Xd normal;            ///< unit normal of each row (world, from b to a)
  std::vector<char> jacobian_zero;    ///< per row: its rows of J and A hold zeros (a free row's)
};

class SelfCollisionTask : public TaskModel {
 public:
  SelfCollisionTask(std::string name, const model::RobotModel& model, const SelfCollisionParams& params = {});

  int rows() const override { return static_cast<int>(pairs_.size()); }
  TaskKind kind() const override { return TaskKind::Inequality; }
  bool hasFunction() const override { return true; }
  bool geometric() const override { return true; }
  bool supports(Domain) const override { return true; }

  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void reset(TaskData& d) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;
  void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                         Eigen::Ref<Eigen::MatrixXd> H) const override;
  void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const override;

  /// Model collision-pair index of row r, and the frames (links) of its capsules a and b.
  int modelPair(int r) const { return pairs_[static_cast<size_t>(r)].pair; }
  model::FrameId frameA(int r) const { return pairs_[static_cast<size_t>(r)].frame_a; }
  model::FrameId frameB(int r) const { return pairs_[static_cast<size_t>(r)].frame_b; }
  const DamperParams& damper() const { return damper_; }

 private:
  struct Pair {
    int pair = -1;
    model::FrameId frame_a = -1, frame_b = -1;
    int body_a = -1, body_b = -1;
  };
  int nv_ = 0;
  std::vector<Pair> pairs_;
  DamperParams damper_;
};

}  // namespace lexdyn::tasks
