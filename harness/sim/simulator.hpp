// The true dynamics: a Simbody multibody system built from the same URDF + data file as the
// controller's model but by the simulator's own code (multibody.hpp: only the reading of the
// files, model::RobotDescription, is shared), integrated by SUNDIALS CVODE between control ticks. See docs/simulator.md
// for the contact model, the joint servo and its set-point profile, the sensors, the
// integrator settings and the failure handling.
//
// The robot is position-controlled: every control period the controller sends, per joint, a
// position and velocity set-point and a feed-forward torque; the joint servo tracks them with a
// PD law saturated at the URDF effort limit. The set-point is presented to the servo as a
// profile over the period that starts at the previous command and ends at the new one.
//
// This header includes neither Simbody nor SUNDIALS.
#pragma once

#include "harness/sim/cvode_integrator.hpp"
#include "harness/sim/multibody.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace lexdyn::sim {

/// Compliant ground contact at every point of every contact surface of the model.
struct ContactSettings {
  /// Hunt-Crossley normal force fn = k d^n (1 + c ddot) for penetration d > 0 (N, m, s).
  double stiffness = 2.0e6;          ///< k, N / m^n
  double exponent = 1.5;             ///< n (1.5: Hertz-like; the force is C1 at touch-down)
  double dissipation_s_per_m = 5.0;  ///< c
  /// Regularised Coulomb friction ft = -mu fn v / sqrt(|v|^2 + v_s^2) (tangential velocity v).
  double friction_coefficient = -1.0;   ///< mu; < 0: take the model's data-file value
  double slip_velocity_m_per_s = 1e-3;  ///< v_s
  double ground_height_m = 0.0;         ///< horizontal ground plane z = h
};

enum class SetpointProfile {
  Step,     ///< the new command applies at once for the whole period (stiff: slow to integrate)
  Linear,   ///< position ramps linearly from the previous to the new command; velocity and
            ///< feed-forward held at the new command / ramped linearly
  Hermite,  ///< cubic Hermite through (previous q, qdot) and (new q, qdot): continuous position
            ///< and velocity set-points; feed-forward torque ramped linearly
};

struct ServoSettings {
  Eigen::VectorXd kp;  ///< per joint (model order), Nm/rad or N/m
  Eigen::VectorXd kd;  ///< per joint, Nm s/rad or N s/m
  SetpointProfile profile = SetpointProfile::Hermite;
};

/// A fixed (bilateral) grasp contact between a frame of the robot and the world, modelled as a
/// stiff 6-D spring-damper (bushing). When switched on, its anchor is the frame's current pose.
struct GraspSettings {
  std::string name;
  std::string frame;
  double stiffness_N_per_m = 2.0e4;
  double damping_Ns_per_m = 400.0;
  double rot_stiffness_Nm_per_rad = 500.0;
  double rot_damping_Nms_per_rad = 10.0;
  bool initially_active = false;
};

/// The Jacobian of CVODE's Newton matrix (docs/simulator.md, "Integrator").
enum class IntegratorJacobian {
  DifferenceQuotient,  ///< CVODE's difference quotients: one right-hand side per state component
  AppliedForces        ///< the derivatives of the contact, grasp and servo forces mapped by M(q)^-1,
                       ///< and N(q) for the coordinates' rates; no right-hand side (an approximation)
};

const char* toString(IntegratorJacobian j);  ///< "difference_quotient" | "applied_forces"

struct IntegratorSettings {
  double rtol = 1e-4;
  double atol_position = 1e-6;  ///< rad or m (Euler angles, base position, joint positions)
  double atol_velocity = 1e-4;  ///< rad/s or m/s
  int max_order = 5;
  long max_steps_per_tick = 20000;
  double max_step_s = 0.0;  ///< 0: no limit (the control period bounds each call anyway)
  /// Solver of CVODE's Newton systems: our block elimination of the kinematic block, or
  /// SUNDIALS' dense LU of the whole matrix (for comparisons; docs/simulator.md, "Integrator").
  LinearSolver linear_solver = LinearSolver::BlockElimination;
  IntegratorJacobian jacobian = IntegratorJacobian::AppliedForces;
};

