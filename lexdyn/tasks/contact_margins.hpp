// Contact safety margins of the plan (docs/controller.md, "Contact margins"): the contact-wrench
// constraints of a friction contact tightened so that the plan keeps a reserve the robot can
// spend (the simulated or real wrench always goes a little beyond the plan).
//   - friction: the pyramid's coefficient is (1 - friction) mu;
//   - cop_m: the points are moved inward so that the plan's centre of pressure stays cop_m from
//     every edge of the contact's support polygon (the points' convex hull in the contact plane);
//   - min_normal_N: every point of an active contact pushes with at least this normal force.
// Fixed (grasp) contacts have no sign bound and take no margin.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace lexdyn::tasks {

struct ContactSpec;

struct ContactMargins {
  double friction = 0.0;      ///< fraction of the friction coefficient held in reserve, [0, 1)
  double cop_m = 0.0;         ///< distance of the plan's CoP to the support polygon's edges, m
  double min_normal_N = 0.0;  ///< minimum normal force of each point, N
};

/// The contact as the plan sees it: the spec's points, friction and minimum normal force with the
/// margins applied. Returns the problems with the margins (empty when they fit the contact): a
/// negative or non-finite value, a friction margin of 1 or more, a CoP margin that leaves no
/// support polygon.
std::vector<std::string> applyContactMargins(ContactSpec& spec, const ContactMargins& margins);

/// The points moved inward by `distance` in the plane orthogonal to `normal`: the vertices of
/// their convex hull onto the hull offset inward by `distance`, other points radially toward the
/// offset hull's centroid until inside it. One point: unchanged. Two or more collinear points:
/// the segment's ends moved toward each other. Returns false (points unchanged) when the offset
/// hull would vanish or turn over; `room` then holds the largest distance that fits (m).
bool shrinkSupport(std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& normal, double distance, double& room);

}  // namespace lexdyn::tasks
