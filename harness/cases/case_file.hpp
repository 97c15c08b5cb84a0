// Case files: a scenario as strict data (docs/simulator.md, "Case files"). The same binary runs
// every case; nothing case-specific is compiled in.
//
// Top level: name, description?, robot{urdf, data}, duration_s, control_period_s?,
// initial_state{posture, joints?, base_xy?, base_yaw_rad?, settle?}, controller{type, ...},
// sim{contact, servo, grasps?, integrator?}, events?[...], trace?{every_n_ticks?,
// flush_every_rows?, frames?, timings?}, checks[...], comparisons?[...]. The lexdyn controller's
// section and events are described in docs/cases.md. Unknown keys, wrong types and unknown references (joints, frames, surfaces,
// grasps, postures) are errors naming the file, line and key path. Paths are relative to the
// case file's directory. Sections are tagged by `type` / `action` so that later controllers,
// events and checks are added without changing existing files.
#pragma once

#include "harness/records/controller_type.hpp"
#include "harness/cases/case_overrides.hpp"
#include "harness/cases/lexdyn_spec.hpp"
#include "harness/cases/target_path.hpp"
#include "harness/checks/check_registry.hpp"
#include "harness/checks/checks.hpp"
#include "harness/records/run_status.hpp"
#include "harness/sim/simulator.hpp"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lexdyn::yaml {
class Node;
}

