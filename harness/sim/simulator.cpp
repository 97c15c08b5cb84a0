// Simulator: the robot's Simbody matter subsystem (the simulator's own, multibody.hpp; built
// from the robot description independently of lexdyn::model), external forces computed here (gravity, compliant ground contact, grasp
// bushings, joint servos), Simbody's articulated-body forward dynamics for udot, CVODE for time integration. Conventions and parameters:
// docs/simulator.md.
#include "harness/sim/simulator.hpp"

#include "lexdyn/common/format.hpp"
#include "lexdyn/common/error.hpp"
#include "harness/sim/multibody.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace lexdyn::sim {

namespace {

struct PointInfo {
  int surface = -1;
  int body = -1;
  Eigen::Vector3d r_body = Eigen::Vector3d::Zero();  // point in its body frame (a sphere's centre)
  double radius = 0.0;                               // a sphere (ball foot): it touches the ground at its lowest point
};

struct GraspState {
  GraspSettings settings;
  int body = -1;
  Eigen::Isometry3d X_body_frame = Eigen::Isometry3d::Identity();
  bool active = false;
  Eigen::Matrix3d R_anchor = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_anchor = Eigen::Vector3d::Zero();
};

struct SensorInfo {
  int body = -1;
  Eigen::Isometry3d X_body_frame = Eigen::Isometry3d::Identity();
};

std::string fmt(double v) { return formatNumber(v); }

// Adds the integrator counters of `b` to `a` (last_step and last_order stay a's).
void addCounters(CvodeStats& a, const CvodeStats& b) {
  a.steps += b.steps;
  a.rhs_evals += b.rhs_evals;
  a.jac_evals += b.jac_evals;
  a.jac_rhs_evals += b.jac_rhs_evals;
  a.nonlin_iters += b.nonlin_iters;
  a.nonlin_conv_fails += b.nonlin_conv_fails;
  a.err_test_fails += b.err_test_fails;
  a.lin_setups += b.lin_setups;
  a.lin_full_setups += b.lin_full_setups;
}

// Rotation vector of R (angle * axis), |angle| <= pi.
Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace

// Signed distance (> 0 inside) of p to the convex hull of `pts` in the plane; -distance to the
// nearest point when there are fewer than 3.
static double horizontalMargin(std::vector<Eigen::Vector2d> pts, const Eigen::Vector2d& p) {
  std::sort(pts.begin(), pts.end(),
            [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * pts.size() + 1);
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 1e-12) --k;
    h[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 1e-12) --k;
    h[k++] = pts[i];
  }
  if (k > 1) --k;
  h.resize(k);
  if (h.size() < 3) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& q : h) d = std::min(d, (q - p).norm());
    return h.empty() ? -std::numeric_limits<double>::infinity() : -d;
  }
  double m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < h.size(); ++i) {
    const Eigen::Vector2d a = h[i], e = (h[(i + 1) % h.size()] - a).normalized();
    m = std::min(m, e.x() * (p.y() - a.y()) - e.y() * (p.x() - a.x()));
  }
  return m;
}

struct Simulator::Impl final : public OdeSystem {
  Impl(Multibody m, SimulatorSettings s)
      : model(std::move(m)), settings(std::move(s)), data(model.createState()), observed(model.createState()) {}

  Multibody model;
  SimulatorSettings settings;
  MultibodyState data;      // used by the right-hand side
  MultibodyState observed;  // state at the last tick
  int nj = 0, nv = 0, nqc = 0, ny = 0, off = 0;
  double mu = 0.0;
  std::vector<PointInfo> points;
  std::vector<GraspState> grasps;
  std::vector<SensorInfo> sensor_info;

  // Servo commands: the profile goes from (q0, qd0, tau0) at t0 to (q1, qd1, tau1) at t0 + T.
  Eigen::VectorXd q0, qd0, tau0, q1, qd1, tau1;
  double t0 = 0.0;

  std::vector<double> y;
  std::unique_ptr<CvodeIntegrator> cvode;
  long k = 0;
  long restarts = 0;
  bool restart_pending = false;
  bool failed = false;
  StepResult failure;

  // Observations at the tick.
  SensorReadings sensors;
  model::Configuration config;
  Eigen::VectorXd u;
  std::vector<ContactPoint> contact_points;
  std::vector<Wrench> grasp_world;
  Eigen::VectorXd tau_work;

  int size() const override { return ny; }

  // Counters of the integrator before its last restart.
  CvodeStats before_restart;
  void accumulate(const CvodeStats& c) { addCounters(before_restart, c); }

  double period() const { return settings.control_period_s; }

  // Servo set-point at time t (s in [0, 1] over the current period).
  void setpoint(double t, int j, double& q_ref, double& qd_ref, double& tau_ff) const {
    const double T = period();
    double s = (t - t0) / T;
    s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    switch (settings.servo.profile) {
      case SetpointProfile::Step:
        q_ref = q1[j];
        qd_ref = qd1[j];
        tau_ff = tau1[j];
        return;
      case SetpointProfile::Linear:
        q_ref = q0[j] + s * (q1[j] - q0[j]);
        qd_ref = qd1[j];
        tau_ff = tau0[j] + s * (tau1[j] - tau0[j]);
        return;
      case SetpointProfile::Hermite: {
        const double s2 = s * s, s3 = s2 * s;
        const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
        const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1, d01 = -6 * s2 + 6 * s, d11 = 3 * s2 - 2 * s;
        q_ref = h00 * q0[j] + h10 * T * qd0[j] + h01 * q1[j] + h11 * T * qd1[j];
        qd_ref = (d00 * q0[j] + d01 * q1[j]) / T + d10 * qd0[j] + d11 * qd1[j];
        tau_ff = tau0[j] + s * (tau1[j] - tau0[j]);
        return;
      }
    }
  }

  // Servo torque of joint j at (t, q, u), before its torque limit.
  double servoTorque(double t, int j, const double* q, const double* uu) const {
    double q_ref = 0.0, qd_ref = 0.0, tau_ff = 0.0;
    setpoint(t, j, q_ref, qd_ref, tau_ff);
    return settings.servo.kp[j] * (q_ref - q[off + j]) + settings.servo.kd[j] * (qd_ref - uu[off + j]) + tau_ff;
  }

