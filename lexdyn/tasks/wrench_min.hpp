// wrench_min (equality, ng rows): dt gamma = 0 (velocity domain) or gamma = 0 (acceleration
// domain), on every generator variable (paper sec. IX, level 11; the WLS objective's gamma = 0).
#pragma once

#include "lexdyn/tasks/variable_rows.hpp"

namespace lexdyn::tasks {

class WrenchMinTask : public GeneratorRowsTask {
 public:
  WrenchMinTask(std::string name, const ContactLayout& layout);

  TaskKind kind() const override { return TaskKind::Equality; }
  /// lower = upper = 0.
  void compute(const TickContext& ctx, TaskData& d) const override;
};

}  // namespace lexdyn::tasks
