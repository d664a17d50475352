#pragma once
// A term whose energy, gradient and Hessian are `scale` times another's: how a
// body's soft tissue is made stiffer or softer without rebuilding its terms.
// Scaling every Young's modulus and the Fung c of a material by s (Poisson's
// ratio kept) scales its StVK stiffness C, c and the barrier's κ (∝ Young) by
// s, and Ψ = (sc/2)(exp(2 sΨ_stvk / (sc)) − 1) + s Ψ_vol = s Ψ: the elastic
// energy, and the damping's K₀, are exactly s times the unscaled ones (up to
// rounding). So wrapping a body's ElasticTerm and DampingTerm in a ScaledTerm
// of scale s is the body with its materials scaled by s.
//
// Name, blocks, caches, activity and reported quantities are the inner term's
// (elastic and damping report none).
#include <memory>

#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

class ScaledTerm final : public EnergyTerm {
 public:
  /// `scale` > 0 (finite); the inner term is shared, not copied.
  ScaledTerm(std::shared_ptr<const EnergyTerm> inner, double scale);
  std::string name() const override { return inner_->name(); }
  BodyBlocks blocks() const override { return inner_->blocks(); }
  std::vector<std::string> input_frames() const override { return inner_->input_frames(); }
  std::string input_anchor_set() const override { return inner_->input_anchor_set(); }
  std::unique_ptr<TermCache> make_cache() const override { return inner_->make_cache(); }
  void begin_step(const StepContext& ctx) const override { inner_->begin_step(ctx); }
  bool active(const StepContext& ctx) const override { return inner_->active(ctx); }
  bool in_nonlinearity_check() const override { return inner_->in_nonlinearity_check(); }
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override {
    return inner_->report(ctx, q);
  }
  /// scale × the inner term's energy; adds scale × its gradient and Hessian
  /// (computed into zeroed buffers of the argument's size, per thread).
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

  double scale() const { return scale_; }
  const std::shared_ptr<const EnergyTerm>& inner() const { return inner_; }

 private:
  std::shared_ptr<const EnergyTerm> inner_;
  double scale_;
};

}  // namespace sflsh
