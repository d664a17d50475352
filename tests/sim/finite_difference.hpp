#pragma once
// Finite-difference checks of an EnergyTerm in the tangent space of q
// (configuration.hpp): the term's gradient/Hessian are those of
// δ ↦ E(retract(q, δ)) at δ = 0. Header-only, for tests/sim/*_test.cpp.
#include <random>

#include "sflsh/sim/energy_term.hpp"

namespace sflsh::test {

/// E(retract(q, δ)).
inline double energy_at(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, const VecX& delta) {
  return term.evaluate(ctx, retract(q, delta, ctx.layout), nullptr, nullptr);
}

/// Central-difference gradient (layout.size()). The + side is evaluated
/// first (a term with a warm-started inner minimization, as the contact
/// patch, sees the same sequence of evaluations every run).
inline VecX fd_gradient(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, double eps) {
  const int n = ctx.layout.size();
  VecX g(n);
  for (int i = 0; i < n; ++i) {
    VecX d = VecX::Zero(n);
    d[i] = eps;
    const double plus = energy_at(term, ctx, q, d);
    g[i] = (plus - energy_at(term, ctx, q, -d)) / (2 * eps);
  }
  return g;
}

/// uᵀ H v by second differences of the energy (polarization).
inline double fd_bilinear(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, const VecX& u,
                          const VecX& v, double eps) {
  return (energy_at(term, ctx, q, eps * (u + v)) - energy_at(term, ctx, q, eps * (u - v)) -
          energy_at(term, ctx, q, eps * (v - u)) + energy_at(term, ctx, q, -eps * (u + v))) /
         (4 * eps * eps);
}

/// Analytic value, gradient and Hessian of a term at q.
struct TermDerivatives {
  double value;
  VecX grad;
  MatX hess;
};
inline TermDerivatives analytic(const EnergyTerm& term, const StepContext& ctx, const Configuration& q) {
  TermDerivatives d;
  d.grad = VecX::Zero(ctx.layout.size());
  d.hess = MatX::Zero(ctx.layout.size(), ctx.layout.size());
  d.value = term.evaluate(ctx, q, &d.grad, &d.hess);
  return d;
}

/// Largest relative error of uᵀHv over `trials` random unit directions (scale: ‖H‖).
inline double hessian_fd_error(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, const MatX& H,
                               double eps, int trials, std::mt19937& rng) {
  std::normal_distribution<double> n01;
  double worst = 0;
  const double scale = H.norm();
  for (int t = 0; t < trials; ++t) {
    VecX u(H.rows()), v(H.rows());
    for (int i = 0; i < u.size(); ++i) u[i] = n01(rng), v[i] = n01(rng);
    u.normalize();
    v.normalize();
    worst = std::max(worst, std::abs(u.dot(H * v) - fd_bilinear(term, ctx, q, u, v, eps)) / scale);
  }
  return worst;
}

}  // namespace sflsh::test
