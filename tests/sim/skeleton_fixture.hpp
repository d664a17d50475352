#pragma once
// Test helpers for the skeletal terms (header-only; only *_test.cpp files are
// compiled): a small T-pose SMPL skeleton, random configurations and
// finite differences in the tangent space (perturbations through retract).
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/bone_residual.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh::test {

/// An Avatar with only the skeleton filled: SMPL's 24 joints in a T-pose of a
/// ~1.75 m adult (y up, +x = the body's left, +z = forward).
inline Avatar make_tpose_skeleton() {
  Avatar a;
  a.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (const auto& n : kSmplJointNames) a.joint_names.emplace_back(n);
  a.joints_rest.resize(24, 3);
  a.joints_rest << 0.00, 0.95, 0.00,    // pelvis
      0.09, 0.87, 0.00, -0.09, 0.87, 0.00,     // hips
      0.00, 1.05, -0.01,                       // spine1
      0.10, 0.50, 0.01, -0.10, 0.50, 0.01,     // knees
      0.00, 1.18, 0.00,                        // spine2
      0.10, 0.08, -0.02, -0.10, 0.08, -0.02,   // ankles
      0.00, 1.24, 0.01,                        // spine3
      0.11, 0.02, 0.10, -0.11, 0.02, 0.10,     // feet
      0.00, 1.45, -0.01,                       // neck
      0.07, 1.37, 0.00, -0.07, 1.37, 0.00,     // collars
      0.00, 1.52, 0.03,                        // head
      0.17, 1.40, -0.01, -0.17, 1.40, -0.01,   // shoulders
      0.43, 1.39, -0.02, -0.43, 1.39, -0.02,   // elbows
      0.68, 1.39, -0.01, -0.68, 1.39, -0.01,   // wrists
      0.76, 1.38, -0.01, -0.76, 1.38, -0.01;   // hands
  return a;
}

inline Vec3 random_vector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return scale * Vec3(u(rng), u(rng), u(rng));
}

/// A random SMPL pose: axis-angle components in ±max_angle (rad), translation ±0.3 m.
inline BodyPose random_pose(std::mt19937& rng, double max_angle) {
  BodyPose p;
  for (int j = 0; j < 24; ++j) p.axis_angle.row(j) = random_vector(rng, max_angle).transpose();
  p.translation = random_vector(rng, 0.3);
  return p;
}

/// 24 random, unconnected bone transforms (rotation vectors ±max_angle, translations ±max_shift).
inline Configuration random_bones(std::mt19937& rng, double max_angle, double max_shift) {
  Configuration q;
  q.z = VecX(0);
  for (int i = 0; i < 24; ++i) {
    Isometry G = Isometry::Identity();
    G.linear() = rodrigues(random_vector(rng, max_angle));
    G.translation() = random_vector(rng, max_shift);
    q.bones.push_back(G);
  }
  return q;
}

inline Configuration bones_config(const std::vector<Isometry>& bones) {
  Configuration q;
  q.bones = bones;
  q.z = VecX(0);
  return q;
}

/// Context for skeleton-only tests: 24 dynamic bones, no reduced DoFs.
inline StepContext skeleton_context(const Avatar& a, const Configuration& q_prev, double h = 1.0 / 60.0) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.num_bones = 24;
  ctx.layout.bones_dynamic = true;
  ctx.layout.num_reduced = 0;
  ctx.h = h;
  ctx.q_prev = q_prev;
  ctx.q_prev2 = q_prev;
  return ctx;
}

inline Configuration perturbed(const StepContext& ctx, const Configuration& q, int k, double eps) {
  VecX d = VecX::Zero(ctx.layout.size());
  d[k] = eps;
  return retract(q, d, ctx.layout);
}

/// Central differences of the energy along each tangent direction.
inline VecX fd_gradient(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, double eps = 1e-6) {
  VecX g(ctx.layout.size());
  for (int k = 0; k < g.size(); ++k)
    g[k] = (term.evaluate(ctx, perturbed(ctx, q, k, eps), nullptr, nullptr) -
            term.evaluate(ctx, perturbed(ctx, q, k, -eps), nullptr, nullptr)) /
           (2 * eps);
  return g;
}

