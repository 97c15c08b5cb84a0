// Tasks and constraints of the controller (docs/controller.md). One file pair per task type.
//
// Decision variables (paper eq. 86, torques substituted out by the equation of motion as in the
// paper's experiments):
//   velocity domain (LexDyn, pure GN):   x = [u(k+1) (nv); dt * gamma(k+1) (ng)]
//   acceleration domain (WLS baseline):  x = [udot(k+1) (nv); gamma(k+1) (ng)]
// u is the model's generalized velocity (docs/model.md): [omega_world; v_base; qdot_joints] for
// a free-flyer robot. gamma are the contact wrench generators of every contact the controller
// may use (ContactLayout); inactive contacts keep their variables, bounded to zero, so that the
// problem sizes never change and a tick allocates nothing.
//
// Model / Data split: a TaskModel is configuration (const after construction: frame, gains,
// damper distances); the TaskData it creates holds the runtime state (current target, box
// limits: changed by timeline events through setTarget) and every per-tick quantity.
// TaskModel::compute() fills the task's rows of the hierarchy; geometric tasks also provide the
// second derivatives of their task function for the analytic Hessian (LexDynAH) and their
// Jacobian with respect to u (for BFGS, eq. 88).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include <limits>

#include "lexdyn/common/error.hpp"
#include "lexdyn/model/robot_model.hpp"

namespace lexdyn::hessian {
class KinematicHessianWorkspace;
}

namespace lexdyn::tasks {

/// Which formulation a row block is written for.
enum class Domain { Velocity, Acceleration };

/// One contact of the controller: a set of points on one frame, 4 friction-pyramid generators per
/// point. A friction contact has gamma >= 0; a fixed (grasp) contact has no sign bound.
struct ContactSpec {
  std::string name;           ///< e.g. "RIGHT_FOOT", "LEFT_HAND_POLE"
  model::FrameId frame = -1;  ///< points are given in this frame
  std::vector<Eigen::Vector3d> points;
  bool fixed = false;     ///< fixed contact: no sign bound on its generators
  double friction = 0.7;  ///< friction coefficient of the pyramid
  /// Contact normal in the frame (direction of the force the environment applies on the robot).
  Eigen::Vector3d normal_in_frame = Eigen::Vector3d::UnitZ();
  /// A point contact (one point): its contact task holds the point's position only (3 rows) and
  /// its friction pyramid is about the ground's normal, world +z, whatever the frame's attitude
  /// (a ball foot on a pitched shank). normal_in_frame is then unused.
  bool point = false;
  /// Minimum normal force of each point of the active friction contact, N (the plan's contact
  /// margin, tasks/contact_margins.hpp): each of the point's generators is at least
  /// min_normal_force sqrt(1 + mu^2) / 4.
  double min_normal_force = 0.0;
};

/// Layout of the contact generator variables: contact c, point p, generator g (0..3) is variable
/// nv + offset(c) + 4 p + g. Whether a contact is active is per-tick state (ControlState).
class ContactLayout {
 public:
  ContactLayout() = default;
  ContactLayout(int nv, std::vector<ContactSpec> contacts);
  int nv() const { return nv_; }
  int ng() const { return ng_; }        ///< number of generator variables
  int nx() const { return nv_ + ng_; }  ///< total number of decision variables
  int count() const { return static_cast<int>(contacts_.size()); }
  const ContactSpec& contact(int c) const {
    checkIndex("ContactLayout::contact", c, static_cast<long>(contacts_.size()));
    return contacts_[static_cast<size_t>(c)];
  }
  int offset(int c) const {  ///< first generator of contact c (relative to nv)
    checkIndex("ContactLayout::offset", c, static_cast<long>(offset_.size()));
    return offset_[static_cast<size_t>(c)];
  }                                         ///< first generator of contact c (relative to nv)
  int find(const std::string& name) const;  ///< -1 when absent
  /// 3 x 4 matrix of unit generator directions of a point in world coordinates, given the
  /// contact frame's world rotation: normalized (n + mu t_k) for t_k = +t1, -t1, +t2, -t2.
  static void generators(const Eigen::Matrix3d& R_world_frame, const Eigen::Vector3d& normal_in_frame, double mu,
                         Eigen::Ref<Eigen::Matrix<double, 3, 4>> D);
  /// The generators of a contact's points given its frame's world rotation: about the frame's
  /// normal, or the world's +z for a point contact.
  static void generators(const ContactSpec& spec, const Eigen::Matrix3d& R_world_frame, Eigen::Ref<Eigen::Matrix<double, 3, 4>> D);

