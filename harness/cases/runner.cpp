#include "harness/cases/runner.hpp"
#include "harness/checks/check_registry.hpp"
#include "harness/checks/output_files.hpp"

#include "harness/sim/build_info.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

namespace lexdyn::cases {

namespace fs = std::filesystem;

namespace {

std::string num(double v) { return formatNumber(v, 10); }

// The posture servo: a fixed posture plus optional periodic joint motions.
class PostureServo {
 public:
  PostureServo(const ControllerSpec& spec, const Eigen::VectorXd& posture) : spec_(spec), posture_(posture) {}
  void command(double t, sim::JointCommand& cmd) const {
    cmd.q = posture_;
    cmd.qdot.setZero();
    cmd.tau_ff.setZero();
    for (const MotionSpec& m : spec_.motions) {
      if (t < m.start_s) continue;
      const double w = 2.0 * M_PI / m.period_s;
      const double a = w * (t - m.start_s) + m.phase_rad;
      double x = 0.0, xd = 0.0;
      if (m.waveform == Waveform::Sine) {
        x = m.amplitude * std::sin(a);
        xd = m.amplitude * w * std::cos(a);
      } else {
        x = m.amplitude * 0.5 * (1.0 - std::cos(a));
        xd = m.amplitude * 0.5 * w * std::sin(a);
      }
      for (int j : m.joints) {
        cmd.q[j] += x;
        cmd.qdot[j] += xd;
      }
    }
  }

 private:
  ControllerSpec spec_;
  Eigen::VectorXd posture_;
};

// Channels recorded every tick and how to fill them.
class Recorder {
 public:
  Recorder(const CaseSpec& spec, const sim::Simulator& simu, const LexdynDriver* driver) : simu_(simu), driver_(driver) {
    const sim::Multibody& m = simu.model();
    const model::RobotDescription& d = m.description();
    schema_.add(checks::kTimeChannel);
    for (const char* n : {"base.x", "base.y", "base.z", "base.rx", "base.ry", "base.rz", "com.x", "com.y", "com.z"}) schema_.add(n);
    for (const char* prefix : {"q.", "qd.", "q_cmd.", "tau."}) {
      for (const auto& j : m.jointNames()) schema_.add(prefix + j);
    }
    for (const auto& s : d.force_sensors) {
      for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"}) schema_.add("ft." + s.name + "." + c);
    }
    for (const auto& s : d.contact_surfaces) {
      schema_.add(checks::contactForceChannel(s.name));
      for (size_t i = 0; i < s.points.size(); ++i) {
        schema_.add(checks::contactPointChannel(s.name, static_cast<int>(i), 'x'));
        schema_.add(checks::contactPointChannel(s.name, static_cast<int>(i), 'y'));
      }
    }
    for (const auto& g : spec.sim.grasps) {
      for (const char* c : {"active", "fx", "fy", "fz"}) schema_.add("grasp." + g.name + "." + c);
    }
    std::vector<std::string> frames = spec.trace.frames;
    for (const auto& c : spec.checks) {
      for (const auto& f : checks::framesRead(c)) frames.push_back(f);
    }
    for (const auto& f : frames) {
      if (schema_.find(checks::frameChannel(f, 'x')) >= 0) continue;
      frame_ids_.push_back(m.frameId(f));
      for (char a : {'x', 'y', 'z'}) schema_.add(checks::frameChannel(f, a));
    }
    for (const char* n : {"sim.steps", "sim.rhs_evals", "sim.jac_evals"}) schema_.add(n);
    sim_channels_ = static_cast<size_t>(schema_.size());
    if (driver_) driver_->addChannels(schema_);
    row_.assign(static_cast<size_t>(schema_.size()), 0.0);
  }

  const checks::TraceSchema& channels() const { return schema_; }
  const std::vector<double>& row() const { return row_; }

  /// The controller's channels of the tick just computed.
  void fillController() {
    if (!driver_) return;
    const int n = driver_->fill(simu_, row_.data() + sim_channels_);
    LEXDYN_ALWAYS_ASSERT(sim_channels_ + static_cast<size_t>(n) == row_.size(), "trace row layout mismatch (controller)");
  }