struct SimulatorSettings {
  double control_period_s = 0.005;
  ContactSettings contact;
  ServoSettings servo;
  std::vector<GraspSettings> grasps;
  IntegratorSettings integrator;
};

/// One control command: set-points at the end of the coming period.
struct JointCommand {
  Eigen::VectorXd q;       ///< joint positions
  Eigen::VectorXd qdot;    ///< joint velocities
  Eigen::VectorXd tau_ff;  ///< feed-forward torques
};

/// A wrench expressed in a sensor frame, about the sensor frame's origin.
struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
};

/// What the robot's sensors report at a tick.
struct SensorReadings {
  double time_s = 0.0;
  Eigen::VectorXd q;             ///< joint encoders
  Eigen::VectorXd qdot;          ///< joint velocities
  Eigen::VectorXd tau;           ///< applied joint torques (after saturation)
  std::vector<Wrench> wrenches;  ///< one per model force sensor (description().force_sensors)
};

/// Ground truth of one contact point (world frame).
struct ContactPoint {
  int surface = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  ///< ground on robot
};

/// How the initial state is put on the ground (docs/simulator.md, "Initial state").
enum class Settle {
  /// Static equilibrium of the whole simulated system at rest: base height, roll and pitch and
  /// the joint positions such that, at zero velocity, the compliant contact forces balance
  /// gravity and every joint servo (holding the given posture) balances its joint's load. The
  /// joints sit below the posture by the servo's static deflection (load / kp).
  StaticEquilibrium,
  /// Base height, roll and pitch only, joints exactly at the posture: the contact forces balance
  /// gravity as if the robot were rigid; the servos start unloaded (they take up the load in
  /// the first few ticks).
  BaseOnly,
  /// No solve: placeOnGround (base orientation = the given yaw, the lowest contact point at the
  /// penetration of an even share of the weight).
  None,
};

const char* toString(Settle s);

/// The initial state found by Simulator::restingState, with the force imbalance left at it.
struct RestingState {
  model::Configuration q;  ///< base pose and joints (velocity zero)
  Settle settle = Settle::None;
  bool converged = true;  ///< false: no equilibrium was found (`message` says why)
  int iterations = 0;     ///< Newton iterations
  /// At (q, u = 0), servo holding the posture: net external force on the robot (gravity +
  /// contact), net external moment about the base origin, and the largest net generalized force
  /// on a joint (servo torque + load; the unloaded servo's imbalance for BaseOnly / None).
  double net_force_N = 0.0;
  double net_moment_Nm = 0.0;
  double joint_residual_Nm = 0.0;
  std::string message;
};

struct StepResult {
  bool ok = true;
  CvodeStatus status = CvodeStatus::Success;
  std::string message;
};

class Simulator {
 public:
  /// Loads the robot (throws lexdyn::InputError on bad files or settings).
  Simulator(const std::string& urdf_path, const std::string& data_path, SimulatorSettings settings);
  /// Simulates the robot of `description` (e.g. a perturbed copy of the controller's).
  Simulator(model::RobotDescription description, SimulatorSettings settings);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  /// The simulated robot: its description, names, sizes and the ground-truth queries
  /// (framePlacement, centerOfMass) on data(). Not the controller's model::RobotModel.
  const Multibody& model() const;
  const SimulatorSettings& settings() const;

  /// Base pose that puts the lowest contact point at the static penetration below the ground
  /// (an even share of the weight on every contact point), for the given joints and base
  /// orientation / horizontal position.
  model::Configuration placeOnGround(const Eigen::VectorXd& joints, const Eigen::Matrix3d& base_rotation = Eigen::Matrix3d::Identity(),
                                     const Eigen::Vector2d& base_xy = Eigen::Vector2d::Zero()) const;

