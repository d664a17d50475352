// The Newton step's caps (sim/step_cap.hpp): a bone over the rotation cap is
// capped alone, keeping its pivot's displacement, and the other bones (the
// root) take their full step. Expected values by hand (Eigen::AngleAxis, the
// targets of a quadratic test energy whose Newton step reaches them exactly).
#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/newton_step.hpp"
#include "sflsh/sim/step_cap.hpp"

namespace sflsh {
namespace {

Mat3 axis_angle(double angle, const Vec3& axis) { return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix(); }

/// Two dynamic bones with pivots, no soft DoFs: bone 0 (the root) and bone 1.
struct TwoBones {
  DofLayout layout;
  Configuration q;
  TwoBones() {
    layout.num_bones = 2;
    layout.bones_dynamic = true;
    layout.num_reduced = 0;
    layout.bone_pivots = Points(2, 3);
    layout.bone_pivots << 0.0, 0.9, 0.0,  // pelvis-like joint
        0.1, 0.5, 0.05;                  // a distal joint
    Isometry G0 = Isometry::Identity(), G1 = Isometry::Identity();
    G0.linear() = axis_angle(0.3, Vec3(0, 1, 0));
    G0.translation() = Vec3(0.02, -0.01, 0.03);
    G1.linear() = axis_angle(0.7, Vec3(1, 0.5, 0));
    G1.translation() = Vec3(-0.05, 0.2, 0.1);
    q.bones = {G0, G1};
    q.z = VecX(0);
  }
  Vec3 pivot(const Configuration& c, int i) const { return c.bones[i] * Vec3(layout.bone_pivots.row(i).transpose()); }
};

TEST(StepCap, CapsOnlyTheBoneOverTheCapAndKeepsItsPivotDisplacement) {
  const TwoBones s;
  VecX delta(12);
  delta << 0.2, -0.1, 0.3, 0.01, 0.02, -0.03,  // bone 0: |ω| = 0.374 rad, within the 1 rad cap
      0.0, 1.2, 1.6, 0.04, -0.02, 0.05;        // bone 1: |ω| = 2 rad
  const VecX original = delta;
  VecX capped = delta;
  EXPECT_EQ(cap_bone_rotations(capped, {s.q}, {s.layout}, 1.0), 1);
  // Bone 0 untouched, bit for bit.
  for (int j = 0; j < 6; ++j) EXPECT_EQ(capped(j), original(j)) << j;
  // Bone 1 turns by exactly 1 rad about the same axis (0, 0.6, 0.8).
  EXPECT_NEAR((capped.segment<3>(6) - Vec3(0.0, 0.6, 0.8)).norm(), 0.0, 1e-15);
  const Configuration full = retract(s.q, original, s.layout);
  const Configuration after = retract(s.q, capped, s.layout);
  EXPECT_LT((after.bones[1].linear() - axis_angle(1.0, Vec3(0, 0.6, 0.8)) * s.q.bones[1].linear()).norm(), 1e-14);
  // Its pivot (joint) lands where the full step puts it; bone 0 as in the full step.
  EXPECT_LT((s.pivot(after, 1) - s.pivot(full, 1)).norm(), 1e-15);
  EXPECT_LT((after.bones[0].matrix() - full.bones[0].matrix()).norm(), 1e-15);
}

TEST(StepCap, LeavesAStepWithinTheCapsBitIdentical) {
  const TwoBones s;
  VecX delta(12);
  delta << 0.2, -0.1, 0.3, 0.01, 0.02, -0.03, 0.0, 0.6, 0.79, 0.04, -0.02, 0.05;  // |ω_1| = 0.991 rad
  VecX capped = delta;
  EXPECT_EQ(cap_bone_rotations(capped, {s.q}, {s.layout}, 1.0), 0);
  EXPECT_EQ(capped, delta);
  delta.segment<3>(6) *= 3.0;
  capped = delta;
  EXPECT_EQ(cap_bone_rotations(capped, {s.q}, {s.layout}, 0.0), 0);  // 0: no cap
  EXPECT_EQ(capped, delta);
  // Kinematic bones are not in δ: nothing to cap.
  DofLayout kinematic = s.layout;
  kinematic.bones_dynamic = false;
  VecX empty(0);
  EXPECT_EQ(cap_bone_rotations(empty, {s.q}, {kinematic}, 1.0), 0);
}

TEST(StepCap, PerBoneOnlyWhenEveryBoneOverTheCapIsALeaf) {
  const TwoBones s;
  const std::vector<int> parents = {-1, 0};
  VecX delta = VecX::Zero(12);
  delta(8) = 2.0;  // the leaf (bone 1) over the cap
  EXPECT_TRUE(rotation_cap_per_bone_applies(delta, {s.layout}, {&parents}, 1.0));
  delta(2) = 1.5;  // the root, parent of bone 1, too
  EXPECT_FALSE(rotation_cap_per_bone_applies(delta, {s.layout}, {&parents}, 1.0));
  EXPECT_DOUBLE_EQ(rotation_step_scale(delta, {s.layout}, 1.0), 0.5);
  delta(2) = 0.0;
  EXPECT_FALSE(rotation_cap_per_bone_applies(delta, {s.layout}, {nullptr}, 1.0));  // unknown skeleton
}

TEST(StepCap, HandleCapScalesTheWholeStep) {
  DofLayout layout;
  layout.bones_dynamic = false;
  layout.num_reduced = 6;
  VecX delta(6);
  delta << 0.03, 0.0, 0.04, 0.0, 0.01, 0.0;  // handle 0 moves 0.05 m, handle 1 0.01 m
  EXPECT_DOUBLE_EQ(handle_step_scale(delta, {layout}, 0.02), 0.4);
  EXPECT_EQ(handle_step_scale(delta, {layout}, 0.06), 1.0);
  EXPECT_EQ(handle_step_scale(delta, {layout}, 0.0), 1.0);
}

/// E = ½ k Σ_i |P_i − P*_i|² + ½ k_r Σ_i |log(R_i R*_iᵀ)|², P_i = G_i p̄_i the
/// bone's pivot. With pivot retraction P moves by v + ω × P exactly, so the
/// first part is quadratic in δ; the second has gradient log(R R*ᵀ) at ω = 0
/// and Hessian k_r I is used: one Newton step then reaches every target
/// exactly (ω_i = log(R*_i R_iᵀ), pivot at P*_i).
class BoneTargets : public EnergyTerm {
 public:
  std::vector<Vec3> pivot_target;
  std::vector<Mat3> rotation_target;
  double k = 1e3, k_r = 10;
  double rotation_hessian_scale = 1;  ///< < 1: the Hessian underestimates the curvature (Newton overshoots)
  std::string name() const override { return "bone_targets"; }
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override {
    double E = 0;
    for (int i = 0; i < ctx.layout.num_bones; ++i) {
      const Vec3 P = q.bones[i] * Vec3(ctx.layout.bone_pivots.row(i).transpose());
      const Vec3 r = P - pivot_target[i];
      const Vec3 phi = rotation_log(q.bones[i].linear() * rotation_target[i].transpose());
      E += 0.5 * k * r.squaredNorm() + 0.5 * k_r * phi.squaredNorm();
      const int o = ctx.layout.bone_offset(i);
      Eigen::Matrix<double, 3, 6> A;  // ∂P/∂(ω, v) = [−[P]×, I]
      A << -hat(P), Mat3::Identity();
      if (grad) {
        grad->segment<6>(o) += k * A.transpose() * r;
        grad->segment<3>(o) += k_r * phi;
      }
      if (hess) {
        hess->block<6, 6>(o, o) += k * A.transpose() * A;
        hess->block<3, 3>(o, o) += rotation_hessian_scale * k_r * Mat3::Identity();
      }
    }
    return E;
  }
};

/// The two bones of TwoBones as a chain (bone 1 a leaf child of the root), pulled by
/// BoneTargets: the root 0.1 m along x and 0.2 rad about y (within the cap), bone 1's joint
/// 3 cm up and its rotation `distal_angle` rad about z.
struct CappedChain {
  TwoBones s;
  BoneTargets term;
  Avatar skeleton;  // only its parent table is read
  StepContext ctx;
  explicit CappedChain(double distal_angle) {
    term.pivot_target = {s.pivot(s.q, 0) + Vec3(0.1, 0, 0), s.pivot(s.q, 1) + Vec3(0, 0.03, 0)};
    term.rotation_target = {axis_angle(0.2, Vec3(0, 1, 0)) * s.q.bones[0].linear(),
                            axis_angle(distal_angle, Vec3(0, 0, 1)) * s.q.bones[1].linear()};
    skeleton.parents = {-1, 0};
    ctx.avatar = &skeleton;
    ctx.layout = s.layout;
    ctx.q_prev = ctx.q_prev2 = s.q;
  }
};

TEST(StepCap, RootTakesItsFullNewtonStepWhenADistalBoneHitsTheCap) {
  CappedChain chain(2.0);  // 2 rad: over the 1 rad cap
  const TwoBones& s = chain.s;
  BoneTargets& term = chain.term;
  const StepContext& ctx = chain.ctx;
  NewtonOptions o;
  o.max_rotation_step = 1.0;
  o.iterations_after_damping = 0;  // the capped iteration itself (more iterations: the test below)
  for (bool line_search : {false, true}) {
    o.line_search = line_search;
    Configuration q = s.q;
    const StepReport rep = newton_minimize({&term}, ctx, q, o);
    EXPECT_EQ(rep.damped, 1) << rep.summary();
    EXPECT_EQ(rep.rejected, 0);
    // The root reaches its targets: the whole step was not scaled (0.5 before).
    EXPECT_LT((s.pivot(q, 0) - term.pivot_target[0]).norm(), 1e-12) << "root pivot moved by "
                                                                    << (s.pivot(q, 0) - s.pivot(s.q, 0)).transpose();
    EXPECT_LT((q.bones[0].linear() - term.rotation_target[0]).norm(), 1e-12);
    // The capped bone: its joint where asked, its rotation 1 rad of the 2 about z.
    EXPECT_LT((s.pivot(q, 1) - term.pivot_target[1]).norm(), 1e-12);
    EXPECT_LT((q.bones[1].linear() - axis_angle(1.0, Vec3(0, 0, 1)) * s.q.bones[1].linear()).norm(), 1e-12);
  }
  // Without the cap, one Newton step reaches both targets (the test energy is exact).
  o.max_rotation_step = 0;
  o.line_search = false;
  Configuration q = s.q;
  const StepReport rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.accepted, 1);
  EXPECT_LT((q.bones[1].linear() - term.rotation_target[1]).norm(), 1e-12);
  EXPECT_LT((s.pivot(q, 1) - term.pivot_target[1]).norm(), 1e-12);
}

/// A damped iteration is followed by more (NewtonOptions::iterations_after_damping)
/// until one is taken in full: the distal bone, 2.5 rad from its target with a 1 rad
/// cap, turns 1 + 1 + 0.5 rad in three iterations and ends on its target; the root's
/// targets, reached in the first, stay reached. With too few extra iterations it
/// ends the last one capped, 0.7 rad at a time.
TEST(StepCap, IterationsAfterADampedOneCarryTheBoneToItsTarget) {
  CappedChain chain(2.5);
  const TwoBones& s = chain.s;
  BoneTargets& term = chain.term;
  const StepContext& ctx = chain.ctx;
  NewtonOptions o;
  o.max_rotation_step = 1.0;
  ASSERT_EQ(o.iterations_after_damping, 3) << "the default this test documents";
  Configuration q = s.q;
  StepReport rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.iterations, 3) << rep.summary();
  EXPECT_EQ(rep.iterations_after_damping, 2);
  EXPECT_EQ(rep.damped, 2);
  EXPECT_EQ(rep.accepted, 1);
  EXPECT_EQ(rep.step_scale, 1.0);
  EXPECT_LT((q.bones[1].linear() - term.rotation_target[1]).norm(), 1e-12);
  EXPECT_LT((s.pivot(q, 1) - term.pivot_target[1]).norm(), 1e-12);
  EXPECT_LT((q.bones[0].linear() - term.rotation_target[0]).norm(), 1e-12);
  EXPECT_LT((s.pivot(q, 0) - term.pivot_target[0]).norm(), 1e-12);
  EXPECT_NEAR(rep.energy_after, 0.0, 1e-18) << "the final report is of the final configuration";

