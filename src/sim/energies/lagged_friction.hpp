#pragma once
// Private to the contact terms: Coulomb friction lagged per step at one
// contact point (Li et al. 2020, "Incremental Potential Contact" §5), as
// sdf_contact.hpp's header comment states it. A point that touched at time t
// with normal force λ and normal n gets the dissipative potential
//   D = μ λ f0(|s|),   s = (I − n nᵀ)(x − y),
// y where the object carries the touched point by the iterate (s: the
// tangential slip over the step), f0 the C¹ mollifier of |s| below ε:
// a stiff tangential spring up to μλ, then sliding friction μλ.
#include "sflsh/core/types.hpp"

namespace sflsh::contact_friction {

/// IPC's friction mollifier at slip z ≥ 0 (ε > 0): f0, f1 = f0′ and f1′.
void mollifier(double z, double eps, double& f0, double& f1, double& df1);

/// D, ∂D/∂x and its PSD Hessian at one point.
struct PointFriction {
  double energy = 0;
  Vec3 gradient = Vec3::Zero();  ///< ∂D/∂x = −(the friction force on the point)
  Mat3 hessian = Mat3::Zero();   ///< μλ P[(f1/z) I + (f1′ − f1/z) ŝŝᵀ]P (2μλ/ε P at z = 0)
};

/// D at x for a point carried to y, normal n (unit), c = μλ (N) and ε (m);
/// with `derivatives` also its gradient and Hessian.
PointFriction point_friction(const Vec3& x, const Vec3& y, const Vec3& n, double c, double eps, bool derivatives);

}  // namespace sflsh::contact_friction
