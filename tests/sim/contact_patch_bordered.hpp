#pragma once
// For the contact patch's tests: what the Newton iteration's gradient takes
// that a gradient-only evaluation does not (contact_patch.cpp, the bordered
// system's right-hand side), read from the cache the Hessian evaluation left.
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh::test {

/// −Φ_qp Φ_pp⁻¹ Φ_p over `n` rows, Φ_pp⁻¹ Φ_p = δu − δu_lin (the minimizer's
/// remaining inner step, below the inner tolerance) and Φ_qp with the dented
/// tets' stiffening on its z rows.
inline VecX bordered_rhs_difference(const contact_patch_detail::PatchCache& c, int z0, int n) {
  const VecX rest = c.du - c.du_lin;
  VecX d = VecX::Zero(n);
  d.head(c.Hqp.rows()) -= c.Hqp * rest;
  d.segment(z0, c.Hzp_stiffening.rows()) -= c.Hzp_stiffening * rest;
  return d;
}

}  // namespace sflsh::test
