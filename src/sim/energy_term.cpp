#include "sflsh/sim/energy_term.hpp"

#include <optional>

#include "sflsh/core/error.hpp"

namespace sflsh {

void TermCache::restore_state(const std::vector<double>& values, const std::string& where) {
  require(values.empty(), where, ": this term's cache carries no state, the checkpoint gives it ", values.size(),
          " values");
}

double EnergyTerm::evaluate(const StepContext& ctx, const Configuration& q, VecX* grad, MatX* hess) const {
  if (!grad && !hess) return compute(ctx, q, nullptr, nullptr);
  // Views of the whole caller-sized vectors: the term's local system.
  std::optional<VecRef> g;
  std::optional<MatRef> H;
  if (grad) g.emplace(*grad);
  if (hess) H.emplace(*hess);
  return compute(ctx, q, g ? &*g : nullptr, H ? &*H : nullptr);
}

std::unique_ptr<TermCache> begin_term_step(const EnergyTerm& term, StepContext& ctx) {
  std::unique_ptr<TermCache> cache = term.make_cache();
  ctx.cache = cache.get();
  term.begin_step(ctx);
  return cache;
}

}  // namespace sflsh
