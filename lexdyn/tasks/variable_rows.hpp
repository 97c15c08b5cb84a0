// Bases of the tasks whose rows are decision variables themselves (A is a constant block of the
// identity): one row per velocity variable (trust_region, velocity_min) or per contact generator
// variable (contact_force_bounds, wrench_min).
#pragma once

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

/// Row i is u_i(k+1) (free-flyer included): A = [I 0], every row engaged. Velocity domain only.
class VelocityRowsTask : public TaskModel {
 public:
  int rows() const override { return nv_; }
  bool supports(Domain d) const override { return d == Domain::Velocity; }
  bool velocityOnly() const override { return true; }
  bool constantMatrix() const override { return true; }
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;

 protected:
  VelocityRowsTask(std::string name, const model::RobotModel& model);

  int nv_ = 0;
};

/// Row k is generator variable k (dt gamma_k in the velocity domain, gamma_k in the acceleration
/// domain): A = [0 I]. The layout fixes the rows (its ng); createData() requires a layout of the
/// same sizes. Equality rows are engaged at every tick, other rows as compute() decides.
class GeneratorRowsTask : public TaskModel {
 public:
  int rows() const override { return ng_; }
  bool supports(Domain) const override { return true; }
  bool constantMatrix() const override { return true; }
  std::unique_ptr<TaskData> createData(const ContactLayout& layout) const override;

 protected:
  GeneratorRowsTask(std::string name, const ContactLayout& layout);

  int nv_ = 0, ng_ = 0;
};

}  // namespace lexdyn::tasks
