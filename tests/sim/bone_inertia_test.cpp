// Bone rigid-body inertia and bone gravity (energies/bone_inertia.hpp, bone_gravity.hpp).
#include "sflsh/sim/energies/bone_inertia.hpp"

#include <gtest/gtest.h>

#include "sflsh/sim/energies/bone_gravity.hpp"
#include "skeleton_fixture.hpp"

namespace sflsh {
namespace {

constexpr double kSkeletonMass = 10.5;  // kg, 15 % of 70 kg

TEST(BoneBodies, MassesFollowWinterAndInertiaIsPhysical) {
  double sum = 0;
  for (double f : smpl_segment_mass_fractions()) sum += f;
  EXPECT_NEAR(sum, 1.0, 1e-12);
  const Avatar a = test::make_tpose_skeleton();
  const std::vector<BoneBody> bodies = bone_bodies(a, kSkeletonMass);
  EXPECT_NEAR(total_mass(bodies), kSkeletonMass, 1e-12);
  EXPECT_NEAR(bodies[1].mass, 0.100 * kSkeletonMass, 1e-12);  // thigh
  // Left thigh: centre of mass halfway between hip and knee.
  EXPECT_LT((bodies[1].com_rest - 0.5 * (a.joints_rest.row(1) + a.joints_rest.row(4)).transpose()).norm(), 1e-12);
  // Its inertia: a rod of length L = 0.3701 m along ~y, r = 0.05 L + 0.01:
  // axial ½ m r², transverse m (3r² + L²)/12.
  const double L = (a.joints_rest.row(4) - a.joints_rest.row(1)).norm(), r = 0.05 * L + 0.01, m = bodies[1].mass;
  Eigen::SelfAdjointEigenSolver<Mat3> eig(bodies[1].inertia_rest);
  EXPECT_NEAR(eig.eigenvalues()(0), 0.5 * m * r * r, 1e-12);
  EXPECT_NEAR(eig.eigenvalues()(2), m * (3 * r * r + L * L) / 12, 1e-12);
  for (const BoneBody& b : bodies) EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat3>(b.inertia_rest).eigenvalues()(0), 0);
  EXPECT_THROW(bone_bodies(a, -1.0), Error);
}

/// q_prev2, q_prev random; q_pred = the constant-velocity prediction.
struct Motion {
  Configuration prev2, prev, pred;
};

Motion random_motion(const std::vector<BoneBody>& bodies, std::mt19937& rng) {
  Motion m;
  m.prev = test::random_bones(rng, 1.0, 0.5);
  m.prev2 = m.prev;
  m.pred = m.prev;
  for (int i = 0; i < 24; ++i) {
    // Previous step: rotated by a random increment, shifted a little.
    m.prev2.bones[i].linear() = rodrigues(test::random_vector(rng, 0.2)) * m.prev.bones[i].linear();
    m.prev2.bones[i].translation() += test::random_vector(rng, 0.03);
    const Mat3 Rt = m.prev.bones[i].linear(), Rp = m.prev2.bones[i].linear();
    const Vec3 c = bodies[i].com_rest;
    const Vec3 c_pred = 2.0 * (m.prev.bones[i] * c) - m.prev2.bones[i] * c;
    m.pred.bones[i].linear() = Rt * Rp.transpose() * Rt;
    m.pred.bones[i].translation() = c_pred - m.pred.bones[i].linear() * c;
  }
  return m;
}

TEST(BoneInertia, ZeroAtTheConstantVelocityPrediction) {
  const Avatar a = test::make_tpose_skeleton();
  BoneInertia term(bone_bodies(a, kSkeletonMass));
  std::mt19937 rng(11);
  const Motion m = random_motion(term.bodies(), rng);
  StepContext ctx = test::skeleton_context(a, m.prev);
  ctx.q_prev2 = m.prev2;
  const auto cache_term = begin_term_step(term, ctx);
  VecX g = VecX::Zero(ctx.layout.size());
  EXPECT_LT(term.evaluate(ctx, m.pred, &g, nullptr), 1e-20);
  EXPECT_LT(g.norm(), 1e-8);
  // And not zero elsewhere: staying at q_prev costs the kinetic energy.
  EXPECT_GT(term.evaluate(ctx, m.prev, nullptr, nullptr), 1e-3);
}

TEST(BoneInertia, KineticEnergyOfATranslationIsHalfMvSquared) {
  // From rest, displacing every bone by d costs Σ m |d|² / (2h²) = ½ M (d/h)².
  const Avatar a = test::make_tpose_skeleton();
  BoneInertia term(bone_bodies(a, kSkeletonMass));
  const Configuration rest = test::bones_config(std::vector<Isometry>(24, Isometry::Identity()));
  StepContext ctx = test::skeleton_context(a, rest, 0.01);
  const auto cache_term = begin_term_step(term, ctx);
  Configuration moved = rest;
  for (auto& G : moved.bones) G.translation() = Vec3(0.001, -0.002, 0.0);
  EXPECT_NEAR(term.evaluate(ctx, moved, nullptr, nullptr), 0.5 * kSkeletonMass * (5e-6 / 1e-4), 1e-12);
}

TEST(BoneInertia, DerivativesMatchFiniteDifferences) {
  const Avatar a = test::make_tpose_skeleton();
  BoneInertia term(bone_bodies(a, kSkeletonMass));
  std::mt19937 rng(12);
  const Motion m = random_motion(term.bodies(), rng);
  StepContext ctx = test::skeleton_context(a, m.prev);
  ctx.q_prev2 = m.prev2;
  const auto cache_term = begin_term_step(term, ctx);
  const int n = ctx.layout.size();

  // Away from the prediction: gradient and residual Jacobians (which give the
  // Gauss–Newton Hessian Jᵀ W J) against finite differences.
  const Configuration q = test::random_bones(rng, 1.0, 0.5);
  const MatX H = test::expect_residual_derivatives_match(term, ctx, q);
  EXPECT_LT((H - H.transpose()).norm(), 1e-9 * H.norm());

  // At the prediction (zero residual) Gauss–Newton is the exact Hessian.
  MatX H0 = MatX::Zero(n, n);
  term.evaluate(ctx, m.pred, nullptr, &H0);
  EXPECT_LT(test::rel_error(H0, test::fd_hessian(term, ctx, m.pred)), 1e-5);
}

TEST(BoneInertia, KinematicBonesAddNothing) {
  const Avatar a = test::make_tpose_skeleton();
  BoneInertia term(bone_bodies(a, kSkeletonMass));
  std::mt19937 rng(13);
  StepContext ctx = test::skeleton_context(a, test::random_bones(rng, 0.5, 0.2));
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = 6;
  const auto cache_term = begin_term_step(term, ctx);
  VecX g = VecX::Zero(6);
  MatX H = MatX::Zero(6, 6);
  const double E = term.evaluate(ctx, test::random_bones(rng, 0.5, 0.2), &g, &H);
  EXPECT_GT(E, 0);
  EXPECT_EQ(g.norm(), 0.0);
  EXPECT_EQ(H.norm(), 0.0);
}

TEST(BoneInertia, EvaluateBeforeBeginStepThrows) {
  const Avatar a = test::make_tpose_skeleton();
  BoneInertia term(bone_bodies(a, kSkeletonMass));
  const Configuration rest = test::bones_config(std::vector<Isometry>(24, Isometry::Identity()));
  EXPECT_THROW(term.evaluate(test::skeleton_context(a, rest), rest, nullptr, nullptr), Error);
}

TEST(BoneGravity, ValueAndGradient) {
  const Avatar a = test::make_tpose_skeleton();
  const std::vector<BoneBody> bodies = bone_bodies(a, kSkeletonMass);
  BoneGravity term(bodies);
  std::mt19937 rng(14);
  const Configuration q = test::random_bones(rng, 1.0, 0.5);
  StepContext ctx = test::skeleton_context(a, q);
  ctx.gravity = Vec3(0.3, -9.81, 0.1);
  double expected = 0;
  for (int i = 0; i < 24; ++i) expected -= bodies[i].mass * ctx.gravity.dot(q.bones[i] * bodies[i].com_rest);
  VecX g = VecX::Zero(ctx.layout.size());
  MatX H = MatX::Zero(ctx.layout.size(), ctx.layout.size());
  EXPECT_NEAR(term.evaluate(ctx, q, &g, &H), expected, 1e-12);
  EXPECT_LT(test::rel_error(g, test::fd_gradient(term, ctx, q)), 1e-7);
  EXPECT_EQ(H.norm(), 0.0);  // linear potential: zero (PSD) Hessian by design
  // The force on the translations is the weight.
  Vec3 force = Vec3::Zero();
  for (int i = 0; i < 24; ++i) force -= g.segment<3>(6 * i + 3);
  EXPECT_LT((force - kSkeletonMass * ctx.gravity).norm(), 1e-10);
}

TEST(BoneInertiaAndGravity, OneNewtonStepFromRestFallsByGravity) {
  // min m/(2h²)|c − c*|² − m g·c  ->  c = c* + h² g: from rest, one exact
  // Newton step moves every bone by h² g and does not rotate it.
  const Avatar a = test::make_tpose_skeleton();
  const std::vector<BoneBody> bodies = bone_bodies(a, kSkeletonMass);
  BoneInertia inertia(bodies);
  BoneGravity gravity(bodies);
  std::mt19937 rng(15);
  const Configuration q0 = test::random_bones(rng, 1.0, 0.5);
  StepContext ctx = test::skeleton_context(a, q0);
  const auto cache_inertia = begin_term_step(inertia, ctx);
  const int n = ctx.layout.size();
  VecX g = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  inertia.evaluate(ctx, q0, &g, &H);
  gravity.evaluate(ctx, q0, &g, &H);
  const Configuration q1 = retract(q0, H.ldlt().solve(-g), ctx.layout);
  for (int i = 0; i < 24; ++i) {
    const Vec3 dc = q1.bones[i] * bodies[i].com_rest - q0.bones[i] * bodies[i].com_rest;
    EXPECT_LT((dc - ctx.h * ctx.h * ctx.gravity).norm(), 1e-12) << "bone " << i;
    EXPECT_LT((q1.bones[i].linear() - q0.bones[i].linear()).norm(), 1e-12) << "bone " << i;
  }
}

}  // namespace
}  // namespace sflsh
