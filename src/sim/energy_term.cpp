#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

double EnergyTerm::evaluate(const StepContext& ctx, const Configuration& q, VecX* grad, MatX* hess) const {
  if (!grad && !hess) return compute(ctx, q, nullptr, nullptr);
  // Views of the whole caller-sized vectors: the term's local system.
  std::unique_ptr<VecRef> g = grad ? std::make_unique<VecRef>(*grad) : nullptr;
  std::unique_ptr<MatRef> H = hess ? std::make_unique<MatRef>(*hess) : nullptr;
  return compute(ctx, q, g.get(), H.get());
}

std::unique_ptr<TermCache> begin_term_step(const EnergyTerm& term, StepContext& ctx) {
  std::unique_ptr<TermCache> cache = term.make_cache();
  ctx.cache = cache.get();
  term.begin_step(ctx);
  return cache;
}

}  // namespace sflsh
