#include "sflsh/sim/energies/scaled_term.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {

ScaledTerm::ScaledTerm(std::shared_ptr<const EnergyTerm> inner, double scale)
    : inner_(std::move(inner)), scale_(scale) {
  require(inner_ != nullptr, "ScaledTerm: no inner term");
  require(std::isfinite(scale) && scale > 0, "ScaledTerm '", inner_->name(), "': scale ", scale,
          ", expected a finite value > 0");
}

double ScaledTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  if (!grad && !hess) return scale_ * inner_->compute(ctx, q, nullptr, nullptr);
  // The inner term adds into its own zeroed buffers (per thread: groups step in parallel).
  thread_local VecX g;
  thread_local MatX H;
  if (grad) g.setZero(grad->size());
  if (hess) H.setZero(hess->rows(), hess->cols());
  VecRef gv(g);
  MatRef Hv(H);
  const double e = inner_->compute(ctx, q, grad ? &gv : nullptr, hess ? &Hv : nullptr);
  if (grad) *grad += scale_ * g;
  if (hess) *hess += scale_ * H;
  return scale_ * e;
}

}  // namespace sflsh