  // A contact point at the state of `d`: its lever arm r from its body's origin, its position p
  // and velocity v (world).
  static void pointState(const BodyKinematics& d, const PointInfo& P, Eigen::Vector3d& r, Eigen::Vector3d& p, Eigen::Vector3d& v) {
    // The point of contact: a sphere's lowest point, whose material velocity is the body's
    // there (a rolling ball does not slip).
    r = d.R[static_cast<size_t>(P.body)] * P.r_body;
    r.z() -= P.radius;
    p = d.p.col(P.body) + r;
    v = d.v.col(P.body) + d.omega.col(P.body).cross(r);
  }

  // All applied forces at (t, q, u) with `d` updated at that state. With `record`, the contact
  // point states, grasp wrenches and servo torques are stored as observations.
  void evaluateForces(MultibodyState& md, double t, const double* q, const double* uu, bool record) {
    const model::RobotDescription& desc = model.description();
    const BodyKinematics& d = md.bodies();
    model.clearForces(md);
    // Gravity at each body's CoM.
    for (int b = 0; b < model.numBodies(); ++b) {
      const Eigen::Vector3d f = desc.links[static_cast<size_t>(b)].mass * desc.gravity;
      model.addBodyForce(md, b, (d.com.col(b) - d.p.col(b)).cross(f), f);
    }
    // Ground contact.
    const ContactSettings& c = settings.contact;
    for (size_t i = 0; i < points.size(); ++i) {
      const PointInfo& P = points[i];
      Eigen::Vector3d r, p, v;
      pointState(d, P, r, p, v);
      Eigen::Vector3d F = Eigen::Vector3d::Zero();
      const double pen = c.ground_height_m - p.z();
      if (pen > 0.0) {
        // Hunt-Crossley: fn = k pen^n (1 + c pen_dot), never pulling.
        double fn = c.stiffness * std::pow(pen, c.exponent) * (1.0 - c.dissipation_s_per_m * v.z());
        if (fn < 0.0) fn = 0.0;
        // Regularised Coulomb friction.
        const double vx = v.x(), vy = v.y();
        const double scale = -mu * fn / std::sqrt(vx * vx + vy * vy + c.slip_velocity_m_per_s * c.slip_velocity_m_per_s);
        F = Eigen::Vector3d(scale * vx, scale * vy, fn);
        model.addBodyForce(md, P.body, r.cross(F), F);
      }
      if (record) {
        ContactPoint& cp = contact_points[i];
        cp.surface = P.surface;
        cp.position = p;
        cp.velocity = v;
        cp.force = F;
      }
    }
    // Grasp bushings.
    for (size_t g = 0; g < grasps.size(); ++g) {
      const GraspState& G = grasps[g];
      Wrench w;
      if (G.active) {
        const Eigen::Matrix3d& Rb = d.R[static_cast<size_t>(G.body)];
        const Eigen::Vector3d r = Rb * G.X_body_frame.translation();
        const Eigen::Vector3d pG = d.p.col(G.body) + r;
        const Eigen::Matrix3d RG = Rb * G.X_body_frame.linear();
        const Eigen::Vector3d vG = d.v.col(G.body) + d.omega.col(G.body).cross(r);
        const Eigen::Vector3d w_body = d.omega.col(G.body);
        const GraspSettings& s = G.settings;
        const Eigen::Vector3d F = -s.stiffness_N_per_m * (pG - G.p_anchor) - s.damping_Ns_per_m * vG;
        const Eigen::Vector3d rot_err = G.R_anchor * rotationVector(G.R_anchor.transpose() * RG);
        const Eigen::Vector3d T = -s.rot_stiffness_Nm_per_rad * rot_err - s.rot_damping_Nms_per_rad * w_body;
        model.addBodyForce(md, G.body, T + r.cross(F), F);
        w.force = F;
        w.torque = T;
      }
      if (record) grasp_world[g] = w;
    }
    // Joint servos.
    const Eigen::VectorXd& tau_max = model.jointTorqueLimits();
    for (int j = 0; j < nj; ++j) {
      const double tau = std::clamp(servoTorque(t, j, q, uu), -tau_max[j], tau_max[j]);
      model.setJointForce(md, j, tau);
      if (record) tau_work[j] = tau;
    }
  }

  // Workspaces of jacobian().
  Eigen::MatrixXd jac_point, jac_Ku, jac_Kq, jac_N, jac_Ninv, jac_Minv, jac_dq;

