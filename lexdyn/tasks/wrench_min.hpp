// wrench_min (equality, ng rows): dt gamma = 0 (velocity domain) or gamma = 0 (acceleration
// domain), on every generator variable (paper sec. IX, level 11; the WLS objective's gamma = 0).
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

class WrenchMinTask : public TaskModel {
 public:
  WrenchMinTask(std::string name, const ContactLayout& layout);

  int rows() const override { return ng_; }
  TaskKind kind() const override { return TaskKind::Equality; }
  bool supports(Domain) const override { return true; }
  /// A = [0 I], lower = upper = 0 (constant).
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;
  void compute(const TickContext& ctx, TaskData& d) const override;

 private:
  int nv_ = 0, ng_ = 0;
};

}  // namespace lexdyn::tasks
