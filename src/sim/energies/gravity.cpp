#include "sflsh/sim/energies/gravity.hpp"

#include "sflsh/sim/energies/inertia.hpp"

namespace sflsh {

GravityTerm::GravityTerm(const Avatar& avatar)
    : points_(PosedPoints::at_cubature(avatar, avatar.inertia)), mass_(cubature_masses(avatar, avatar.inertia)) {}

double GravityTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const Points x = points_.world(q);
  const double E = -mass_.dot(x * ctx.gravity);
  if (grad) {
    Points f(points_.size(), 3);  // ∂E/∂x_s = −m_s g
    for (int s = 0; s < points_.size(); ++s) f.row(s) = -mass_[s] * ctx.gravity.transpose();
    points_.add_jacobian_transpose(q, ctx.layout, f, *grad);
  }
  return E;
}

}  // namespace sflsh