  /// The simulator's channels at its current time.
  void fillSim() {
    const sim::Multibody& m = simu_.model();
    const model::RobotDescription& d = m.description();
    const model::Configuration& q = simu_.configuration();
    const sim::SensorReadings& s = simu_.sensors();
    size_t i = 0;
    row_[i++] = simu_.time();
    const Eigen::Vector3d e = model::eulerXYZFromRotation(q.base_rotation);
    for (int k = 0; k < 3; ++k) row_[i++] = q.base_position[k];
    for (int k = 0; k < 3; ++k) row_[i++] = e[k];
    const Eigen::Vector3d com = m.centerOfMass(simu_.data());
    for (int k = 0; k < 3; ++k) row_[i++] = com[k];
    const int nj = m.numJoints();
    for (int j = 0; j < nj; ++j) row_[i++] = s.q[j];
    for (int j = 0; j < nj; ++j) row_[i++] = s.qdot[j];
    for (int j = 0; j < nj; ++j) row_[i++] = simu_.commandedPosition()[j];
    for (int j = 0; j < nj; ++j) row_[i++] = s.tau[j];
    for (const auto& w : s.wrenches) {
      for (int k = 0; k < 3; ++k) row_[i++] = w.force[k];
      for (int k = 0; k < 3; ++k) row_[i++] = w.torque[k];
    }
    const auto& cps = simu_.contactPoints();
    size_t p = 0;
    for (size_t s = 0; s < d.contact_surfaces.size(); ++s) {
      const auto& surf = d.contact_surfaces[s];
      row_[i++] = simu_.surfaceNormalForce(static_cast<int>(s));
      for (size_t k = 0; k < surf.points.size(); ++k) {
        row_[i++] = cps[p + k].position.x();
        row_[i++] = cps[p + k].position.y();
      }
      p += surf.points.size();
    }
    for (int g = 0; g < static_cast<int>(simu_.settings().grasps.size()); ++g) {
      row_[i++] = simu_.graspActive(g) ? 1.0 : 0.0;
      const sim::Wrench w = simu_.graspWrenchWorld(g);
      for (int k = 0; k < 3; ++k) row_[i++] = w.force[k];
    }
    for (model::FrameId f : frame_ids_) {
      const Eigen::Vector3d x = m.framePlacement(simu_.data(), f).translation();
      for (int k = 0; k < 3; ++k) row_[i++] = x[k];
    }
    const sim::CvodeStats st = simu_.integratorStats();
    row_[i++] = static_cast<double>(st.steps);
    row_[i++] = static_cast<double>(st.rhs_evals);
    row_[i++] = static_cast<double>(st.jac_evals);
    LEXDYN_ALWAYS_ASSERT(i == sim_channels_, "trace row layout mismatch");
  }

