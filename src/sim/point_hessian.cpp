#include "sflsh/sim/point_hessian.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

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


}  // namespace sflsh