  // IntegratorJacobian::AppliedForces: with G(q, u) the generalized applied forces and the
  // dynamics udot = M(q)^-1 (G - C(q, u)), qdot = N(q) u,
  //   d qdot / d q = 0,  d qdot / d u = N,
  //   d udot / d q = M^-1 (dG/dx) N^-1,  d udot / d u = M^-1 dG/du,
  // where x is the displacement that the speeds integrate (dx = N^-1 dq). dG/dx and dG/du hold
  // the stiffness and damping of the contact points (J^T dF/dp J, J^T dF/dv J with the point's
  // Jacobian J), of the grasp bushings and of the unsaturated servos. Left out: the derivatives
  // of N, M, gravity, the Coriolis terms and of J itself. They are small beside the stiff
  // forces over one step; CVODE's error test decides the accuracy either way.
  void jacobian(double t, const double* yy, const double*, double* out) override {
    const double* q = yy;
    const double* uu = yy + nqc;
    model.setState(data, q, uu);
    const BodyKinematics& d = data.bodies();
    jac_Ku.setZero(nv, nv);
    jac_Kq.setZero(nv, nv);
    jac_point.resize(6, nv);
    // Ground contact: F(p, v) of evaluateForces, differentiated.
    const ContactSettings& c = settings.contact;
    for (const PointInfo& P : points) {
      Eigen::Vector3d r, p, v;
      pointState(d, P, r, p, v);
      const double pen = c.ground_height_m - p.z();
      if (!(pen > 0.0)) continue;
      const double kp = c.stiffness * std::pow(pen, c.exponent);
      const double fn = kp * (1.0 - c.dissipation_s_per_m * v.z());
      if (!(fn > 0.0)) continue;
      const double dfn_dpz = -c.stiffness * c.exponent * std::pow(pen, c.exponent - 1.0) * (1.0 - c.dissipation_s_per_m * v.z());
      const double dfn_dvz = -kp * c.dissipation_s_per_m;
      const double w = std::sqrt(v.x() * v.x() + v.y() * v.y() + c.slip_velocity_m_per_s * c.slip_velocity_m_per_s);
      // dF/dfn: friction scales with fn.
      const Eigen::Vector3d dF_dfn(-mu * v.x() / w, -mu * v.y() / w, 1.0);
      Eigen::Matrix3d dF_dp = Eigen::Matrix3d::Zero();
      dF_dp.col(2) = dF_dfn * dfn_dpz;
      Eigen::Matrix3d dF_dv = Eigen::Matrix3d::Zero();
      const Eigen::Vector2d vt(v.x(), v.y());
      dF_dv.topLeftCorner<2, 2>() = (-mu * fn / w) * (Eigen::Matrix2d::Identity() - vt * vt.transpose() / (w * w));
      dF_dv.col(2) += dF_dfn * dfn_dvz;
      // At the point of contact (a sphere's lowest point; the point itself otherwise).
      if (P.radius > 0.0)
        model.pointJacobian(data, P.body, d.R[static_cast<size_t>(P.body)].transpose() * r, jac_point);
      else
        model.pointJacobian(data, P.body, P.r_body, jac_point);
      const auto Jl = jac_point.topRows<3>();
      jac_Kq.noalias() += Jl.transpose() * (dF_dp * Jl);
      jac_Ku.noalias() += Jl.transpose() * (dF_dv * Jl);
    }
    // Grasp bushings: F = -k (p - p0) - d v, T = -k_r rot_err - d_r omega (rot_err taken as the
    // rotation's displacement).
    for (const GraspState& G : grasps) {
      if (!G.active) continue;
      const GraspSettings& gs = G.settings;
      model.pointJacobian(data, G.body, G.X_body_frame.translation(), jac_point);
      const auto Jl = jac_point.topRows<3>();
      const auto Ja = jac_point.bottomRows<3>();
      jac_Kq.noalias() -= gs.stiffness_N_per_m * Jl.transpose() * Jl + gs.rot_stiffness_Nm_per_rad * Ja.transpose() * Ja;
      jac_Ku.noalias() -= gs.damping_Ns_per_m * Jl.transpose() * Jl + gs.rot_damping_Nms_per_rad * Ja.transpose() * Ja;
    }
    // Servos below their torque limit (on the diagonal of dG/dx: the joints' block of N is the
    // identity, joint rates = joint speeds).
    const Eigen::VectorXd& tau_max = model.jointTorqueLimits();
    for (int j = 0; j < nj; ++j) {
      if (!(std::abs(servoTorque(t, j, q, uu)) < tau_max[j])) continue;  // clamped: no change with q or u
      jac_Kq(off + j, off + j) -= settings.servo.kp[j];
      jac_Ku(off + j, off + j) -= settings.servo.kd[j];
    }
    jac_N.resize(nqc, nv);
    model.rateMatrix(data, jac_N);
    jac_Ninv = jac_N.partialPivLu().inverse();
    jac_Minv.resize(nv, nv);
    model.inverseMassMatrix(data, jac_Minv);
    Eigen::Map<Eigen::MatrixXd> J(out, ny, ny);
    J.setZero();
    J.topRightCorner(nqc, nv) = jac_N;
    jac_dq.noalias() = jac_Kq * jac_Ninv;
    J.bottomLeftCorner(nv, nqc).noalias() = jac_Minv * jac_dq;
    J.bottomRightCorner(nv, nv).noalias() = jac_Minv * jac_Ku;
  }

  void rhs(double t, const double* yy, double* ydot) override {
    const double* q = yy;
    const double* uu = yy + nqc;
    if (model.hasFreeFlyer() && std::cos(q[1]) < 0.02) {
      // The base's orientation coordinates (body-fixed X-Y-Z Euler angles) are singular at a
      // pitch of 90 degrees. The base is then tilted that far: the robot has fallen over, or it
      // bends its pelvis that far with its feet down (base height tells which).
      throw std::runtime_error("base orientation at the Euler-angle singularity of the simulator's coordinates (pitch " +
                               fmt(q[1] * 180.0 / M_PI) + " deg, base height " + fmt(q[5]) +
                               " m): the base is tilted by 90 degrees (fallen over, or bent that far)");
    }
    model.setState(data, q, uu);
    evaluateForces(data, t, q, uu, false);
    model.accelerations(data, ydot + nqc);
    model.coordinateRates(data, ydot);
  }

  // Net generalized force on the robot at rest (u = 0, t = t0) at the integration coordinates
  // `coords` (Euler angles, base position, joints): gravity, contact and servo forces minus the
  // (zero) inertial terms, in model u order. Zero exactly at a static equilibrium.
  void restForce(const Eigen::VectorXd& coords, Eigen::VectorXd& f) {
    const Eigen::VectorXd zero_u = Eigen::VectorXd::Zero(nv);
    model.setState(data, coords.data(), zero_u.data());
    evaluateForces(data, t0, coords.data(), zero_u.data(), false);
    f.resize(nv);
    model.netForce(data, f.data());  // at u = 0: the applied forces
  }

