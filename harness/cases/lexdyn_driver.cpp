#include "harness/cases/lexdyn_driver.hpp"

#include "harness/checks/checks.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/control/controller.hpp"
#include "lexdyn/model/robot_model.hpp"
#include "lexdyn/solver/problem_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Geometry>

namespace lexdyn::cases {

namespace {

std::string num(double v) { return formatNumber(v, 10); }

int indexOf(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

const char* const kWrench[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};
const char* const kTimers[5] = {"model", "tasks", "hessian", "solver", "tick"};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  rank = std::clamp<size_t>(rank, 1, v.size());
  return v[rank - 1];
}

}  // namespace

struct LexdynDriver::Impl {
  const CaseSpec& spec;
  const LexdynSpec& lx;
  model::RobotModel model;
  std::unique_ptr<control::Controller> ctl;
  control::RobotState state;
  int nj = 0;
  double dt = 0.005;

  struct TaskRec {
    int index = -1;  // controller task index
    std::string name;
    int target_values = 0;  // recorded target values
    std::vector<std::string> target_names;
  };
  std::vector<TaskRec> tasks;  // the tasks of the method's hierarchy
  struct ContactRec {
    int index = -1;  // controller contact index
    std::string name;
    model::FrameId frame = -1;       // in the simulator's model
    model::FrameId ctrl_frame = -1;  // in the controller's model
    int grasp = -1;                  // simulator grasp
    int sensor = -1;                 // index into the simulator's sensor readings
    model::FrameId sensor_frame = -1;
    bool point = false;  // a point contact: its wrenches in the world's axes (z the ground's normal)
    bool fixed = false;
    int surface = -1;                                              // the simulator's contact surface (description order); -1: none
    double lost_since = std::numeric_limits<double>::quiet_NaN();  // divergence guard
  };
  std::vector<ContactRec> contacts;

  struct Generator {
    enum class Kind { Trajectory, Swing, Ramp } kind = Kind::Trajectory;
    int task = -1;
    double start = 0.0;
    TargetTrajectory trajectory;
    Swing sw;
    double ramp_s = 0.0;
    Eigen::VectorXd from, to;  ///< ramp: entries not finite at either end take `to` at once
  };
  std::vector<Generator> generators;
  // Divergence guard: the configuration the last command planned for this tick.
  model::Configuration expected;
  bool have_expected = false;
  double weight = 0.0;  // N
  Eigen::VectorXd target3 = Eigen::VectorXd::Zero(3);
  Eigen::VectorXd rampValue;

  // Statistics.
  long ticks = 0;
  std::vector<double> error_sum, error_last;
  int peak_iterations = -1;
  double peak_at = 0.0;
  int peak_factorizations = -1;
  double peak_factorizations_at = 0.0;
  std::vector<long> status_counts, solver_counts, augmented;
  std::vector<std::vector<double>> timers;

