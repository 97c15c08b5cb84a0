#include "lexdyn/tasks/contact_jacobian.hpp"

#include "lexdyn/common/error.hpp"

namespace lexdyn::tasks {

bool contactActive(const TickContext& ctx, int c) {
  LEXDYN_ALWAYS_ASSERT(ctx.contact_active != nullptr && static_cast<int>(ctx.contact_active->size()) > c,
                       "TickContext::contact_active must hold one flag per contact");
  return (*ctx.contact_active)[static_cast<size_t>(c)] != 0;
}

void contactJacobianTranspose(const TickContext& ctx, Eigen::Ref<Eigen::MatrixXd> Jp, Eigen::Ref<Eigen::MatrixXd> JcT,
                              std::vector<Eigen::MatrixXd>* point_jacobians) {
  const ContactLayout& layout = *ctx.contacts;
  const model::RobotModel& model = *ctx.model;
  const int nv = layout.nv();
  LEXDYN_ALWAYS_ASSERT(JcT.rows() == nv && JcT.cols() == layout.ng() && Jp.rows() == 3 && Jp.cols() == nv,
                       "contactJacobianTranspose: workspace sizes");
  LEXDYN_ALWAYS_ASSERT(point_jacobians == nullptr || static_cast<int>(point_jacobians->size()) == layout.ng() / 4,
                       "contactJacobianTranspose: one point Jacobian per contact point");
  Eigen::Matrix<double, 3, 4> D;
  for (int c = 0; c < layout.count(); ++c) {
    const ContactSpec& spec = layout.contact(c);
    const int np = static_cast<int>(spec.points.size());
    auto block = JcT.middleCols(layout.offset(c), 4 * np);
    if (!contactActive(ctx, c)) {
      block.setZero();
      continue;
    }
    const Eigen::Matrix3d R = model.framePlacement(*ctx.data, spec.frame).linear();
    ContactLayout::generators(spec, R, D);
    for (int p = 0; p < np; ++p) {
      // The point's Jacobian, kept for the caller when asked.
      const size_t point = static_cast<size_t>(layout.offset(c) / 4 + p);
      Eigen::Ref<Eigen::MatrixXd> J = point_jacobians ? Eigen::Ref<Eigen::MatrixXd>((*point_jacobians)[point]) : Jp;
      model.pointJacobian(*ctx.data, spec.frame, spec.points[static_cast<size_t>(p)], J);
      // Column k of J_p^T D_p: sum_r J_p(r, :)^T D_p(r, k), written coefficient-wise.
      for (int g = 0; g < 4; ++g) {
        auto col = block.col(4 * p + g);
        for (int i = 0; i < nv; ++i) col[i] = J(0, i) * D(0, g) + J(1, i) * D(1, g) + J(2, i) * D(2, g);
      }
    }
  }
}

}  // namespace lexdyn::tasks