  // Where the weight goes at rest in q: the contact points that carry load, the centre of mass's
  // margin to their support polygon, the servos saturated at their effort limits.
  std::string describeSupport(const model::Configuration& q) {
    Eigen::VectorXd coords(nqc);
    model.coordinates(q, coords.data());
    const Eigen::VectorXd zero_u = Eigen::VectorXd::Zero(nv);
    model.setState(data, coords.data(), zero_u.data());
    evaluateForces(data, t0, coords.data(), zero_u.data(), true);
    const model::RobotDescription& desc = model.description();
    const double weight = model.totalMass() * model.gravity().norm();
    std::vector<int> loaded(desc.contact_surfaces.size(), 0), total(desc.contact_surfaces.size(), 0);
    std::vector<Eigen::Vector2d> support;
    for (const ContactPoint& cp : contact_points) {
      ++total[static_cast<size_t>(cp.surface)];
      if (cp.force.z() > 1e-3 * weight) {
        ++loaded[static_cast<size_t>(cp.surface)];
        support.emplace_back(cp.position.x(), cp.position.y());
      }
    }
    std::string text = "loaded contact points:";
    for (size_t k = 0; k < loaded.size(); ++k) {
      text += (k ? ", " : " ") + desc.contact_surfaces[k].name + " " + std::to_string(loaded[k]) + " of " + std::to_string(total[k]);
    }
    const Eigen::Vector3d com = model.centerOfMass(data);
    const double margin = horizontalMargin(support, com.head<2>());
    text += "; the centre of mass is " + fmt(std::abs(margin) * 1000.0) + " mm " + (margin >= 0.0 ? "inside" : "OUTSIDE") +
            " the support polygon of the loaded points";
    std::string saturated;
    const Eigen::VectorXd& tau_max = model.jointTorqueLimits();
    for (int j = 0; j < nj; ++j) {
      if (std::abs(servoTorque(t0, j, coords.data(), zero_u.data())) >= tau_max[j])
        saturated += (saturated.empty() ? "" : ", ") + desc.joints[static_cast<size_t>(j)].name;
    }
    if (!saturated.empty()) text += "; servos at their effort limit (they cannot hold the posture): " + saturated;
    return text;
  }

  // Observations at the current y and tick time.
  void observe(double t) {
    const double* q = y.data();
    const double* uu = y.data() + nqc;
    model.setKinematicState(observed, q, uu);  // positions and body velocities are all it reads
    evaluateForces(observed, t, q, uu, true);
    model.configuration(q, config);
    for (int i = 0; i < nv; ++i) u[i] = uu[i];
    sensors.time_s = t;
    sensors.q = config.joints;
    sensors.qdot = u.tail(nj);
    sensors.tau = tau_work;
    // Force/torque sensors: external contact wrenches on the sensor's body.
    const BodyKinematics& d = observed.bodies();
    for (size_t s = 0; s < sensor_info.size(); ++s) {
      const SensorInfo& S = sensor_info[s];
      const Eigen::Matrix3d Rs = d.R[static_cast<size_t>(S.body)] * S.X_body_frame.linear();
      const Eigen::Vector3d ps = d.p.col(S.body) + d.R[static_cast<size_t>(S.body)] * S.X_body_frame.translation();
      Eigen::Vector3d F = Eigen::Vector3d::Zero(), T = Eigen::Vector3d::Zero();
      for (size_t i = 0; i < points.size(); ++i) {
        if (points[i].body != S.body) continue;
        F += contact_points[i].force;
        T += (contact_points[i].position - ps).cross(contact_points[i].force);
      }
      for (size_t g = 0; g < grasps.size(); ++g) {
        if (grasps[g].body != S.body || !grasps[g].active) continue;
        const Eigen::Vector3d pG = d.p.col(S.body) + d.R[static_cast<size_t>(S.body)] * grasps[g].X_body_frame.translation();
        F += grasp_world[g].force;
        T += grasp_world[g].torque + (pG - ps).cross(grasp_world[g].force);
      }
      sensors.wrenches[s].force = Rs.transpose() * F;
      sensors.wrenches[s].torque = Rs.transpose() * T;
    }
  }
};

const char* toString(IntegratorJacobian j) {
  switch (j) {
    case IntegratorJacobian::DifferenceQuotient:
      return "difference_quotient";
    case IntegratorJacobian::AppliedForces:
      return "applied_forces";
  }
  return "unknown";
}

Simulator::Simulator(const std::string& urdf_path, const std::string& data_path, SimulatorSettings settings)
    : Simulator(model::loadRobotDescription(urdf_path, data_path), std::move(settings)) {}