 private:
  int nv_ = 0, ng_ = 0;
  std::vector<ContactSpec> contacts_;
  std::vector<int> offset_;
};

/// Per-tick inputs shared by all tasks. Everything is valid for the current tick only.
struct TickContext {
  const model::RobotModel* model = nullptr;
  model::ModelData* data = nullptr;  ///< updated at the measured state of this tick
  const model::Configuration* q = nullptr;
  const Eigen::VectorXd* u = nullptr;  ///< measured velocity (nv)
  const ContactLayout* contacts = nullptr;
  const std::vector<char>* contact_active = nullptr;  ///< per contact
  double dt = 0.005;                                  ///< control period, s
  double time = 0.0;                                  ///< s
  Domain domain = Domain::Velocity;
  /// Shared per-tick quantities computed once by the controller before the tasks.
  const Eigen::MatrixXd* M = nullptr;  ///< mass matrix (nv x nv)
  const Eigen::VectorXd* N = nullptr;  ///< Coriolis + gravity (nv)
  /// Jc^T of the active contacts (nv x ng, contactJacobianTranspose), when the controller computed
  /// it for this tick; null: each dynamics task computes its own.
  const Eigen::MatrixXd* JcT = nullptr;
  /// Dof axes and subtree CoMs updated at this tick (KinematicHessianWorkspace::update); needed
  /// only by accumulateHessian() of geometric tasks (LexDynAH).
  const hessian::KinematicHessianWorkspace* hessian = nullptr;
  /// Whether a row that constrains nothing at this tick (a self-collision pair beyond its
  /// interaction distance: lower bound -inf) gets its TaskData::J when it was active in the
  /// previous solve (TaskData::held). A method that reads earlier ticks' Jacobians with the
  /// previous solve's multipliers needs them (LexDynBFGS's secant, eq. 88: y(k) = sum (J(k) -
  /// J(k-1))^T lambda; a row held then may be free now, and a row not held then has lambda = 0).
  /// Other free rows, and every free row when false (LexDynAH, WLS), have rows of J and A of
  /// zeros.
  bool free_row_jacobians = true;
};

/// Per-tick data of a task. Sizes are fixed by TaskModel::createData().
struct TaskData {
  /// The task's rows of the hierarchy: lower <= A x <= upper (A: rows x nx).
  Eigen::MatrixXd A;
  Eigen::VectorXd lower, upper;
  /// Task function value, error and Jacobian with respect to u (rows x nv), for recording,
  /// switching, BFGS (eq. 88) and the analytic Hessian. Tasks without a task function
  /// (dynamics, bounds) leave J zero and return false from TaskModel::hasFunction().
  Eigen::VectorXd error;  ///< e = f_d - f(q) (or the distance-like quantity of an inequality)
  Eigen::MatrixXd J;      ///< d f / d u
  /// Per row: true when the row constrains the solution at this tick (an inequality inside its
  /// interaction distance, or any equality row); for recording "which constraints are active".
  std::vector<char> engaged;
  /// Per row: the row was active in the previous tick's solve, so that it may hold a multiplier
  /// of that solve (an inactive row's are zero). Set by the controller after each solve; all
  /// zero before the first and after a reset.
  std::vector<char> held;
  /// Runtime target of the task (meaning per task type; empty when the task has none).
  Eigen::VectorXd target;
  /// False while the task has no target yet: a task created without an initial target holds
  /// the value its function has at the first compute() (which then sets the target and this
  /// flag). setTarget() sets it.
  bool target_set = false;
  virtual ~TaskData() = default;
};

enum class TaskKind {
  Equality,    ///< rows are equalities (lower == upper)
  Inequality,  ///< rows are inequalities (dampers, limits, boxes)
  Bounds,      ///< rows act on single variables: placed in the first (bounds) level
};

class TaskModel {
 public:
  explicit TaskModel(std::string name) : name_(std::move(name)) {}
  virtual ~TaskModel() = default;
  TaskModel(const TaskModel&) = delete;
  TaskModel& operator=(const TaskModel&) = delete;