 private:
  const sim::Simulator& simu_;
  const LexdynDriver* driver_ = nullptr;
  size_t sim_channels_ = 0;
  checks::TraceSchema schema_;
  std::vector<model::FrameId> frame_ids_;
  std::vector<double> row_;
};

checks::TraceMetadata metadata(const CaseSpec& spec, const sim::Simulator& simu, const sim::RestingState& rest,
                               const LexdynDriver* driver) {
  const sim::Multibody& m = simu.model();
  const sim::SimulatorSettings& s = spec.sim;
  checks::TraceMetadata md;
  md.emplace_back("lexdyn_trace", "1");
  md.emplace_back("case", spec.name);
  md.emplace_back("case_file", spec.path);
  md.emplace_back("model", m.name() + " (urdf " + spec.urdf_path + ", data " + spec.data_path + ")");
  md.emplace_back("robot_mass_kg", num(m.totalMass()));
  md.emplace_back(checks::kWeightMetadata, num(m.totalMass() * m.gravity().norm()));
  md.emplace_back("control_period_s", num(spec.control_period_s));
  md.emplace_back("duration_s", num(spec.duration_s));
  if (spec.duration_s < spec.scenario_duration_s - 1e-9) md.emplace_back(checks::kScenarioDurationMetadata, num(spec.scenario_duration_s));
  if (!spec.overrides.empty()) {
    std::string o;
    for (const auto& x : spec.overrides) o += (o.empty() ? "" : "; ") + overrideText(x);
    md.emplace_back("overrides", o);
  }
  const InitialStateSpec& is = spec.initial_state;
  std::string init = "posture " + is.posture;
  for (const auto& [j, v] : is.joints)
    init += (&j == &is.joints.front().first ? " with " : ", ") + m.jointNames()[static_cast<size_t>(j)] + " " + num(v);
  init += ", base_xy [" + num(is.base_x) + ", " + num(is.base_y) + "], base_yaw_rad " + num(is.base_yaw_rad) + "; settle " +
          sim::toString(rest.settle);
  if (rest.settle != sim::Settle::None) init += " (" + std::to_string(rest.iterations) + " Newton iterations)";
  if (is.perturbation.amplitude_rad > 0.0) {
    init += "; perturbed by up to " + num(is.perturbation.amplitude_rad) + " rad on " + std::to_string(is.perturbation.joints.size()) +
            " joints (seed " + std::to_string(is.perturbation.seed) + ")";
  }
  init += "; at rest: net force " + num(rest.net_force_N) + " N, net moment " + num(rest.net_moment_Nm) + " N m, largest joint imbalance " +
          num(rest.joint_residual_Nm) + " N m";
  md.emplace_back("initial_state", init);
  const bool dq_jacobian = s.integrator.jacobian == sim::IntegratorJacobian::DifferenceQuotient;
  md.emplace_back("integrator", std::string("SUNDIALS CVODE BDF, Newton, ") +
                                    (dq_jacobian ? "dense difference-quotient Jacobian" : "Jacobian of the applied forces") + "; rtol " +
                                    num(s.integrator.rtol) + ", atol_position " + num(s.integrator.atol_position) + ", atol_velocity " +
                                    num(s.integrator.atol_velocity) + ", max_order " + std::to_string(s.integrator.max_order) +
                                    ", max_steps_per_tick " + std::to_string(s.integrator.max_steps_per_tick) + ", max_step_s " +
                                    num(s.integrator.max_step_s) +
                                    // Only when not the default, so that the default traces keep their header.
                                    (s.integrator.linear_solver != sim::LinearSolver::BlockElimination
                                         ? std::string(", linear_solver ") + sim::toString(s.integrator.linear_solver)
                                         : std::string()));
  md.emplace_back("contact", "Hunt-Crossley k " + num(s.contact.stiffness) + " N/m^" + num(s.contact.exponent) + ", c " +
                                 num(s.contact.dissipation_s_per_m) + " s/m; regularised Coulomb mu " +
                                 num(s.contact.friction_coefficient) + ", v_s " + num(s.contact.slip_velocity_m_per_s) + " m/s; ground z " +
                                 num(s.contact.ground_height_m) + " m");
  std::string gains;
  for (const auto& g : spec.gain_groups) gains += (gains.empty() ? "" : "; ") + g.match + " kp " + num(g.kp) + " kd " + num(g.kd);
  if (!spec.sim_model.mass_scale.empty() || !spec.sim_model.com_offset.empty()) {
    std::string p = "the simulated robot differs from the controller's model:";
    for (const auto& x : spec.sim_model.mass_scale) p += " mass x" + num(x.scale) + " on " + x.match + ";";
    for (const auto& x : spec.sim_model.com_offset) {
      p += " CoM + [" + num(x.offset_m.x()) + ", " + num(x.offset_m.y()) + ", " + num(x.offset_m.z()) + "] m on " + x.match + ";";
    }
    md.emplace_back("sim_model", p);
  }
  md.emplace_back("servo",
                  std::string("set-point profile ") + toString(s.servo.profile) + "; torque saturated at the URDF effort limit; " + gains);
  if (driver) {
    md.emplace_back("controller", "lexdyn (docs/controller.md)");
    driver->addMetadata(md);
  } else {
    md.emplace_back("controller", std::string(records::toString(spec.controller.type)) + " (posture " + spec.controller.posture + ", " +
                                      std::to_string(spec.controller.motions.size()) + " motions)");
  }
  for (const auto& kv : sim::buildInfo()) md.push_back(kv);
  md.emplace_back("trace_every_n_ticks", std::to_string(spec.trace.every_n_ticks));
  return md;
}

// Written to PATH.partial, synced and renamed: a killed run never leaves a half-written file.
void writeFileAtomically(const std::string& path, const std::string& text) { files::writeAtomically(path, text); }

void writeSummary(const std::string& path, const records::RunRecord& record) {
  writeFileAtomically(path, records::toJson(record).dump(2) + "\n");
}

}  // namespace

records::CheckRecord checkRecord(const checks::CheckResult& c) {
  records::CheckRecord o;
  o.name = c.name;
  o.type = c.type;
  o.passed = c.passed;
  o.value = c.value;
  o.limit = c.limit;
  o.margin = checks::margin(c);
  o.unit = c.unit;
  o.detail = c.detail;
  o.machine_dependent = c.machine_dependent;
  o.decides = c.decides;
  o.partial_window = c.partial_window;
  return o;
}

records::RunRecord runRecord(const CaseSpec& spec, const RunSummary& r, const checks::TraceMetadata& trace_header) {
  records::RunRecord o;
  static_cast<records::RunOutcome&>(o) = r;
  o.case_name = spec.name;
  o.case_file = spec.path;
  o.integrator = {r.integrator.steps,        r.integrator.rhs_evals,         r.integrator.jac_evals,      r.integrator.jac_rhs_evals,
                  r.integrator.nonlin_iters, r.integrator.nonlin_conv_fails, r.integrator.err_test_fails, r.integrator_restarts};
  for (const auto& c : r.checks) o.checks.push_back(checkRecord(c));
  for (const auto& c : r.statistics) o.statistics[c.name] = {c.value, c.detail};
  for (const auto& ov : spec.overrides) o.overrides.emplace_back(ov.path, ov.value);
  o.effective_case = fs::path(r.case_path).filename().string();
  for (const auto& sk : r.skipped_checks) o.skipped_checks.emplace_back(sk.name, sk.reason);
  if (spec.duration_s < spec.scenario_duration_s - 1e-9) o.scenario_duration_s = spec.scenario_duration_s;
  o.robot_warnings = spec.robot_warnings;
  if (r.expected_failure) {
    const ExpectedFailure& x = *r.expected_failure;
    o.expected_failure = records::ExpectedFailureRecord{
        x.status, x.checks, x.reason, r.expectation_mismatches.empty(), r.expectation_mismatches, r.expected_failure_reached};
  }
  o.exit_code = exitCode(r);
  if (r.has_controller_stats) {
    const ControllerStats& cs = r.controller;
    records::ControllerRecord c;
    for (const auto& t : cs.tasks) c.tasks[t.name] = {t.final_error, t.mean_error};
    c.ticks = cs.ticks;
    for (const auto& [n, k] : cs.status_counts) c.status_counts[n] = k;
    for (const auto& [n, k] : cs.augmented_ticks) c.augmented_ticks[n] = k;
    c.peak_iterations = cs.peak_iterations;
    c.peak_iterations_at_s = cs.peak_iterations_at_s;
    c.peak_factorizations = cs.peak_factorizations;
    c.peak_factorizations_at_s = cs.peak_factorizations_at_s;
    for (const auto& [n, k] : cs.solver_status_counts) c.solver_status_counts[n] = k;
    for (const auto& t : cs.timing) c.timing_us[t.name] = {t.median_us, t.p99_us, t.max_us};
    o.controller = std::move(c);
  }
  o.trace = fs::path(r.trace_path).filename().string();
  o.trace_header.assign(trace_header.begin(), trace_header.end());
  return o;
}

// A contact the plan holds from the start that carries less at rest (the settled state) than its
// minimum normal force: the plan has to move the weight onto it at once, which a posture with
// the centre of mass over the other contacts cannot do without tipping the robot (docs/controller.md,
// "Contact margins").
namespace {
std::vector<std::string> startWarnings(const CaseSpec& spec, const sim::Simulator& simu) {
  std::vector<std::string> out;
  if (!isLexdyn(spec)) return out;
  const auto& lx = spec.controller.lexdyn;
  const auto& surfaces = simu.model().description().contact_surfaces;
  for (const auto& c : lx.contacts) {
    if (c.fixed || c.surface.empty() || !(c.margins.min_normal_N > 0.0)) continue;
    if (std::find(lx.initial_contacts.begin(), lx.initial_contacts.end(), c.name) == lx.initial_contacts.end()) continue;
    for (size_t k = 0; k < surfaces.size(); ++k) {
      if (surfaces[k].name != c.surface) continue;
      const double need = c.margins.min_normal_N * static_cast<double>(c.points.size());
      const double at_rest = simu.surfaceNormalForce(static_cast<int>(k));
      if (at_rest < need) {
        out.push_back("contact " + c.name + " carries " + formatNumber(at_rest, 3) +
                      " N at rest, less than the plan's minimum normal force " + formatNumber(need, 3) + " N (" +
                      formatNumber(c.margins.min_normal_N, 3) + " N per point" + (c.margins_default ? ", the default margins" : "") +
                      "): the plan moves the weight onto it at the start; a posture with the centre of mass nearer the middle of "
                      "the support, or a lower min_normal_N (contact_margins), avoids that");
      }
    }
  }
  return out;
}
}  // namespace

RunSummary runCase(const CaseSpec& spec, const RunOptions& options) {
  std::error_code ec;
  // One job per output folder: a second one exits at once naming this one (docs/architecture.md,
  // "Faults").
  const files::FolderLock lock(options.out_dir,
                               "lexdyn-harness run " + spec.name + (methodName(spec).empty() ? "" : " " + methodName(spec)));

  if (!spec.robot_warnings.empty()) {
    std::fprintf(stderr, "[%s] the robot files were read with %zu warning(s) (kept in summary.json, robot_warnings):\n", spec.name.c_str(),
                 spec.robot_warnings.size());
    for (const std::string& w : spec.robot_warnings) std::fprintf(stderr, "  warning: %s\n", w.c_str());
  }
  sim::Simulator simu(simulatedRobot(spec), spec.sim);
  const sim::Multibody& m = simu.model();
  // The initial state: at rest, the servos holding the initial posture (docs/simulator.md,
  // "Initial state"). No equilibrium is bad input: nothing is simulated.
  const InitialStateSpec& is = spec.initial_state;
  const Eigen::VectorXd q_init = initialJointPositions(spec, m.description());
  const sim::RestingState rest = simu.restingState(q_init, is.settle, is.base_yaw_rad, Eigen::Vector2d(is.base_x, is.base_y));
  if (!rest.converged) {
    throw InputError(is.settle_where, rest.message + " (posture '" + is.posture + "'; settle: none starts without it)");
  }
  const int nj = m.numJoints();
  const bool lexdyn = isLexdyn(spec);
  sim::JointCommand hold{q_init, Eigen::VectorXd::Zero(nj), Eigen::VectorXd::Zero(nj)};
  if (lexdyn && spec.controller.lexdyn.feedforward_torque) {
    // The controller commands the measured (deflected) joints plus feed-forward torques: the
    // servo's command at t = 0 is the same hand-over, (q at rest, 0, the servo torques at rest),
    // which applies exactly the torques of the equilibrium. Holding the posture instead would
    // make the first set-point profile jump by the servo deflection (a velocity set-point of
    // the deflection / period).
    hold.q = rest.q.joints;
    hold.tau_ff = spec.sim.servo.kp.cwiseProduct(q_init - rest.q.joints);
  }
  simu.reset(rest.q, Eigen::VectorXd::Zero(m.nv()), &hold);
  std::unique_ptr<PostureServo> servo;
  std::unique_ptr<LexdynDriver> driver;
  if (lexdyn) {
    driver = std::make_unique<LexdynDriver>(spec, simu);
    driver->reset(simu);
  } else {
    servo = std::make_unique<PostureServo>(spec.controller, m.posture(spec.controller.posture));
  }
  const bool dump = !options.dump_problems_dir.empty();
  if (dump) {
    if (!driver)
      throw InputError(options.dump_problems_dir,
                       "solver problems are dumped only for a lexdyn controller (this case has the posture servo)");
    if (!(options.dump_from_s <= options.dump_to_s)) {
      throw InputError(options.dump_problems_dir,
                       "the dump window starts after it ends (" + num(options.dump_from_s) + " > " + num(options.dump_to_s) + " s)");
    }
    files::createFolder(options.dump_problems_dir);
  }

  Recorder recorder(spec, simu, driver.get());
  const checks::TraceMetadata md = metadata(spec, simu, rest, driver.get());
  RunSummary r;
  r.method = methodName(spec);
  r.start_warnings = startWarnings(spec, simu);
  for (const std::string& w : r.start_warnings) std::fprintf(stderr, "[%s] warning: %s\n", spec.name.c_str(), w.c_str());
  std::vector<std::unique_ptr<checks::Check>> check_list;
  std::vector<std::string> partial;  // per check of check_list: what of its window a short run covers
  for (const auto& cs : spec.checks) {
    if (!checks::appliesTo(cs, r.method)) {
      r.skipped_checks.push_back({cs.name, "restricted to other methods (" + checks::joinNames(cs.methods) + ")"});
      continue;
    }
    const checks::WindowCut cut = checks::cutWindow(cs, spec.duration_s, spec.scenario_duration_s);
    if (cut.skip) {
      r.skipped_checks.push_back({cs.name, cut.note});
      continue;
    }
    check_list.push_back(checks::makeCheck(cs));
    check_list.back()->bind(recorder.channels(), md);
    partial.push_back(cut.note);
  }
  std::vector<std::unique_ptr<checks::Check>> statistic_list;
  for (const auto& cs : options.statistics) {
    statistic_list.push_back(checks::makeCheck(cs));
    statistic_list.back()->bind(recorder.channels(), md);
  }

  r.duration_s = spec.duration_s;
  r.trace_path = (fs::path(options.out_dir) / "trace.csv").string();
  r.summary_path = (fs::path(options.out_dir) / "summary.json").string();
  r.case_path = (fs::path(options.out_dir) / "case.yaml").string();
  // The outputs of an earlier run in the same directory go first, so that a run that is killed
  // never leaves an old summary or trace beside its own partial trace.
  for (const std::string& old : {r.trace_path, r.summary_path, r.case_path}) {
    fs::remove(old, ec);
    if (ec) throw InputError(old, "cannot remove the output of an earlier run: " + ec.message());
  }
  writeFileAtomically(r.case_path, effectiveCaseText(spec, options.out_dir));
  checks::TraceWriter writer(r.trace_path, recorder.channels(), md, spec.trace.flush_every_rows);

  const double T = spec.control_period_s;
  const long n_ticks = std::lround(spec.duration_s / T);
  sim::JointCommand cmd{Eigen::VectorXd::Zero(nj), Eigen::VectorXd::Zero(nj), Eigen::VectorXd::Zero(nj)};
  size_t next_event = 0;
  r.status = records::RunStatus::Completed;

  double last_recorded_t = -1.0;
  // A row holds the simulator's state at its time (before the events of that time, which act
  // from that time on) and the controller's tick at that time (after the events).
  auto applyEvents = [&](double t) {
    while (next_event < spec.events.size() && spec.events[next_event].at_s <= t + 1e-9) {
      const EventSpec& e = spec.events[next_event++];
      if (e.action == EventAction::GraspOn || e.action == EventAction::GraspOff) {
        simu.setGraspActive(simu.graspIndex(e.grasp), e.action == EventAction::GraspOn);
      } else if (driver) {
        driver->applyEvent(e, t, simu);
      }
    }
  };
  auto write = [&](long k, bool force_write) {
    const std::vector<double>& row = recorder.row();
    last_recorded_t = row[0];
    for (auto& c : check_list) c->consume(row.data());
    for (auto& c : statistic_list) c->consume(row.data());
    if (force_write || k % spec.trace.every_n_ticks == 0) writer.write(row.data());
  };

  const auto wall0 = std::chrono::steady_clock::now();
  auto wallNow = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count(); };
  double last_progress_wall = 0.0;
  long k = 0;
  std::string failure;
  // An exception once the run has started (an internal error, out of memory, an input error that
  // only the run could reveal) stops it like a failure: the trace keeps its rows and says why.
  auto stopOnException = [&](records::RunStatus status, const std::string& what) {
    r.status = status;
    r.message = std::string(status == records::RunStatus::InputError ? "bad input found at " : "internal error at ") +
                "t = " + num(simu.time()) + " s: " + what;
  };
  std::optional<OutputError> output_error;
  try {
    for (; k < n_ticks; ++k) {
      const double t = static_cast<double>(k) * T;
      recorder.fillSim();
      applyEvents(t);
      bool ok = true;
      if (driver) {
        ok = driver->tick(t, simu, cmd, failure);
        if (dump && t >= options.dump_from_s && t <= options.dump_to_s) {
          char name[32];
          std::snprintf(name, sizeof(name), "tick_%06ld.json", k);
          driver->writeProblem((fs::path(options.dump_problems_dir) / name).string());
        }
        recorder.fillController();
      } else {
        servo->command(static_cast<double>(k + 1) * T, cmd);
      }
      std::string diverged;
      if (ok && driver) diverged = driver->divergence(t, simu);
      write(k, k == 0 || !ok || !diverged.empty());
      if (!ok) {
        r.status = records::RunStatus::ControllerFailure;
        r.message = failure;
        break;
      }
      if (!diverged.empty()) {
        r.status = records::RunStatus::Diverged;
        r.message = diverged;
        break;
      }
      if (options.interrupt && options.interrupt->load()) {
        r.status = records::RunStatus::Interrupted;
        r.signal = options.interrupt_signal ? options.interrupt_signal->load() : 0;
        r.message = std::string("interrupted") + (r.signal == SIGINT ? " by SIGINT" : (r.signal == SIGTERM ? " by SIGTERM" : "")) +
                    " at t = " + num(t) + " s";
        break;
      }
      const sim::StepResult sr = simu.step(cmd);
      if (!sr.ok) {
        r.status = records::RunStatus::IntegratorFailure;
        r.message = sr.message;
        break;
      }
      if (options.progress) {
        // A line every progress_interval_s of wall time (stderr only; nothing else depends on it).
        const double w = wallNow();
        if (w - last_progress_wall >= options.progress_interval_s) {
          last_progress_wall = w;
          const double rate = w > 0.0 ? simu.time() / w : 0.0;
          std::fprintf(stderr, "[%s%s%s] t = %.2f / %.2f s, wall %.1f s, %.1fx real time, about %.0f s left\n", spec.name.c_str(),
                       r.method.empty() ? "" : " ", r.method.c_str(), simu.time(), spec.duration_s, w, rate,
                       rate > 0.0 ? (spec.duration_s - simu.time()) / rate : 0.0);
        }
      }
    }
    // The last state (end of the run), unless already recorded. The controller ticks there too
    // (its command is not used) so that every row has the controller's channels.
    if (simu.time() != last_recorded_t) {
      recorder.fillSim();
      applyEvents(simu.time());
      if (driver) {
        std::string ignored;
        driver->tick(simu.time(), simu, cmd, ignored);
        recorder.fillController();
      }
      write(k, true);
    }
  } catch (const OutputError& e) {
    // The trace cannot be written (a full disk, a file-size limit): the run stops at once; what
    // can still be written is, and the error ends the run as a run failure (exit code 3).
    r.status = records::RunStatus::OutputError;
    r.message = std::string(e.what()) + " (the run stopped at t = " + num(simu.time()) + " s)";
    output_error.emplace(e.where(), r.message.substr(e.where().empty() ? 0 : e.where().size() + 2));
  } catch (const InputError& e) {
    stopOnException(records::RunStatus::InputError, e.what());
  } catch (const std::bad_alloc&) {
    stopOnException(records::RunStatus::InternalError, "out of memory");
  } catch (const std::exception& e) {
    stopOnException(records::RunStatus::InternalError, e.what());
  }
  r.wall_s = wallNow();
  r.simulated_s = simu.time();
  r.ticks = simu.tick();
  r.realtime_factor = r.wall_s > 0.0 ? r.simulated_s / r.wall_s : 0.0;
  r.integrator = simu.integratorStats();
  r.integrator_restarts = simu.integratorRestarts();
  if (output_error) {
    try {
      writer.finish(r.status, r.message);
    } catch (const OutputError&) {}
  } else {
    writer.finish(r.status, r.message);
  }
  if (driver) {
    r.has_controller_stats = true;
    r.controller = driver->stats();
  }