Simulator::Simulator(model::RobotDescription description, SimulatorSettings settings) {
  impl_ = std::make_unique<Impl>(Multibody(std::move(description)), std::move(settings));
  Impl& s = *impl_;
  const Multibody& model = s.model;
  const std::string where = "simulator settings";
  s.nj = model.numJoints();
  s.nv = model.nv();
  s.off = model.hasFreeFlyer() ? 6 : 0;
  s.nqc = model.nq();  // Euler angles + position + joints, or joints
  s.ny = s.nqc + s.nv;

  const SimulatorSettings& st = s.settings;
  if (!(st.control_period_s > 0.0)) throw InputError(where, "control period must be > 0");
  if (st.servo.kp.size() != s.nj || st.servo.kd.size() != s.nj) {
    throw InputError(where, "servo gains must have one entry per joint (" + std::to_string(s.nj) + ")");
  }
  if ((st.servo.kp.array() < 0.0).any() || (st.servo.kd.array() < 0.0).any()) {
    throw InputError(where, "servo gains must be >= 0");
  }
  const ContactSettings& c = st.contact;
  if (!(c.stiffness > 0.0) || !(c.exponent >= 1.0) || !(c.dissipation_s_per_m >= 0.0) || !(c.slip_velocity_m_per_s > 0.0)) {
    throw InputError(where, "contact: expected stiffness > 0, exponent >= 1, dissipation >= 0, slip velocity > 0");
  }
  s.mu = c.friction_coefficient >= 0.0 ? c.friction_coefficient : model.description().friction_coefficient;

  const model::RobotDescription& desc = model.description();
  for (size_t si = 0; si < desc.contact_surfaces.size(); ++si) {
    const auto& surf = desc.contact_surfaces[si];
    const auto& F = desc.frames[static_cast<size_t>(surf.frame)];
    for (const auto& p : surf.points) {
      PointInfo P;
      P.surface = static_cast<int>(si);
      P.body = F.link;
      P.r_body = F.placement * p;
      P.radius = surf.radius;
      s.points.push_back(P);
    }
  }
  if (!s.points.empty() && !(s.mu > 0.0)) throw InputError(where, "contact: friction coefficient must be > 0");
  for (const GraspSettings& g : st.grasps) {
    GraspState G;
    G.settings = g;
    const model::FrameId f = model.frameId(g.frame);
    G.body = desc.frames[static_cast<size_t>(f)].link;
    G.X_body_frame = desc.frames[static_cast<size_t>(f)].placement;
    for (const auto& o : s.grasps) {
      if (o.settings.name == g.name) throw InputError(where, "duplicate grasp name '" + g.name + "'");
    }
    s.grasps.push_back(G);
  }
  for (const auto& fs : desc.force_sensors) {
    SensorInfo S;
    S.body = desc.frames[static_cast<size_t>(fs.frame)].link;
    S.X_body_frame = desc.frames[static_cast<size_t>(fs.frame)].placement;
    s.sensor_info.push_back(S);
  }

  s.y.assign(static_cast<size_t>(s.ny), 0.0);
  s.q0 = s.q1 = Eigen::VectorXd::Zero(s.nj);
  s.qd0 = s.qd1 = s.tau0 = s.tau1 = Eigen::VectorXd::Zero(s.nj);
  s.config = model.neutralConfiguration();
  s.u = Eigen::VectorXd::Zero(s.nv);
  s.contact_points.assign(s.points.size(), ContactPoint());
  s.grasp_world.assign(s.grasps.size(), Wrench());
  s.tau_work = Eigen::VectorXd::Zero(s.nj);
  s.sensors.wrenches.assign(s.sensor_info.size(), Wrench());

  CvodeSettings cs;
  const IntegratorSettings& is = st.integrator;
  if (!(is.rtol > 0.0) || !(is.atol_position > 0.0) || !(is.atol_velocity > 0.0) || is.max_order < 1 || is.max_order > 5 ||
      is.max_steps_per_tick < 1 || is.max_step_s < 0.0) {
    throw InputError(where, "integrator: expected rtol, atol > 0, max_order in 1..5, max_steps_per_tick >= 1");
  }
  cs.rtol = is.rtol;
  cs.atol.assign(static_cast<size_t>(s.ny), is.atol_velocity);
  for (int i = 0; i < s.nqc; ++i) cs.atol[static_cast<size_t>(i)] = is.atol_position;
  cs.max_order = is.max_order;
  cs.max_steps = is.max_steps_per_tick;
  cs.max_step = is.max_step_s;
  cs.kinematic_block = s.nqc;  // q = [Euler angles, base position, joints]: qdot = N(q) u
  cs.linear_solver = is.linear_solver;
  if (is.jacobian == IntegratorJacobian::AppliedForces) {
    if (s.nqc != s.nv) throw InputError(where, "integrator: the applied_forces Jacobian needs as many coordinates as speeds");
    cs.jacobian = JacobianSource::System;
  }
  s.cvode = std::make_unique<CvodeIntegrator>(s, cs);
}

Simulator::~Simulator() = default;

const Multibody& Simulator::model() const { return impl_->model; }
const SimulatorSettings& Simulator::settings() const { return impl_->settings; }

model::Configuration Simulator::placeOnGround(const Eigen::VectorXd& joints, const Eigen::Matrix3d& base_rotation,
                                              const Eigen::Vector2d& base_xy) const {
  const Impl& s = *impl_;
  model::Configuration q = s.model.neutralConfiguration();
  q.joints = joints;
  q.base_rotation = base_rotation;
  q.base_position = Eigen::Vector3d(base_xy.x(), base_xy.y(), 0.0);
  if (s.points.empty() || !s.model.hasFreeFlyer()) return q;
  MultibodyState state = s.model.createState();
  std::vector<double> coords(static_cast<size_t>(s.nqc));
  s.model.coordinates(q, coords.data());
  const Eigen::VectorXd zero_u = Eigen::VectorXd::Zero(s.nv);
  s.model.setState(state, coords.data(), zero_u.data());
  const BodyKinematics& d = state.bodies();
  double zmin = std::numeric_limits<double>::infinity();
  for (const PointInfo& P : s.points) {
    zmin = std::min(zmin, (d.p.col(P.body) + d.R[static_cast<size_t>(P.body)] * P.r_body).z() - P.radius);
  }
  const ContactSettings& c = s.settings.contact;
  const double weight = s.model.totalMass() * s.model.gravity().norm();
  const double share = weight / static_cast<double>(s.points.size());
  const double penetration = std::pow(share / c.stiffness, 1.0 / c.exponent);
  q.base_position.z() = c.ground_height_m - zmin - penetration;
  return q;
}

const char* toString(Settle s) {
  switch (s) {
    case Settle::StaticEquilibrium:
      return "static_equilibrium";
    case Settle::BaseOnly:
      return "base_only";
    case Settle::None:
      return "none";
  }
  return "?";
}