/// Second differences of E(retract(q, δ)) at δ = 0: the exact tangent-space Hessian.
inline MatX fd_hessian(const EnergyTerm& term, const StepContext& ctx, const Configuration& q, double eps = 1e-4) {
  const int n = ctx.layout.size();
  MatX H(n, n);
  auto E = [&](int k, double a, int l, double b) {
    VecX d = VecX::Zero(n);
    d[k] += a;
    d[l] += b;
    return term.evaluate(ctx, retract(q, d, ctx.layout), nullptr, nullptr);
  };
  for (int k = 0; k < n; ++k)
    for (int l = k; l < n; ++l)
      H(k, l) = H(l, k) = (E(k, eps, l, eps) - E(k, eps, l, -eps) - E(k, -eps, l, eps) + E(k, -eps, l, -eps)) /
                          (4 * eps * eps);
  return H;
}

/// All residual blocks stacked: r (3B) and the analytic Jacobian dr/dδ (3B by n).
inline void stacked_residuals(const BoneLeastSquaresTerm& term, const StepContext& ctx, const Configuration& q,
                              VecX& r, MatX* J) {
  std::vector<BoneResidual> blocks;
  term.residuals(ctx, q, blocks);
  r.resize(3 * blocks.size());
  if (J) J->setZero(3 * blocks.size(), ctx.layout.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    r.segment<3>(3 * b) = blocks[b].r;
    if (!J) continue;
    for (int s = 0; s < 2; ++s)
      if (blocks[b].bones[s] >= 0) J->block<3, 6>(3 * b, ctx.layout.bone_offset(blocks[b].bones[s])) += blocks[b].J[s];
  }
}

/// Central differences of the stacked residuals (the block structure must not
/// change between q ± eps).
inline MatX fd_residual_jacobian(const BoneLeastSquaresTerm& term, const StepContext& ctx, const Configuration& q,
                                 double eps = 1e-6) {
  VecX r0, rp, rm;
  stacked_residuals(term, ctx, q, r0, nullptr);
  MatX J(r0.size(), ctx.layout.size());
  for (int k = 0; k < J.cols(); ++k) {
    stacked_residuals(term, ctx, perturbed(ctx, q, k, eps), rp, nullptr);
    stacked_residuals(term, ctx, perturbed(ctx, q, k, -eps), rm, nullptr);
    if (rp.size() != r0.size() || rm.size() != r0.size()) return MatX();  // structure changed
    J.col(k) = (rp - rm) / (2 * eps);
  }
  return J;
}

/// Relative error ‖a − b‖ / max(‖b‖, floor).
inline double rel_error(const MatX& a, const MatX& b, double floor = 1e-12) {
  return (a - b).norm() / std::max(b.norm(), floor);
}

/// Smallest eigenvalue of the symmetric part of H.
inline double min_eigenvalue(const MatX& H) {
  return Eigen::SelfAdjointEigenSolver<MatX>(0.5 * (H + H.transpose()), Eigen::EigenvaluesOnly).eigenvalues()(0);
}

/// Checks a bone least-squares term at q: its gradient and stacked residual
/// Jacobian against finite differences (relative 1e-6 / 1e-7), `rows` stacked
/// residuals when rows ≥ 0, and a PSD (Gauss–Newton) Hessian. Returns that Hessian.
inline MatX expect_residual_derivatives_match(const BoneLeastSquaresTerm& term, const StepContext& ctx,
                                              const Configuration& q, int rows = -1) {
  const int n = ctx.layout.size();
  VecX g = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  term.evaluate(ctx, q, &g, &H);
  EXPECT_LT(rel_error(g, fd_gradient(term, ctx, q)), 1e-6);
  VecX r;
  MatX J;
  stacked_residuals(term, ctx, q, r, &J);
  if (rows >= 0) {
    EXPECT_EQ(r.size(), rows);
  }
  EXPECT_LT(rel_error(J, fd_residual_jacobian(term, ctx, q)), 1e-7);
  EXPECT_GT(min_eigenvalue(H), -1e-9 * H.norm());
  return H;
}

/// The synthetic box of synthetic_avatar.hpp (`handles` hat handles,
/// `samples` cubature samples per cubature) carrying the T-pose skeleton.
inline std::shared_ptr<const Avatar> make_tpose_box(int handles, int samples) {
  SyntheticAvatarOptions so;
  so.handles = handles;
  so.all_tets = false;
  so.samples = samples;
  Avatar a = make_synthetic_avatar(so);
  a.joints_rest = make_tpose_skeleton().joints_rest;
  return std::make_shared<const Avatar>(std::move(a));
}

}  // namespace sflsh::test
