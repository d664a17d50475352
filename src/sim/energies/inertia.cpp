#include "sflsh/sim/energies/inertia.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/point_hessian.hpp"

namespace sflsh {

VecX cubature_masses(const Avatar& avatar, const Cubature& cubature) {
  VecX m(cubature.size());
  for (int s = 0; s < cubature.size(); ++s) m[s] = tet_material(avatar, cubature.elements[s]).density * cubature.weights[s];
  return m;
}

InertiaTerm::InertiaTerm(const Avatar& avatar)
    : points_(PosedPoints::at_cubature(avatar, avatar.inertia)), mass_(cubature_masses(avatar, avatar.inertia)) {}

namespace {

/// The explicit prediction x* of the current step.
struct InertiaCache : TermCache {
  Points x_predicted;  // #S by 3, world (m, step frame)
};

}  // namespace

std::unique_ptr<TermCache> InertiaTerm::make_cache() const { return std::make_unique<InertiaCache>(); }

void InertiaTerm::begin_step(const StepContext& ctx) const {
  auto* cache = dynamic_cast<InertiaCache*>(ctx.cache);
  require(cache != nullptr, "InertiaTerm::begin_step: the context carries no inertia cache (see begin_term_step)");
  cache->x_predicted = 2.0 * points_.world(ctx.q_prev) - points_.world(ctx.q_prev2);
}

double InertiaTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const auto* cache = dynamic_cast<const InertiaCache*>(ctx.cache);
  require(cache != nullptr && cache->x_predicted.rows() == points_.size(),
          "InertiaTerm::compute called before begin_step");
  const double inv_h2 = 1.0 / (ctx.h * ctx.h);
  const Points dx = points_.world(q) - cache->x_predicted;
  double E = 0;
  for (int s = 0; s < points_.size(); ++s) E += 0.5 * inv_h2 * mass_[s] * dx.row(s).squaredNorm();
  if (grad) {
    const Points f = (inv_h2 * mass_).asDiagonal() * dx;  // ∂E/∂x_s
    points_.add_jacobian_transpose(q, ctx.layout, f, *grad);
  }
  if (hess) {
    // Gauss–Newton (1/h²) Jᵀ M J. Points touch few DoFs when the basis is sparse:
    // then per-point products scattered into H are cheaper than one dense
    // update Ĵᵀ Ĵ (rows of J scaled by √m_s / h) over all DoFs.
    const int n = ctx.layout.size();
    double local_cost = 0;
    for (int s = 0; s < points_.size(); ++s) local_cost += std::pow(points_.local_size(s, ctx.layout), 2);
    if (local_cost < 0.3 * double(points_.size()) * n * n) {
      for (int s = 0; s < points_.size(); ++s) add_point_hessian(points_, s, q, ctx.layout, inv_h2 * mass_[s], *hess);
    } else {
      MatX J;
      points_.jacobian(q, ctx.layout, J, (mass_ * inv_h2).cwiseSqrt());
      hess->selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
      hess->triangularView<Eigen::StrictlyUpper>() = hess->transpose();
    }
  }
  return E;
}

}  // namespace sflsh