RestingState Simulator::restingState(const Eigen::VectorXd& joints, Settle settle, double base_yaw_rad, const Eigen::Vector2d& base_xy) {
  Impl& s = *impl_;
  const std::string where = "initial state";
  if (joints.size() != s.nj) throw InputError(where, "the posture must have one entry per joint (" + std::to_string(s.nj) + ")");
  const bool ff = s.model.hasFreeFlyer();
  if (settle == Settle::BaseOnly && !ff) throw InputError(where, "settle base_only needs a free-flyer base");
  if (settle != Settle::None && ff && s.points.empty()) {
    throw InputError(where, "a floating robot without contact points has no static equilibrium (use settle none)");
  }
  // The servo holds `joints` at rest; grasps are off (switched on later, they anchor where the
  // frame is and start without force).
  const Eigen::VectorXd saved[6] = {s.q0, s.qd0, s.tau0, s.q1, s.qd1, s.tau1};
  const double saved_t0 = s.t0;
  std::vector<bool> saved_grasps;
  for (auto& g : s.grasps) {
    saved_grasps.push_back(g.active);
    g.active = false;
  }
  s.q0 = s.q1 = joints;
  s.qd0 = s.qd1 = s.tau0 = s.tau1 = Eigen::VectorXd::Zero(s.nj);
  s.t0 = 0.0;

  const Eigen::Matrix3d R_yaw = Eigen::AngleAxisd(base_yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  RestingState out;
  out.settle = settle;
  out.q = placeOnGround(joints, R_yaw, base_xy);
  const bool solve_base = ff && settle != Settle::None;
  // The first guess of the base's roll and pitch: the contact surfaces level (their normals, the
  // frames' z, averaged over the points, vertical). A posture that tilts the soles a few degrees
  // (an ankle a little off) then starts flat on them, not balanced on an edge. A tilt below
  // 1e-6 rad is left alone (the guess stays exactly level).
  double roll0 = 0.0, pitch0 = 0.0;
  if (solve_base && !s.points.empty()) {
    MultibodyState state = s.model.createState();
    std::vector<double> coords(static_cast<size_t>(s.nqc));
    s.model.coordinates(out.q, coords.data());
    const Eigen::VectorXd zero_u = Eigen::VectorXd::Zero(s.nv);
    s.model.setState(state, coords.data(), zero_u.data());
    const model::RobotDescription& desc = s.model.description();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (const auto& surf : desc.contact_surfaces) {
      const auto& F = desc.frames[static_cast<size_t>(surf.frame)];
      normal += static_cast<double>(surf.points.size()) * (state.bodies().R[static_cast<size_t>(F.link)] * F.placement.linear().col(2));
    }
    if (normal.norm() > 0.0 && std::acos(std::clamp(normal.normalized().z(), -1.0, 1.0)) > 1e-6) {
      const Eigen::Matrix3d C = Eigen::Quaterniond::FromTwoVectors(normal.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const Eigen::Matrix3d M = R_yaw.transpose() * C * R_yaw;  // ~ Ry(pitch) Rx(roll) in the heading's axes
      pitch0 = std::asin(std::clamp(-M(2, 0), -1.0, 1.0));
      roll0 = std::atan2(M(2, 1), M(2, 2));
      if (std::abs(pitch0) <= 0.5 && std::abs(roll0) <= 0.5) {
        out.q = placeOnGround(joints,
                              R_yaw * Eigen::AngleAxisd(pitch0, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                                  Eigen::AngleAxisd(roll0, Eigen::Vector3d::UnitX()).toRotationMatrix(),
                              base_xy);
      } else {
        roll0 = pitch0 = 0.0;  // surfaces far from level: not a stance to start from
      }
    }
  }

  // Unknowns x: [roll, pitch, z] of the base (free-flyer; R = Rz(yaw) Ry(pitch) Rx(roll), x and
  // y kept) then, with StaticEquilibrium, the joints. Equations, each (nearly) conjugate to its
  // unknown: the net moment about the base origin along the heading's x and y axes, the net
  // vertical force, the joints' net torques. The other components (horizontal force, yaw
  // moment) vanish at rest: vertical normal forces and gravity have none, and friction is zero
  // at zero slip velocity.
  const bool solve_joints = settle == Settle::StaticEquilibrium;
  const int n = (solve_base ? 3 : 0) + (solve_joints ? s.nj : 0);
  Eigen::VectorXd x(n);
  if (solve_base) x.head(3) << roll0, pitch0, out.q.base_position.z();
  if (solve_joints) x.tail(s.nj) = joints;

  auto configuration = [&](const Eigen::VectorXd& xx) {
    model::Configuration q = out.q;
    if (solve_base) {
      q.base_rotation = R_yaw * Eigen::AngleAxisd(xx[1], Eigen::Vector3d::UnitY()).toRotationMatrix() *
                        Eigen::AngleAxisd(xx[0], Eigen::Vector3d::UnitX()).toRotationMatrix();
      q.base_position.z() = xx[2];
    }
    if (solve_joints) q.joints = xx.tail(s.nj);
    return q;
  };
  Eigen::VectorXd coords(s.nqc), f(s.nv);
  auto force = [&](const model::Configuration& q, Eigen::VectorXd& ff_out) {
    s.model.coordinates(q, coords.data());
    s.restForce(coords, ff_out);
  };
  // The residual the Newton iteration zeroes. With `conjugate`, the base's moments are taken along
  // the axes roll and pitch turn about (R_yaw Ry(pitch) x and R_yaw y: the generalized forces
  // conjugate to them), so that the stiffness -dr/dx is the Hessian of the potential energy at an
  // equilibrium (symmetric) and its eigenvalues tell a stable start from an unstable one; the
  // iteration itself takes them along the heading's x and y (the same equilibria).
  auto residualOf = [&](const Eigen::VectorXd& xx, Eigen::VectorXd& r, bool conjugate) {
    force(configuration(xx), f);
    r.resize(n);
    int i = 0;
    if (solve_base) {
      const Eigen::Vector3d roll_axis =
          conjugate
              ? Eigen::Vector3d(R_yaw * Eigen::AngleAxisd(xx[1], Eigen::Vector3d::UnitY()).toRotationMatrix() * Eigen::Vector3d::UnitX())
              : Eigen::Vector3d(R_yaw * Eigen::Vector3d::UnitX());
      const Eigen::Vector3d pitch_axis = R_yaw * Eigen::Vector3d::UnitY();
      r[i++] = roll_axis.dot(f.head<3>());
      r[i++] = pitch_axis.dot(f.head<3>());
      r[i++] = f[5];
    }
    if (solve_joints) r.tail(s.nj) = f.tail(s.nj);
  };
  auto residual = [&](const Eigen::VectorXd& xx, Eigen::VectorXd& r) { residualOf(xx, r, false); };
  // Tolerance: 1e-9 of the weight, at least 1e-9 (N; N m for moments and joint torques).
  const double weight = s.model.totalMass() * s.model.gravity().norm();
  const double tol = 1e-9 * std::max(weight, 1.0);
  auto summarize = [&](const model::Configuration& q) {
    force(q, f);
    out.net_force_N = ff ? f.segment(3, 3).norm() : 0.0;
    out.net_moment_Nm = ff ? f.head(3).norm() : 0.0;
    out.joint_residual_Nm = s.nj > 0 ? f.tail(s.nj).cwiseAbs().maxCoeff() : 0.0;
  };
  auto converged = [&] { return out.net_force_N <= tol && out.net_moment_Nm <= tol && (!solve_joints || out.joint_residual_Nm <= tol); };
  // The largest components of a mode of x, named (base roll, pitch, height; joints).
  auto describeMode = [&](const Eigen::VectorXd& v, bool base, bool with_joints) {
    std::vector<std::pair<double, std::string>> parts;
    int i = 0;
    if (base) {
      parts.emplace_back(v[0], "base roll");
      parts.emplace_back(v[1], "base pitch");
      parts.emplace_back(v[2], "base height");
      i = 3;
    }
    if (with_joints) {
      for (int j = 0; j < s.nj; ++j) parts.emplace_back(v[i + j], "joint " + s.model.description().joints[static_cast<size_t>(j)].name);
    }
    std::stable_sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return std::abs(a.first) > std::abs(b.first); });
    std::string text;
    for (size_t k = 0; k < parts.size() && k < 4; ++k) {
      if (k > 0 && std::abs(parts[k].first) < 0.1) break;
      text += (k ? ", " : "") + parts[k].second + " " + fmt(parts[k].first);
    }
    return text + " (unit vector of rad and m)";
  };

  if (n > 0) {
    const int max_iterations = 50;
    const double h = 1e-6;  // finite-difference step (m, rad)
    const double max_tilt_rad = 0.5;
    Eigen::VectorXd r(n), rp(n), rm(n), dx(n), x_try(n), r_try(n);
    Eigen::MatrixXd J(n, n);
    auto jacobianOf = [&](bool conjugate) {  // central differences
      for (int c = 0; c < n; ++c) {
        Eigen::VectorXd xc = x;
        xc[c] = x[c] + h;
        residualOf(xc, rp, conjugate);
        xc[c] = x[c] - h;
        residualOf(xc, rm, conjugate);
        J.col(c) = (rp - rm) / (2.0 * h);
      }
    };
    auto jacobian = [&] { jacobianOf(false); };
    residual(x, r);
    std::string failure;
    for (;;) {
      summarize(configuration(x));
      if (converged()) {
        // Only a stable equilibrium is a start: the stiffness -dr/dx (symmetric for these
        // conservative forces and conjugate unknowns) must have no negative eigenvalue, e.g. not
        // balanced on an edge of a sole. Its inertia does not depend on the units of x.
        jacobianOf(true);
        const Eigen::MatrixXd K = -0.5 * (J + J.transpose());
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
        const double lo = es.eigenvalues()[0], hi = es.eigenvalues()[n - 1];
        if (lo < -1e-6 * std::abs(hi)) {
          failure = "the equilibrium found is unstable (stiffness eigenvalue " + fmt(lo) +
                    " < 0: the robot would fall; the unstable mode is " + describeMode(es.eigenvectors().col(0), solve_base, solve_joints) +
                    ")";
        }
        break;
      }
      if (out.iterations >= max_iterations) {
        failure = "no convergence in " + std::to_string(max_iterations) + " Newton iterations";
        break;
      }
      ++out.iterations;
      jacobian();
      const Eigen::FullPivLU<Eigen::MatrixXd> lu(J);
      if (lu.rank() < n) {
        failure = "singular Jacobian (the contact points cannot carry the load in this pose)";
        break;
      }
      dx = lu.solve(-r);
      // Damped step: at most 5 mm in height, 0.05 rad in any angle, then backtracking on |r|.
      double scale = 1.0;
      for (int c = 0; c < n; ++c) {
        const double cap = (solve_base && c == 2) ? 0.005 : 0.05;
        if (std::abs(dx[c]) * scale > cap) scale = cap / std::abs(dx[c]);
      }
      dx *= scale;
      bool accepted = false;
      for (double alpha = 1.0; alpha > 1e-6; alpha *= 0.5) {
        x_try = x + alpha * dx;
        residual(x_try, r_try);
        if (r_try.norm() < (1.0 - 1e-4 * alpha) * r.norm()) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        failure = "the Newton step does not reduce the imbalance (no equilibrium near this pose)";
        break;
      }
      x = x_try;
      r = r_try;
      if (solve_base && (std::abs(x[0]) > max_tilt_rad || std::abs(x[1]) > max_tilt_rad)) {
        failure = "the base tilts beyond " + fmt(max_tilt_rad) + " rad (roll " + fmt(x[0]) + ", pitch " + fmt(x[1]) + ")";
        summarize(configuration(x));
        break;
      }
    }
    out.q = configuration(x);
    out.converged = failure.empty();
    if (!out.converged) {
      out.message = "no stable static equilibrium found (" + std::string(toString(settle)) + "): " + failure + " after " +
                    std::to_string(out.iterations) + " iterations; left: net force " + fmt(out.net_force_N) + " N, net moment " +
                    fmt(out.net_moment_Nm) + " N m" +
                    (solve_joints ? ", joint torque " + fmt(out.joint_residual_Nm) + " N m" : std::string()) + " (tolerance " + fmt(tol) +
                    ")" + (ff ? "; " + s.describeSupport(out.q) : std::string());
    }
  } else {
    summarize(out.q);
  }
  s.q0 = saved[0];
  s.qd0 = saved[1];
  s.tau0 = saved[2];
  s.q1 = saved[3];
  s.qd1 = saved[4];
  s.tau1 = saved[5];
  s.t0 = saved_t0;
  for (size_t g = 0; g < s.grasps.size(); ++g) s.grasps[g].active = saved_grasps[g];
  return out;
}

void Simulator::reset(const model::Configuration& q, const Eigen::VectorXd& u, const JointCommand* initial_command) {
  Impl& s = *impl_;
  if (q.joints.size() != s.nj || u.size() != s.nv) throw InputError("simulator reset", "state has the wrong size");
  s.model.coordinates(q, s.y.data());
  for (int k = 0; k < s.nv; ++k) s.y[static_cast<size_t>(s.nqc + k)] = u[k];
  if (initial_command) {
    if (initial_command->q.size() != s.nj || initial_command->qdot.size() != s.nj || initial_command->tau_ff.size() != s.nj) {
      throw InputError("simulator reset", "initial command vectors must have one entry per joint");
    }
    s.q1 = initial_command->q;
    s.qd1 = initial_command->qdot;
    s.tau1 = initial_command->tau_ff;
  } else {
    s.q1 = q.joints;
    s.qd1 = u.tail(s.nj);
    s.tau1.setZero();
  }
  s.q0 = s.q1;
  s.qd0 = s.qd1;
  s.tau0 = s.tau1;
  s.restart_pending = false;
  s.k = 0;
  s.restarts = 0;
  s.before_restart = CvodeStats();
  s.t0 = 0.0;
  s.failed = false;
  s.failure = StepResult();
  for (auto& g : s.grasps) g.active = false;
  s.cvode->initialize(0.0, s.y.data());
  s.observe(0.0);
  for (size_t g = 0; g < s.grasps.size(); ++g) {
    if (s.grasps[g].settings.initially_active) setGraspActive(static_cast<int>(g), true);
  }
  s.observe(0.0);
}

StepResult Simulator::step(const JointCommand& cmd) {
  Impl& s = *impl_;
  if (s.failed) return s.failure;
  if (cmd.q.size() != s.nj || cmd.qdot.size() != s.nj || cmd.tau_ff.size() != s.nj) {
    throw InputError("simulator step", "command vectors must have one entry per joint");
  }
  s.q0 = s.q1;
  s.qd0 = s.qd1;
  s.tau0 = s.tau1;
  s.q1 = cmd.q;
  s.qd1 = cmd.qdot;
  s.tau1 = cmd.tau_ff;
  const double T = s.period();
  s.t0 = static_cast<double>(s.k) * T;
  const double t1 = static_cast<double>(s.k + 1) * T;
  // A step set-point or a switched grasp makes the right-hand side jump at this tick: restart
  // the integrator there instead of letting its history straddle the discontinuity.
  if (s.restart_pending || (s.settings.servo.profile == SetpointProfile::Step && s.k > 0)) {
    s.accumulate(s.cvode->stats());  // CVodeReInit resets CVODE's counters
    s.cvode->initialize(s.t0, s.y.data());
    ++s.restarts;
  }
  s.restart_pending = false;
  const CvodeStatus st = s.cvode->advance(t1, s.y.data());
  if (st != CvodeStatus::Success) {
    s.failed = true;
    s.failure.ok = false;
    s.failure.status = st;
    s.failure.message = s.cvode->message();
    s.observe(s.cvode->time());
    return s.failure;
  }
  ++s.k;
  s.observe(t1);
  return StepResult();
}

void Simulator::setGraspActive(int grasp, bool active) {
  Impl& s = *impl_;
  LEXDYN_ALWAYS_ASSERT(grasp >= 0 && grasp < static_cast<int>(s.grasps.size()), "grasp index out of range");
  GraspState& G = s.grasps[static_cast<size_t>(grasp)];
  if (active && !G.active) {
    const Eigen::Isometry3d X = s.model.bodyPlacement(s.observed, G.body) * G.X_body_frame;
    G.R_anchor = X.linear();
    G.p_anchor = X.translation();
  }
  if (G.active != active) s.restart_pending = true;
  G.active = active;
}

bool Simulator::graspActive(int grasp) const { return impl_->grasps.at(static_cast<size_t>(grasp)).active; }

int Simulator::graspIndex(const std::string& name) const {
  for (size_t g = 0; g < impl_->grasps.size(); ++g) {
    if (impl_->grasps[g].settings.name == name) return static_cast<int>(g);
  }
  throw InputError("simulator settings", "unknown grasp '" + name + "'");
}

double Simulator::time() const { return impl_->sensors.time_s; }
long Simulator::tick() const { return impl_->k; }
const SensorReadings& Simulator::sensors() const { return impl_->sensors; }
const model::Configuration& Simulator::configuration() const { return impl_->config; }
const Eigen::VectorXd& Simulator::velocity() const { return impl_->u; }
const std::vector<ContactPoint>& Simulator::contactPoints() const { return impl_->contact_points; }
double Simulator::surfaceNormalForce(int surface) const {
  double fz = 0.0;
  for (const ContactPoint& p : impl_->contact_points) {
    if (p.surface == surface) fz += p.force.z();
  }
  return fz;
}
const MultibodyState& Simulator::data() const { return impl_->observed; }
const Eigen::VectorXd& Simulator::commandedPosition() const { return impl_->q1; }
Wrench Simulator::graspWrenchWorld(int grasp) const { return impl_->grasp_world.at(static_cast<size_t>(grasp)); }
CvodeStats Simulator::integratorStats() const {
  CvodeStats s = impl_->cvode->stats();
  addCounters(s, impl_->before_restart);
  return s;
}
int Simulator::stateSize() const { return impl_->ny; }

std::vector<double> Simulator::integratedState() const { return impl_->y; }

void Simulator::rightHandSide(double t, const std::vector<double>& y, std::vector<double>& ydot) {
  Impl& s = *impl_;
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(y.size()) == s.ny, "rightHandSide: y must have stateSize() entries");
  ydot.resize(static_cast<size_t>(s.ny));
  s.rhs(t, y.data(), ydot.data());
}

void Simulator::appliedForcesJacobian(double t, const std::vector<double>& y, Eigen::MatrixXd& J) {
  Impl& s = *impl_;
  LEXDYN_ALWAYS_ASSERT(static_cast<int>(y.size()) == s.ny, "appliedForcesJacobian: y must have stateSize() entries");
  J.resize(s.ny, s.ny);
  s.jacobian(t, y.data(), nullptr, J.data());
}
long Simulator::integratorRestarts() const { return impl_->restarts; }

}  // namespace lexdyn::sim
