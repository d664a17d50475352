#include "sflsh/sim/energies/inertia.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/elastic.hpp"

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

namespace {

/// hess += c Jᵀ J for point p, J = ∂x_p/∂δ (3 by the point's DoFs), written
/// block by block from J's structure (posed_points.hpp):
///   bone j: J_j = [P_j, w_j I] with P_j = −[w_j G_j y]×;  handle e: J_e = ω_e A, A = Σ_j w_j R_j,
/// so  J_eᵀJ_f = ω_e ω_f AᵀA,  J_jᵀJ_e = ω_e [P_jᵀA; w_j A],
///     J_iᵀJ_j = [P_iᵀP_j, w_j P_iᵀ; w_i P_j, w_i w_j I].
/// Each distinct block is computed once and added with its transpose; no
/// allocation, and no dense 3 by n product (the same sums as c JᵀJ up to the
/// rounding of reassociated products: ≤ 1e-15 relative).
void add_point_hessian(const PosedPoints& points, int p, const Configuration& q, const DofLayout& layout, double c,
                       MatRef& hess) {
  constexpr int kMaxBones = 24;
  const PosedPoints::Rows r = points.rows(p);
  const Vec3 y = points.unposed_displaced(p, q.z);
  Mat3 A = Mat3::Zero();
  for (int e = 0; e < r.num_bones; ++e) A += r.bone_weights[e] * q.bones[r.bones[e]].linear();
  const Mat3 S = c * (A.transpose() * A);
  const int z0 = layout.z_offset();
  for (int e = 0; e < r.num_handles; ++e) {
    const int re = z0 + 3 * r.handles[e];
    const double we = r.handle_weights[e];
    hess.block<3, 3>(re, re) += (we * we) * S;
    for (int f = e + 1; f < r.num_handles; ++f) {
      const int rf = z0 + 3 * r.handles[f];
      const Mat3 B = (we * r.handle_weights[f]) * S;  // symmetric: its transpose is itself
      hess.block<3, 3>(re, rf) += B;
      hess.block<3, 3>(rf, re) += B;
    }
  }
  if (!layout.bones_dynamic) return;
  require(r.num_bones <= kMaxBones, "InertiaTerm: point ", p, " has ", r.num_bones, " bones, expected <= ", kMaxBones);
  Mat3 P[kMaxBones], PtA[kMaxBones];
  const Mat3 cA = c * A;
  for (int i = 0; i < r.num_bones; ++i) {
    P[i] = -hat(r.bone_weights[i] * (q.bones[r.bones[i]] * y));
    PtA[i] = P[i].transpose() * cA;
  }
  for (int i = 0; i < r.num_bones; ++i) {
    const int bi = layout.bone_offset(r.bones[i]);
    const double wi = r.bone_weights[i];
    // Bone–handle blocks (6 by 3) and their transposes.
    for (int e = 0; e < r.num_handles; ++e) {
      const int re = z0 + 3 * r.handles[e];
      const double we = r.handle_weights[e];
      const Mat3 top = we * PtA[i], bottom = (wi * we) * cA;
      hess.block<3, 3>(bi, re) += top;
      hess.block<3, 3>(bi + 3, re) += bottom;
      hess.block<3, 3>(re, bi) += top.transpose();
      hess.block<3, 3>(re, bi + 3) += bottom.transpose();
    }
    // Bone–bone blocks (6 by 6), j >= i.
    for (int j = i; j < r.num_bones; ++j) {
      const int bj = layout.bone_offset(r.bones[j]);
      const double wj = r.bone_weights[j];
      const Mat3 PP = c * (P[i].transpose() * P[j]);
      const Mat3 PtW = (c * wj) * P[i].transpose();  // rotation of i, translation of j
      const Mat3 WP = (c * wi) * P[j];                // translation of i, rotation of j
      const double ww = c * wi * wj;
      hess.block<3, 3>(bi, bj) += PP;
      hess.block<3, 3>(bi, bj + 3) += PtW;
      hess.block<3, 3>(bi + 3, bj) += WP;
      for (int k = 0; k < 3; ++k) hess(bi + 3 + k, bj + 3 + k) += ww;
      if (j == i) continue;
      hess.block<3, 3>(bj, bi) += PP.transpose();
      hess.block<3, 3>(bj + 3, bi) += PtW.transpose();
      hess.block<3, 3>(bj, bi + 3) += WP.transpose();
      for (int k = 0; k < 3; ++k) hess(bj + 3 + k, bi + 3 + k) += ww;
    }
  }
}

}  // namespace

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
