#pragma once
// c JᵀJ of one posed point, written block by block from the Jacobian's
// structure (the Gauss–Newton Hessian of a point mass, c = m/h²).
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

/// hess += c Jᵀ J for point p, J = ∂x_p/∂δ (3 by the point's DoFs), written
/// block by block from J's structure (posed_points.hpp):
///   bone j: J_j = [P_j, w_j I] with P_j = −[w_j G_j y]×;  handle e: J_e = ω_e A, A = Σ_j w_j R_j,
/// so  J_eᵀJ_f = ω_e ω_f AᵀA,  J_jᵀJ_e = ω_e [P_jᵀA; w_j A],
///     J_iᵀJ_j = [P_iᵀP_j, w_j P_iᵀ; w_i P_j, w_i w_j I].
/// Each distinct block is computed once and added with its transpose; no
/// allocation, and no dense 3 by n product (the same sums as c JᵀJ up to the
/// rounding of reassociated products: ≤ 1e-15 relative).
/// `c` may be negative (a subtracted point mass).
void add_point_hessian(const PosedPoints& points, int p, const Configuration& q, const DofLayout& layout, double c,
                       MatRef& hess);

}  // namespace sflsh
