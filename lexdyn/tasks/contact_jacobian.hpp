// The contact part of the equation of motion: Jc^T gamma = sum_points J_p^T D_p gamma_p
// (docs/controller.md, "Decision variables"), shared by equation_of_motion and torque_limits.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

/// Fills JcT (nv x ng): column offset(c) + 4 p + g is J_p^T D_p e_g for contact c, point p,
/// generator g, where J_p is the point's 3 x nv Jacobian and D_p = ContactLayout::generators()
/// at the contact frame's current rotation. Columns of inactive contacts are zero, so an
/// inactive contact exerts no force whatever its variables. Jp is a 3 x nv workspace.
/// point_jacobians, when given (one 3 x nv matrix per point of the layout, point p of contact c
/// at offset(c) / 4 + p), receives J_p of every point of the active contacts; the others are
/// left as they were. Allocation-free. Requires ctx.model, ctx.data, ctx.contacts,
/// ctx.contact_active.
void contactJacobianTranspose(const TickContext& ctx, Eigen::Ref<Eigen::MatrixXd> Jp, Eigen::Ref<Eigen::MatrixXd> JcT,
                              std::vector<Eigen::MatrixXd>* point_jacobians = nullptr);

/// True when contact c is active at this tick (ctx.contact_active is required when the layout
/// has contacts).
bool contactActive(const TickContext& ctx, int c);

}  // namespace lexdyn::tasks