  Impl(const CaseSpec& s, const sim::Simulator& simu)
      : spec(s), lx(s.controller.lexdyn), model(model::RobotModel::fromFiles(s.urdf_path, s.data_path, s.robot_options)) {
    ctl = std::make_unique<control::Controller>(model, buildControllerConfig(lx, model));
    nj = model.numJoints();
    dt = s.control_period_s;
    state.q = model.neutralConfiguration();
    state.u = Eigen::VectorXd::Zero(model.nv());
    for (const std::string& name : usedTasks(lx, lx.method)) {
      TaskRec r;
      r.name = name;
      r.index = ctl->taskIndex(name);
      r.target_names = taskTarget(lx.tasks[static_cast<size_t>(lx.findTask(name))], model.description()).channels;
      r.target_values = static_cast<int>(r.target_names.size());
      tasks.push_back(r);
    }
    const sim::Multibody& sm = simu.model();
    const model::RobotDescription& d = sm.description();
    for (const ContactEntry& ce : lx.contacts) {
      ContactRec c;
      c.name = ce.name;
      c.index = ctl->contactIndex(ce.name);
      c.frame = sm.frameId(ce.frame);
      c.ctrl_frame = model.frameId(ce.frame);
      c.point = ce.dims == 3;
      c.fixed = ce.fixed;
      for (size_t k = 0; k < d.contact_surfaces.size(); ++k) {
        if (!ce.surface.empty() && d.contact_surfaces[k].name == ce.surface) c.surface = static_cast<int>(k);
      }
      if (!ce.grasp.empty()) c.grasp = simu.graspIndex(ce.grasp);
      if (!ce.sensor.empty()) {
        for (size_t k = 0; k < d.force_sensors.size(); ++k) {
          if (d.force_sensors[k].name == ce.sensor) {
            c.sensor = static_cast<int>(k);
            c.sensor_frame = sm.frameId(d.frames[static_cast<size_t>(d.force_sensors[k].frame)].name);
          }
        }
      }
      contacts.push_back(c);
    }
    weight = model.totalMass() * model.gravity().norm();
    expected = state.q;
    error_sum.assign(tasks.size(), 0.0);
    error_last.assign(tasks.size(), 0.0);
    status_counts.assign(checks::controllerStatusNames().size(), 0);
    solver_counts.assign(checks::solverStatusNames().size(), 0);
    augmented.assign(static_cast<size_t>(ctl->levelCount()), 0);
    timers.assign(5, {});
    const long n = std::lround(s.duration_s / s.control_period_s) + 2;
    for (auto& v : timers) v.reserve(static_cast<size_t>(n));
  }
};

LexdynDriver::LexdynDriver(const CaseSpec& spec, const sim::Simulator& simu) : impl_(std::make_unique<Impl>(spec, simu)) {}
LexdynDriver::~LexdynDriver() = default;

void LexdynDriver::addChannels(checks::TraceSchema& schema) const {
  const Impl& I = *impl_;
  schema.add(checks::kControllerStatusChannel);
  schema.add(checks::kSolverStatusChannel);
  schema.add(checks::kSolverIterationsChannel);
  schema.add("solver.optimality_iterations");
  schema.add(checks::kSolverFactorizationsChannel);
  // The controller's own view of the robot (the state it read: measured or its integrated plan).
  for (const char* a : {"x", "y", "z"}) schema.add(std::string("ctrl.com.") + a);
  for (const char* a : {"x", "y", "z", "pitch"}) schema.add(std::string("ctrl.base.") + a);
  if (I.spec.trace.timings) {
    for (const char* t : kTimers) schema.add(checks::timerChannel(t));
  }
  for (const auto& t : I.tasks) {
    for (const char* w : {"error", "active", "engaged"}) schema.add(checks::taskChannel(t.name, w));
  }
  for (const auto& l : I.lx.hierarchy(I.lx.method)) {
    for (const char* w : {"augmented", "hessian_updated", "violation", "second_order_ratio", "curvature_ratio"})
      schema.add(checks::levelChannel(l.name, w));
  }
  for (const char* prefix : {"cmd.q.", "cmd.qd.", "cmd.tau."}) {
    for (const auto& j : I.model.jointNames()) schema.add(prefix + j);
  }
  for (const auto& c : I.contacts) {
    schema.add(checks::contactActiveChannel(c.name));
    for (const char* w : kWrench) schema.add(checks::wrenchChannel(c.name, false, w));
    if (c.sensor >= 0) {
      for (const char* w : kWrench) schema.add(checks::wrenchChannel(c.name, true, w));
    }
  }
  for (const auto& t : I.tasks) {
    for (const auto& n : t.target_names) schema.add("target." + t.name + "." + n);
  }
}

void LexdynDriver::addMetadata(checks::TraceMetadata& md) const {
  const Impl& I = *impl_;
  const control::ControllerParams& p = I.lx.params;
  md.emplace_back(checks::kMethodMetadata, I.lx.method);
  md.emplace_back("controller_params",
                  "nu_dt2 " + num(p.nu_dt2) + ", xi_dt2 " + num(p.xi_dt2) + ", zeta_dt2 " + num(p.zeta_dt2) + ", new_dof_diagonal_dt2 " +
                      num(p.new_dof_diagonal_dt2) + ", rho_dt2 " + num(p.rho_dt2) + ", eps_dt2 " + num(p.eps_dt2) + ", newton_target " +
                      (p.newton_target == control::NewtonTarget::Zero ? "zero" : "previous_velocity") + ", damping " + num(p.damping) +
                      ", use_qmod " + (p.use_qmod ? "true" : "false") + ", sr1 " + (p.sr1 ? "true" : "false") +
                      ", newton_identity_weight " + num(p.newton_identity_weight) + ", bfgs_secant " +
                      (p.bfgs_secant == control::BfgsSecant::CurrentMultipliers ? "current_multipliers"
                       : p.bfgs_secant == control::BfgsSecant::FullDifference   ? "full_difference"
                                                                                : "gauss_newton") +
                      ", ah_add_jtj " + (p.ah_add_jtj ? "true" : "false") + ", multiplier_scale " +
                      (p.multiplier_scale == control::MultiplierScale::Dt ? "dt" : "one") + ", stop_after_level " +
                      (p.stop_after_level.empty() ? std::string("(none)") : p.stop_after_level) + ", rank_switching " +
                      (p.rank_switching ? "true" : "false") + ", sign_change_guard " + (p.sign_change_guard ? "true" : "false") +
                      ", wls_infeasibility_tolerance " + num(p.wls_infeasibility_tolerance) + "; feed-forward torque " +
                      (I.lx.feedforward_torque ? "on" : "off") + "; state feedback " + I.lx.state_feedback);
  const solver::Options& o = p.solver;
  md.emplace_back(
      "solver_options",
      "max_iterations " + std::to_string(o.max_iterations) + ", rank_tolerance " + num(o.rank_tolerance) + ", feasibility_tolerance " +
          num(o.feasibility_tolerance) + ", zero_tolerance " + num(o.zero_tolerance) + ", dual_tolerance " + num(o.dual_tolerance) +
          ", stop_slack_norm " + num(o.stop_slack_norm) + ", stop_optimality_iterations " + std::to_string(o.stop_optimality_iterations) +
          ", stop_total_iterations " + std::to_string(o.stop_total_iterations) + ", split_force_coordinates " +
          (o.split_from_variable != -1 ? "true" : "false") + ", spanning_stages " + (o.spanning_stages ? "true" : "false") +
          ", lazy_snapshots " + (o.lazy_snapshots ? "true" : "false") + ", project_unit_suffix " +
          (o.project_unit_suffix ? "true" : "false") + ", restart_after_bound_change " + (o.restart_after_bound_change ? "true" : "false") +
          ", spanning_any_rows " + (o.spanning_any_rows ? "true" : "false") + ", spanning_structured " +
          (o.spanning_structured ? "true" : "false") + ", swap_reflectors " + (o.swap_reflectors ? "true" : "false"));
  std::string h;
  for (const auto& l : I.lx.hierarchy(I.lx.method)) {
    h += (h.empty() ? "" : " | ") + l.name + ":";
    for (size_t k = 0; k < l.tasks.size(); ++k) {
      h += " " + l.tasks[k] + (l.weights.empty() ? "" : "(" + num(l.weights[k]) + ")");
    }
  }
  md.emplace_back("hierarchy", h);
  std::string cs;
  for (const auto& c : I.lx.contacts) {
    cs += (cs.empty() ? "" : "; ") + c.name + " (frame " + c.frame + ", " + std::to_string(c.points.size()) + " points, " +
          (c.fixed ? "fixed"
                   : "friction " + num(c.friction) + ", margins " + num(c.margins.friction) + " / " + num(c.margins.cop_m) + " m / " +
                         num(c.margins.min_normal_N) + " N per point" + (c.margins_default ? " (default)" : "")) +
          (c.grasp.empty() ? "" : ", grasp " + c.grasp) + (c.sensor.empty() ? "" : ", sensor " + c.sensor) + ")";
  }
  md.emplace_back("contacts", cs.empty() ? "none" : cs);
  std::string codes;
  const auto& sn = checks::controllerStatusNames();
  for (size_t k = 0; k < sn.size(); ++k) codes += (k ? ", " : "") + std::to_string(k) + " " + sn[k];
  md.emplace_back("ctrl_status_codes", codes);
  codes.clear();
  const auto& vn = checks::solverStatusNames();
  for (size_t k = 0; k < vn.size(); ++k) codes += (k ? ", " : "") + std::to_string(k) + " " + vn[k];
  md.emplace_back("solver_status_codes", codes);
  md.emplace_back("wrench_axes",
                  "wrench.<contact>.* from the controller's generators (the plan for the coming period) and "
                  "wrench_sensed.<contact>.* from the linked F/T sensor (at the row's time): force on the robot "
                  "and torque about the contact frame's origin, in the contact frame's axes");
}

void LexdynDriver::reset(const sim::Simulator& simu) {
  Impl& I = *impl_;
  I.state.q = simu.configuration();
  I.state.u = simu.velocity();
  I.state.time = simu.time();
  I.ctl->reset(I.state);
  for (const std::string& c : I.lx.initial_contacts) I.ctl->setContactActive(I.ctl->contactIndex(c), true);
}

void LexdynDriver::applyEvent(const EventSpec& e, double t, sim::Simulator& simu) {
  Impl& I = *impl_;
  if (e.action == EventAction::AddContact || e.action == EventAction::RemoveContact) {
    const bool on = e.action == EventAction::AddContact;
    for (const auto& c : I.contacts) {
      if (c.name != e.contact) continue;
      I.ctl->setContactActive(c.index, on);
      if (c.grasp >= 0) simu.setGraspActive(c.grasp, on);
    }
    return;
  }
  const int task = I.ctl->taskIndex(e.task);
  // A new target for a task stops the trajectory or swing that drove it.
  I.generators.erase(std::remove_if(I.generators.begin(), I.generators.end(), [&](const Impl::Generator& g) { return g.task == task; }),
                     I.generators.end());
  if (e.action == EventAction::SetTarget && e.ramp_s > 0.0) {
    Impl::Generator g;
    g.kind = Impl::Generator::Kind::Ramp;
    g.task = task;
    g.start = t;
    g.ramp_s = e.ramp_s;
    const tasks::TaskData& d = I.ctl->taskData(task);
    g.from = d.target_set && d.target.size() == e.value.size() ? d.target : e.value;
    g.to = e.value;
    I.generators.push_back(std::move(g));
  } else if (e.action == EventAction::SetTarget) {
    I.ctl->setTaskTarget(task, e.value);
  } else if (e.action == EventAction::TargetTrajectory || e.action == EventAction::Swing) {
    Impl::Generator g;
    g.kind = e.action == EventAction::Swing ? Impl::Generator::Kind::Swing : Impl::Generator::Kind::Trajectory;
    g.task = task;
    g.start = t;
    g.trajectory = e.trajectory;
    g.sw = e.swing;
    I.generators.push_back(std::move(g));
  }
}

bool LexdynDriver::tick(double t, const sim::Simulator& simu, sim::JointCommand& cmd, std::string& failure) {
  Impl& I = *impl_;
  for (auto& g : I.generators) {
    const double tau = t - g.start;
    if (g.kind == Impl::Generator::Kind::Ramp) {
      const double a = std::min(1.0, tau / g.ramp_s);
      if (a >= 1.0) {
        I.ctl->setTaskTarget(g.task, g.to);
      } else {
        I.rampValue.resize(g.to.size());
        for (int k = 0; k < g.to.size(); ++k) {
          const bool finite = std::isfinite(g.from[k]) && std::isfinite(g.to[k]);
          I.rampValue[k] = finite ? g.from[k] + a * (g.to[k] - g.from[k]) : g.to[k];
        }
        I.ctl->setTaskTarget(g.task, I.rampValue);
      }
      continue;
    }
    I.target3 = g.kind == Impl::Generator::Kind::Swing ? g.sw.at(tau) : g.trajectory.at(tau);
    I.ctl->setTaskTarget(g.task, I.target3);
  }
  I.have_expected = I.ticks > 0;
  if (I.have_expected) I.expected = I.ctl->command().q;
  if (I.lx.state_feedback == "measured" || I.ticks == 0) {
    I.state.q = simu.configuration();
    I.state.u = simu.velocity();
  } else if (I.lx.state_feedback == "measured_position") {
    I.state.q = simu.configuration();
    I.state.u = I.ctl->command().u;
  } else {
    I.state.q = I.ctl->command().q;
    I.state.u = I.ctl->command().u;
  }
  I.state.time = t;
  const control::Command& c = I.ctl->tick(I.state);
  const control::TickRecord& r = I.ctl->record();
  // Statistics over every tick.
  ++I.ticks;
  for (size_t k = 0; k < I.tasks.size(); ++k) {
    const double e = r.task_error_norm(I.tasks[k].index);
    I.error_sum[k] += e;
    I.error_last[k] = e;
  }
  if (r.iterations > I.peak_iterations) {
    I.peak_iterations = r.iterations;
    I.peak_at = t;
  }
  if (r.factorizations > I.peak_factorizations) {
    I.peak_factorizations = r.factorizations;
    I.peak_factorizations_at = t;
  }
  const int st = indexOf(checks::controllerStatusNames(), control::toString(r.status));
  if (st >= 0) ++I.status_counts[static_cast<size_t>(st)];
  const int ss = indexOf(checks::solverStatusNames(), solver::toString(r.solver_status));
  if (ss >= 0) ++I.solver_counts[static_cast<size_t>(ss)];
  for (size_t l = 0; l < I.augmented.size(); ++l) I.augmented[l] += r.level_augmented[l] ? 1 : 0;
  const double tm[5] = {r.model_us, r.tasks_us, r.hessian_us, r.solver_us, r.tick_us};
  for (int k = 0; k < 5; ++k) I.timers[static_cast<size_t>(k)].push_back(tm[k]);

  if (!c.ok()) {
    failure = std::string("controller_failure: ") + control::toString(c.status) + " at t = " + num(t) + " s (solver " +
              solver::toString(r.solver_status) + ", " + std::to_string(r.iterations) + " active-set iterations)";
    return false;
  }
  cmd.q = c.q.joints;
  cmd.qdot = c.u.tail(I.nj);
  if (I.lx.feedforward_torque)
    cmd.tau_ff = c.tau;
  else
    cmd.tau_ff.setZero();
  return true;
}

std::string LexdynDriver::divergence(double t, const sim::Simulator& simu) {
  Impl& I = *impl_;
  const DivergenceGuard& g = I.lx.guard;
  if (!g.enabled) return {};
  const std::string at = "diverged at t = " + num(t) + " s: ";
  const model::Configuration& q = simu.configuration();
  if (I.have_expected) {
    // The plan's configuration for this tick (the last command) against the simulator's.
    Eigen::Index worst = -1;
    double dq = 0.0;
    for (Eigen::Index j = 0; j < q.joints.size(); ++j) {
      const double e = std::abs(I.expected.joints[j] - q.joints[j]);
      if (!(e <= dq)) {
        dq = e;
        worst = j;
      }
    }
    if (worst >= 0 && !(dq <= g.angle_rad)) {
      return at + "joint " + I.model.jointNames()[static_cast<size_t>(worst)] + " is " + num(dq) + " from the plan's position (limit " +
             num(g.angle_rad) + ", divergence_guard.angle_rad)";
    }
    if (I.model.hasFreeFlyer()) {
      const double dp = (I.expected.base_position - q.base_position).norm();
      if (!(dp <= g.position_m)) {
        return at + "the base is " + num(dp) + " m from the plan's position (limit " + num(g.position_m) +
               " m, divergence_guard.position_m)";
      }
      const double da = Eigen::AngleAxisd(I.expected.base_rotation.transpose() * q.base_rotation).angle();
      if (!(da <= g.angle_rad)) {
        return at + "the base is turned " + num(da) + " rad from the plan's attitude (limit " + num(g.angle_rad) +
               " rad, divergence_guard.angle_rad)";
      }
    }
  }
  // Contacts the plan holds that the simulated robot has left.
  const double fmin = g.contact_lost_fraction * I.weight;
  for (auto& c : I.contacts) {
    if (c.surface < 0 || c.fixed || !I.ctl->contactActive(c.index)) {
      c.lost_since = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    const double fz = simu.surfaceNormalForce(c.surface);
    if (fz >= fmin) {
      c.lost_since = std::numeric_limits<double>::quiet_NaN();
    } else if (std::isnan(c.lost_since)) {
      c.lost_since = t;
    } else if (t - c.lost_since >= g.contact_lost_s - 1e-9) {
      return at + "the plan holds contact " + c.name + " but the simulated robot has left it since t = " + num(c.lost_since) +
             " s (normal force " + num(fz) + " N, below " + num(fmin) + " N = " + num(g.contact_lost_fraction) +
             " of the weight, for divergence_guard.contact_lost_s = " + num(g.contact_lost_s) + " s)";
    }
  }
  // Torques beyond any actuator and task errors beyond any workspace.
  const control::Command& cmd = I.ctl->command();
  const Eigen::VectorXd& lim = I.model.jointTorqueLimits();
  for (Eigen::Index j = 0; j < cmd.tau.size() && j < lim.size(); ++j) {
    if (lim[j] > 0.0 && std::isfinite(lim[j]) && !(std::abs(cmd.tau[j]) <= g.torque_factor * lim[j])) {
      return at + "the plan commands " + num(cmd.tau[j]) + " N m at joint " + I.model.jointNames()[static_cast<size_t>(j)] + ", " +
             num(std::abs(cmd.tau[j]) / lim[j]) + " times its effort limit " + num(lim[j]) + " (limit " + num(g.torque_factor) +
             " times, divergence_guard.torque_factor)";
    }
  }
  const control::TickRecord& r = I.ctl->record();
  for (const auto& tr : I.tasks) {
    // Tasks with a target (equality rows); an inequality's distance-like error is infinite
    // where the task does not bound (a CoM box open in z).
    const tasks::TaskModel& task = I.ctl->task(tr.index);
    if (!task.hasFunction() || task.kind() != tasks::TaskKind::Equality) continue;
    const double e = r.task_error_norm(tr.index);
    if (!(e <= g.task_error)) {
      return at + "task " + tr.name + " has an error of " + num(e) + " (limit " + num(g.task_error) + ", divergence_guard.task_error)";
    }
  }
  return {};
}

int LexdynDriver::fill(const sim::Simulator& simu, double* out) const {
  const Impl& I = *impl_;
  const control::TickRecord& r = I.ctl->record();
  const control::Command& c = I.ctl->command();
  int i = 0;
  out[i++] = indexOf(checks::controllerStatusNames(), control::toString(r.status));
  out[i++] = indexOf(checks::solverStatusNames(), solver::toString(r.solver_status));
  out[i++] = r.iterations;
  out[i++] = r.optimality_iterations;
  out[i++] = r.factorizations;
  for (int k = 0; k < 3; ++k) out[i++] = r.com[k];
  for (int k = 0; k < 3; ++k) out[i++] = I.state.q.base_position[k];
  out[i++] = std::asin(std::clamp(-I.state.q.base_rotation(2, 0), -1.0, 1.0));
  if (I.spec.trace.timings) {
    for (double v : {r.model_us, r.tasks_us, r.hessian_us, r.solver_us, r.tick_us}) out[i++] = v;
  }
  for (const auto& t : I.tasks) {
    out[i++] = r.task_error_norm(t.index);
    out[i++] = r.task_active_rows[static_cast<size_t>(t.index)];
    out[i++] = r.task_engaged_rows[static_cast<size_t>(t.index)];
  }
  for (int l = 0; l < I.ctl->levelCount(); ++l) {
    out[i++] = r.level_augmented[static_cast<size_t>(l)] ? 1.0 : 0.0;
    out[i++] = r.level_hessian_updated[static_cast<size_t>(l)] ? 1.0 : 0.0;
    out[i++] = r.level_violation(l);
    out[i++] = r.level_second_order_ratio(l);
    out[i++] = r.level_curvature_ratio(l);
  }
  for (int j = 0; j < I.nj; ++j) out[i++] = c.q.joints[j];
  for (int j = 0; j < I.nj; ++j) out[i++] = c.u[c.u.size() - I.nj + j];
  for (int j = 0; j < I.nj; ++j) out[i++] = c.tau[j];
  const sim::Multibody& sm = simu.model();
  for (const auto& cr : I.contacts) {
    out[i++] = I.ctl->contactActive(cr.index) ? 1.0 : 0.0;
    // The planned wrench in the contact frame the controller saw (with `integrated` feedback its
    // own state, not the simulator's).
    // A point contact's: in the world's axes, whose z is the ground's normal (its frame turns
    // with the foot).
    const Eigen::Matrix3d Rc = cr.point ? Eigen::Matrix3d::Identity()
                                        : Eigen::Matrix3d(I.model.framePlacement(I.ctl->modelData(), cr.ctrl_frame).linear().transpose());
    const Eigen::Vector3d f = Rc * r.contact_wrench.col(cr.index).head<3>();
    const Eigen::Vector3d m = Rc * r.contact_wrench.col(cr.index).tail<3>();
    const Eigen::Isometry3d X = sm.framePlacement(simu.data(), cr.frame);
    const Eigen::Matrix3d Rt = cr.point ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(X.linear().transpose());
    for (int k = 0; k < 3; ++k) out[i++] = f[k];
    for (int k = 0; k < 3; ++k) out[i++] = m[k];
    if (cr.sensor >= 0) {
      // Sensor frame, about its origin -> world -> about the contact frame's origin, its axes.
      const sim::Wrench& w = simu.sensors().wrenches[static_cast<size_t>(cr.sensor)];
      const Eigen::Isometry3d S = sm.framePlacement(simu.data(), cr.sensor_frame);
      const Eigen::Vector3d fw = S.linear() * w.force;
      const Eigen::Vector3d mw = S.linear() * w.torque + (S.translation() - X.translation()).cross(fw);
      const Eigen::Vector3d fl = Rt * fw, ml = Rt * mw;
      for (int k = 0; k < 3; ++k) out[i++] = fl[k];
      for (int k = 0; k < 3; ++k) out[i++] = ml[k];
    }
  }
  for (const auto& t : I.tasks) {
    const tasks::TaskData& d = I.ctl->taskData(t.index);
    for (int k = 0; k < t.target_values; ++k) out[i++] = k < d.target.size() ? d.target[k] : 0.0;
  }
  return i;
}

void LexdynDriver::writeProblem(const std::string& path) const {
  solver::writeProblemJson(impl_->ctl->problem(), path, &impl_->ctl->solverOptions());
}

ControllerStats LexdynDriver::stats() const {
  const Impl& I = *impl_;
  ControllerStats s;
  s.method = I.lx.method;
  s.ticks = I.ticks;
  for (size_t k = 0; k < I.tasks.size(); ++k) {
    s.tasks.push_back({I.tasks[k].name, I.error_last[k], I.ticks > 0 ? I.error_sum[k] / static_cast<double>(I.ticks) : 0.0});
  }
  s.peak_iterations = std::max(0, I.peak_iterations);
  s.peak_iterations_at_s = I.peak_at;
  s.peak_factorizations = std::max(0, I.peak_factorizations);
  s.peak_factorizations_at_s = I.peak_factorizations_at;
  const auto& sn = checks::controllerStatusNames();
  for (size_t k = 0; k < sn.size(); ++k) s.status_counts.emplace_back(sn[k], I.status_counts[k]);
  const auto& vn = checks::solverStatusNames();
  for (size_t k = 0; k < vn.size(); ++k) s.solver_status_counts.emplace_back(vn[k], I.solver_counts[k]);
  const auto& levels = I.lx.hierarchy(I.lx.method);
  for (size_t l = 0; l < levels.size() && l < I.augmented.size(); ++l) s.augmented_ticks.emplace_back(levels[l].name, I.augmented[l]);
  for (int k = 0; k < 5; ++k) {
    const std::vector<double>& v = I.timers[static_cast<size_t>(k)];
    ControllerStats::Timing t;
    t.name = kTimers[k];
    t.median_us = percentile(v, 50.0);
    t.p99_us = percentile(v, 99.0);
    t.max_us = v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
    s.timing.push_back(t);
  }
  return s;
}

}  // namespace lexdyn::cases