  /// Initial state at rest for a posture held by the servos (`settle`, see Settle): keeps the
  /// base's horizontal position `base_xy` and heading `base_yaw_rad`, and solves by a damped
  /// Newton iteration on this simulator's own force model (contact, gravity, servos; finite-
  /// difference Jacobian) for the base height, roll and pitch (free-flyer) and, with
  /// StaticEquilibrium, the joint positions. Converged when the net force, the net moment and
  /// (StaticEquilibrium) every joint's net torque are below 1e-9 max(m|g|, 1 N) (N, N m), and
  /// only if the equilibrium is stable (no negative eigenvalue of the stiffness -dr/dx). Returns
  /// converged = false with a message when the iteration fails (e.g. the centre of mass is not
  /// above the support); throws InputError for impossible requests (a floating robot without
  /// contact points, BaseOnly on a fixed base, wrong sizes). Start with
  /// reset(r.q, 0, &command holding `joints`) so that the servo holds the posture, not r.q.
  RestingState restingState(const Eigen::VectorXd& joints, Settle settle, double base_yaw_rad = 0.0,
                            const Eigen::Vector2d& base_xy = Eigen::Vector2d::Zero());

  /// Starts at time 0 from (q, u). The servo's command at time 0 (the start of the first
  /// set-point profile) is `initial_command` if given, else the state itself: (q.joints, joint
  /// velocities of u, zero feed-forward).
  void reset(const model::Configuration& q, const Eigen::VectorXd& u, const JointCommand* initial_command = nullptr);
  /// Advances one control period. `cmd` is the set-point at the end of the period. On an
  /// integrator failure the state stays at the last successful time and every later step fails.
  StepResult step(const JointCommand& cmd);

  /// Switches a grasp contact on (anchored at the frame's current pose) or off. The force law
  /// changes discontinuously, so the integrator is restarted at the next step.
  void setGraspActive(int grasp, bool active);
  bool graspActive(int grasp) const;
  int graspIndex(const std::string& name) const;  ///< throws InputError when absent

  double time() const;
  long tick() const;
  const SensorReadings& sensors() const;
  /// Ground truth at time().
  const model::Configuration& configuration() const;
  const Eigen::VectorXd& velocity() const;
  const std::vector<ContactPoint>& contactPoints() const;
  /// The ground's normal force on a contact surface (description order): the sum of its
  /// points' force z, N.
  double surfaceNormalForce(int surface) const;
  /// The simulator's state at time() (for model().framePlacement(data(), f), centerOfMass, the
  /// body kinematics). Each tick sets it with Multibody::setKinematicState: realized through
  /// Simbody's Position stage only, so not for coordinateRates(), netForce() or biasForces().
  const MultibodyState& data() const;
  /// Commanded servo set-point at time() (end of the last period).
  const Eigen::VectorXd& commandedPosition() const;
  /// Grasp wrench on the robot (world frame, at the grasp frame origin); zero when inactive.
  Wrench graspWrenchWorld(int grasp) const;
  /// Integrator counters since reset() (summed over restarts); last_step / last_order are the
  /// current integrator's.
  CvodeStats integratorStats() const;
  /// Size of the integrated state.
  int stateSize() const;
  /// Number of integrator restarts (at discontinuities: step set-points, grasp switches).
  long integratorRestarts() const;

  // ----- the integrator's view, for verification (docs/simulator.md, "Integrator") ---------
  /// The integrated state y (stateSize(): Euler angles, base position, joints; then u).
  std::vector<double> integratedState() const;
  /// ydot = f(t, y), at the current servo set-points.
  void rightHandSide(double t, const std::vector<double>& y, std::vector<double>& ydot);
  /// The Jacobian of the applied forces at (t, y) (IntegratorJacobian::AppliedForces; n x n).
  void appliedForcesJacobian(double t, const std::vector<double>& y, Eigen::MatrixXd& J);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lexdyn::sim