  r.all_checks_passed = true;
  for (size_t k = 0; k < check_list.size(); ++k) {
    checks::CheckResult c = check_list[k]->result();
    // A run stopped early before any row of the check's window came (a contact that is made
    // later, say): not evaluated, as a window that starts after the end.
    if (!partial[k].empty() && !c.saw_rows) {
      r.skipped_checks.push_back({c.name, "no row of its window in what was run (" + c.detail + "): " + partial[k]});
      continue;
    }
    c.partial_window = partial[k];
    checks::applyWallClockPolicy(c, options.wall_clock_checks);
    r.checks.push_back(std::move(c));
  }
  for (auto& c : statistic_list) r.statistics.push_back(c->result());
  r.all_checks_passed = checks::allPassed(r.checks);
  if (const ExpectedFailure* x = expectedFailureFor(spec, r.method)) {
    r.expected_failure = *x;
    const bool cut_short = spec.duration_s < spec.scenario_duration_s - 1e-9;
    r.expectation_mismatches = expectationMismatches(*x, r.status, r.checks, cut_short);
    if (cut_short) {
      const bool listed_failed = std::any_of(r.checks.begin(), r.checks.end(), [&](const checks::CheckResult& c) {
        return c.decides && !c.passed && std::find(x->checks.begin(), x->checks.end(), c.name) != x->checks.end();
      });
      const bool status_reached = x->status != records::RunStatus::Completed && r.status == x->status;
      r.expected_failure_reached = listed_failed || status_reached || (x->checks.empty() && r.status == x->status);
    }
  }
  if (output_error) {
    try {
      writeSummary(r.summary_path, runRecord(spec, r, md));
    } catch (const OutputError&) {}
    throw *output_error;
  }
  writeSummary(r.summary_path, runRecord(spec, r, md));
  return r;
}