  const std::string& name() const { return name_; }
  /// Number of rows this task contributes (constant).
  virtual int rows() const = 0;
  virtual TaskKind kind() const = 0;
  /// True when the task has a task function f(q) and fills d.J / d.error (false: dynamics,
  /// bounds on generators, trust region, velocity and wrench minimisation; their d.J stays 0).
  virtual bool hasFunction() const { return false; }
  /// True when the rows come from a non-linear geometric task function f(q) whose Hessian
  /// enters the hierarchical Hessian (Newton augmentation, paper sec. VI).
  virtual bool geometric() const { return false; }
  /// True when the rows read the velocity (or acceleration) variables only: A's columns past
  /// the first nv are zero at every tick. Geometric tasks write A = [J, 0]. The controller then
  /// copies and multiplies only those columns of the rows (checked on the first copy).
  virtual bool velocityOnly() const { return geometric(); }
  /// True when A is set by createData() and never changes (rows that are decision variables
  /// themselves): the controller copies it into the problem once, its bounds at every tick.
  virtual bool constantMatrix() const { return false; }
  /// Domains the task supports.
  virtual bool supports(Domain d) const { return d == Domain::Velocity; }
  /// True for rows that can always be met exactly whatever earlier levels impose (the equation
  /// of motion: its unactuated rows are solved by the free-flyer velocity). The controller puts
  /// such a task alone on its own solver level ahead of the rest of its level, an exact
  /// reformulation that lets the solver eliminate it (docs/solver.md).
  virtual bool separateLevel() const { return false; }

  virtual std::unique_ptr<TaskData> createData(const ContactLayout& layout) const;
  /// Fills d.A, d.lower, d.upper (and d.error, d.J, d.engaged) for this tick.
  virtual void compute(const TickContext& ctx, TaskData& d) const = 0;
  /// Called when the controller (re)starts from a state, before the first compute(): forget
  /// per-run state (e.g. a contact pose captured when the contact was made).
  virtual void reset(TaskData& d) const { (void)d; }
  /// Bounds tasks: the variable of each row (rows with coefficient 1), filled by compute() into
  /// d.lower / d.upper; A is unused.
  virtual void boundVariables(const ContactLayout& layout, std::vector<int>& vars) const;

  /// Geometric tasks: H += sum_d w[d] * d^2 f_d / dq^2 (nv x nv, symmetric), with the second
  /// derivatives taken in the coordinates whose first derivative is d.J (joint angles, base
  /// translation, base rotation as Euler angles re-zeroed at this tick; lexdyn/hessian).
  virtual void accumulateHessian(const TickContext& ctx, const TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& w,
                                 Eigen::Ref<Eigen::MatrixXd> H) const;
  /// Geometric tasks: mark the dofs on the task's kinematic chain (the I* of eq. 89).
  virtual void chainDofs(const model::RobotModel& model, std::vector<char>& mask) const;

  /// Size of the runtime target (0: the task has none). setTarget() checks the size and throws
  /// lexdyn::InputError naming the task when it is wrong or the task has no target.
  virtual int targetSize() const { return 0; }
  /// Checks the size, then checkTarget(), then stores the target and sets d.target_set.
  void setTarget(TaskData& d, const Eigen::Ref<const Eigen::VectorXd>& target) const;
  /// Task-specific validation of a target of the right size (rotation, box order, finite
  /// values); throws lexdyn::InputError naming the task.
  virtual void checkTarget(const Eigen::Ref<const Eigen::VectorXd>& target) const;

 protected:
  /// Sizes the base members of d for this task (A rows x nx, bounds, error, J rows x nv,
  /// engaged, held, target) and zeroes them; with `engaged`, every row is marked engaged (rows that
  /// always constrain the solution). Used by createData() overrides of derived data types.
  void initData(TaskData& d, const ContactLayout& layout, bool engaged = false) const;
  /// A new data of type D (TaskData or derived from it) set up by initData().
  template <class D = TaskData>
  std::unique_ptr<D> makeData(const ContactLayout& layout, bool engaged) const {
    auto d = std::make_unique<D>();
    initData(*d, layout, engaged);
    return d;
  }
  /// Throws lexdyn::InputError naming the task when the layout's nv is not the model's (`nv`,
  /// the one the task was built for); used by createData() overrides.
  void requireLayoutNv(const ContactLayout& layout, int nv) const;
  /// The same for tasks built for a contact layout: its nv and ng must be `nv` and `ng`.
  void requireLayoutSizes(const ContactLayout& layout, int nv, int ng) const;

 private:
  std::string name_;
};

}  // namespace lexdyn::tasks
