#include "sflsh/sim/energies/damping.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

DampingTerm::DampingTerm(const Avatar& avatar, const ElasticTerm& elastic, double beta) : beta_(beta) {
  require(beta >= 0, "DampingTerm: beta = ", beta, " s, expected >= 0");
  StepContext ctx;
  ctx.avatar = &avatar;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = avatar.num_reduced();
  Configuration rest;
  rest.z = VecX::Zero(avatar.num_reduced());
  K0_ = MatX::Zero(avatar.num_reduced(), avatar.num_reduced());
  VecX g = VecX::Zero(avatar.num_reduced());
  elastic.evaluate(ctx, rest, &g, &K0_);
}

double DampingTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  if (beta_ == 0) return 0;
  const VecX dz = q.z - ctx.q_prev.z;
  const double c = beta_ / ctx.h;
  const VecX Kdz = K0_ * dz;
  const int z0 = ctx.layout.z_offset(), r = ctx.layout.num_reduced;
  if (grad) grad->segment(z0, r) += c * Kdz;
  if (hess) hess->block(z0, z0, r, r) += c * K0_;
  return 0.5 * c * dz.dot(Kdz);
}

}  // namespace sflsh