namespace lexdyn::cases {

enum class Waveform { Sine, RaisedCosine };

/// offset(t) = amplitude * w(2 pi (t - start_s) / period_s + phase_rad) for t >= start_s, with
/// w = sin (sine) or (1 - cos) / 2 (raised_cosine, which starts at rest); 0 before start_s.
struct MotionSpec {
  std::vector<int> joints;
  double amplitude = 0.0;  ///< rad or m
  double period_s = 1.0;
  double phase_rad = 0.0;
  double start_s = 0.0;
  Waveform waveform = Waveform::Sine;
};

struct ControllerSpec {
  records::ControllerType type = records::ControllerType::PostureServo;
  std::string posture;              ///< posture_servo: data-file posture
  std::vector<MotionSpec> motions;  ///< posture_servo: added to the posture
  LexdynSpec lexdyn;                ///< lexdyn: method, parameters, contacts, tasks, levels
};

/// The robot starts at rest in `posture`, its servos holding it; the base keeps (base_x,
/// base_y, base_yaw_rad) and is put on the ground as `settle` says (sim::Settle; default:
/// static_equilibrium for a free-flyer with contact surfaces, none otherwise).
/// A small seeded perturbation of the initial posture (to break exact symmetries): joint j of
/// `joints` moves by amplitude_rad * u_j, u_j uniform in [-1, 1] from (seed, j) alone
/// (docs/cases.md, "Perturbations"); the result is clamped to the joint's limits.
struct PosturePerturbation {
  std::uint64_t seed = 0;
  double amplitude_rad = 0.0;
  std::vector<int> joints;  ///< joint indices (all joints by default)
};

struct InitialStateSpec {
  std::string posture;
  std::vector<std::pair<int, double>> joints;  ///< overrides of the posture (joint index, value)
  PosturePerturbation perturbation;
  double base_x = 0.0, base_y = 0.0, base_yaw_rad = 0.0;
  sim::Settle settle = sim::Settle::None;
  bool settle_given = false;  ///< false: the default was taken
  std::string settle_where;   ///< "file:line: initial_state.settle" (or initial_state) for errors
};

struct GainGroup {
  std::string match;  ///< joint-name pattern, '*' matches any run of characters
  double kp = 0.0, kd = 0.0;
};

/// What an event does: grasp_on, grasp_off (the simulator's grasps); set_target, add_contact,
/// remove_contact, target_trajectory, swing (a lexdyn controller's).
enum class EventAction { GraspOn, GraspOff, SetTarget, AddContact, RemoveContact, TargetTrajectory, Swing };
/// The case file's spelling ("grasp_on", ...).
const char* toString(EventAction a);

/// A timeline event, applied at the first tick at or after at_s (docs/cases.md, "Events").
struct EventSpec {
  double at_s = 0.0;
  EventAction action = EventAction::SetTarget;
  std::string grasp;  ///< grasp_on, grasp_off
  std::string where;
  std::string task;       ///< set_target, target_trajectory, swing
  Eigen::VectorXd value;  ///< set_target: the task's target (TaskModel::targetSize values)
  double ramp_s = 0.0;    ///< set_target: reach `value` linearly over this time (0: at once)
  std::string contact;    ///< add_contact, remove_contact
  std::string file;       ///< target_trajectory: the CSV file (resolved)
  TargetTrajectory trajectory;
  Swing swing;
};

struct TraceSpec {
  int every_n_ticks = 1;
  int flush_every_rows = 200;
  std::vector<std::string> frames;  ///< recorded as frame.<F>.x/y/z (plus the frames checks need)
  bool timings = true;              ///< lexdyn: record the wall-time channels time.*_us
};

/// The simulated robot differs from the model the controller uses (model mismatch): link masses
/// scaled (inertias with them) and centres of mass moved, for links whose name matches a
/// pattern. Later entries act on top of earlier ones (docs/cases.md, "Perturbations").
struct LinkMassScale {
  std::string match;
  double scale = 1.0;
};
struct LinkComOffset {
  std::string match;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  ///< in the link frame
};
struct SimModelPerturbation {
  std::vector<LinkMassScale> mass_scale;
  std::vector<LinkComOffset> com_offset;
};

/// A failure the case expects of one method (`expected_failures`; docs/cases.md, "Expected
/// failures"): the run status it ends with and the checks that fail, with the reason. A run
/// that fails exactly so is an expected failure (exit code 0); any other outcome, including a
/// listed check that passes, is reported as a mismatch.
struct ExpectedFailure {
  std::string method;                                         ///< "" for a case without methods
  records::RunStatus status = records::RunStatus::Completed;  ///< completed | controller_failure | integrator_failure | diverged
  std::vector<std::string> checks;                            ///< the checks expected to fail (sorted)
  std::string reason;
  std::string where;  ///< file:line of the entry
};

struct CaseSpec {
  std::string path;  ///< the case file
  std::string name, description;
  std::string urdf_path, data_path;  ///< resolved
  /// robot.strict and robot.package_path: how the robot files are read (docs/model.md).
  model::LoadOptions robot_options;
  /// What the loader assumed about the robot files (RobotDescription::warnings); the runner
  /// prints them and keeps them in summary.json.
  std::vector<std::string> robot_warnings;
  double duration_s = 0.0;
  double control_period_s = 0.005;
  InitialStateSpec initial_state;
  ControllerSpec controller;
  sim::SimulatorSettings sim;  ///< gains resolved per joint
  std::vector<GainGroup> gain_groups;
  std::vector<EventSpec> events;  ///< sorted by time
  TraceSpec trace;
  std::vector<checks::CheckSpec> checks;
  std::vector<checks::ComparisonSpec> comparisons;  ///< evaluated by `lexdyn-harness compare`
  std::vector<ExpectedFailure> expected_failures;   ///< at most one per method
  SimModelPerturbation sim_model;                   ///< sim.model
  /// stop_at_s (`run --duration`): the run stops there; duration_s is already cut to it.
  double stop_at_s = 0.0;
  /// The scenario's own duration (the file's duration_s, before stop_at_s cut it).
  double scenario_duration_s = 0.0;
  std::vector<Override> overrides;  ///< applied to the file's document before reading
  /// The effective case document (the file with the overrides) as YAML text, and the keys that
  /// hold file paths (key path, resolved path), for effectiveCaseText.
  std::string document;
  std::vector<std::pair<std::string, std::string>> file_fields;
};

/// Reads and validates a case file (and the robot files it names). For a lexdyn controller it
/// builds the controller of every method the case has a hierarchy for, so that a case that
/// loads runs with each of them. Throws lexdyn::InputError.
CaseSpec loadCase(const std::string& path);
/// The same with overrides applied to the file's document first (case_overrides.hpp); errors at
/// an overridden value name the override.
CaseSpec loadCase(const std::string& path, const std::vector<Override>& overrides);

/// The effective case (file + overrides) as one YAML file that reproduces the run on its own:
/// file paths rewritten relative to `dest_dir` (absolute when dest_dir is empty), a header
/// comment naming the source file and the overrides.
std::string effectiveCaseText(const CaseSpec& spec, const std::string& dest_dir);

/// The case's expected failure for `method` ("" for a case without methods), or null.
const ExpectedFailure* expectedFailureFor(const CaseSpec& spec, const std::string& method);

/// Reads a method comparison (the case's `comparisons` entries) against a loaded case.
checks::ComparisonSpec readComparison(const yaml::Node& node, const CaseSpec& spec);

/// The simulated robot's description: the case's robot files with sim.model applied.
model::RobotDescription simulatedRobot(const CaseSpec& spec);

/// The initial joint positions: the posture, the case's joint values, the perturbation (within
/// the joints' limits of `robot`).
Eigen::VectorXd initialJointPositions(const CaseSpec& spec, const model::RobotDescription& robot);

/// The case runs the lexdyn controller (else the posture servo).
inline bool isLexdyn(const CaseSpec& c) { return c.controller.type == records::ControllerType::Lexdyn; }

/// The method of a lexdyn case as a string ("" for other controllers).
std::string methodName(const CaseSpec& spec);

/// Overrides the method of a lexdyn case (--method); InputError naming `where` when the case has
/// no hierarchy for it or is not a lexdyn case.
void overrideMethod(CaseSpec& spec, const std::string& method, const std::string& where);

/// Glob match with '*' only.
using checks::globMatch;

const char* toString(sim::SetpointProfile p);

}  // namespace lexdyn::cases