std::string checkResultsJson(const std::vector<checks::CheckResult>& results) {
  std::vector<records::CheckRecord> list;
  for (const auto& c : results) list.push_back(checkRecord(c));
  const nlohmann::json j = {
      {"format", records::kCheckResultsFormat}, {"checks", records::toJson(list)}, {"all_checks_passed", checks::allPassed(results)}};
  return j.dump(2);
}

std::vector<std::string> expectationMismatches(const ExpectedFailure& x, records::RunStatus status,
                                               const std::vector<checks::CheckResult>& results, bool cut_short) {
  std::vector<std::string> out;
  // A run stopped early may end before the expected failure happens: completing, and the listed
  // checks passing or not evaluated, are then no departure. A failure that is not expected is.
  if (status != x.status && !(cut_short && status == records::RunStatus::Completed)) {
    out.push_back(std::string("status ") + records::toString(status) + " (expected " + records::toString(x.status) + ")");
  }
  auto listed = [&](const std::string& name) { return std::binary_search(x.checks.begin(), x.checks.end(), name); };
  for (const checks::CheckResult& c : results) {
    if (c.decides && !c.passed && !listed(c.name)) out.push_back(c.name + " failed (not expected)");
  }
  if (cut_short) return out;
  for (const std::string& name : x.checks) {
    const auto c = std::find_if(results.begin(), results.end(), [&](const checks::CheckResult& r) { return r.name == name; });
    if (c == results.end())
      out.push_back(name + " was not evaluated (expected to fail)");
    else if (c->passed || !c->decides)
      out.push_back(name + " passed (expected to fail)");
  }
  return out;
}

int exitCode(const RunSummary& s) {
  if (s.status == records::RunStatus::Interrupted) return kExitInterrupted + (s.signal > 0 ? s.signal : 2);
  if (s.status == records::RunStatus::InputError) return kExitBadInput;
  if (s.expected_failure && s.status != records::RunStatus::InternalError) {
    if (s.expectation_mismatches.empty()) return kExitPass;
    return s.status != records::RunStatus::Completed && s.status != s.expected_failure->status ? kExitRunFailure : kExitCheckFailed;
  }
  if (s.status != records::RunStatus::Completed) return kExitRunFailure;
  return s.all_checks_passed ? kExitPass : kExitCheckFailed;
}

std::vector<std::string> traceChannels(const CaseSpec& spec) {
  sim::Simulator simu(spec.urdf_path, spec.data_path, spec.sim);
  std::unique_ptr<LexdynDriver> driver;
  if (isLexdyn(spec)) driver = std::make_unique<LexdynDriver>(spec, simu);
  const Recorder recorder(spec, simu, driver.get());
  return recorder.channels().names();
}

}  // namespace lexdyn::cases