  // Cap 0.7 rad, 1 + 2 iterations: 2.1 of the 2.5 rad, every iteration damped.
  o.max_rotation_step = 0.7;
  o.iterations_after_damping = 2;
  q = s.q;
  rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.iterations, 3) << rep.summary();
  EXPECT_EQ(rep.damped, 3);
  EXPECT_LT((q.bones[1].linear() - axis_angle(2.1, Vec3(0, 0, 1)) * s.q.bones[1].linear()).norm(), 1e-12);
  const double phi = rotation_log(q.bones[1].linear() * term.rotation_target[1].transpose()).norm();
  EXPECT_NEAR(rep.energy_after, 0.5 * term.k_r * phi * phi, 1e-12) << "0.4 rad left on the capped bone";

  // Added iterations must lower the objective. With a Hessian 4× too soft in rotation,
  // the bone 0.5 rad from its target is sent 2 rad, capped to 1 (the planned iteration:
  // damped, past the target by 0.5 rad); without the decrease test every added iteration
  // would swing it back and forth between 0 and 1 rad. With it, the first added one is
  // halved onto the target, and the next finds nothing left to do.
  term.rotation_target[1] = axis_angle(0.5, Vec3(0, 0, 1)) * s.q.bones[1].linear();
  term.rotation_hessian_scale = 0.25;
  o.max_rotation_step = 1.0;
  o.iterations_after_damping = 3;
  q = s.q;
  rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.rejected, 0) << rep.summary();
  EXPECT_LT((q.bones[1].linear() - term.rotation_target[1]).norm(), 1e-12) << rep.summary();
  EXPECT_NEAR(rep.energy_after, 0.0, 1e-18);
  term.rotation_hessian_scale = 1;
  term.rotation_target[1] = axis_angle(2.5, Vec3(0, 0, 1)) * s.q.bones[1].linear();

  // A step that is not damped takes exactly the planned iterations.
  o.max_rotation_step = 3.0;
  q = s.q;
  rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.iterations, 1);
  EXPECT_EQ(rep.iterations_after_damping, 0);
  EXPECT_EQ(rep.accepted, 1);
}

}  // namespace
}  // namespace sflsh
