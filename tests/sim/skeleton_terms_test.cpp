// add_skeleton_terms and the skeletal terms working together: free fall and
// motion tracking, through newton_minimize and through the Simulator.
#include "sflsh/sim/skeleton_terms.hpp"

#include <gtest/gtest.h>

#include "sflsh/sim/newton_step.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "skeleton_fixture.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

constexpr double kBodyMass = 70.0;

TEST(SkeletonTerms, BodyMassFromTheSkinVolume) {
  Avatar a = test::make_tpose_skeleton();
  EXPECT_THROW(estimate_body_mass(a), Error);  // no surface
  // A 0.5 m cube, outward faces: 125 kg at 1000 kg/m³.
  a.surface_rest.resize(8, 3);
  for (int v = 0; v < 8; ++v) a.surface_rest.row(v) << 0.5 * (v & 1), 0.5 * ((v >> 1) & 1), 0.5 * ((v >> 2) & 1);
  a.surface_faces.resize(12, 3);
  a.surface_faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3,
      5, 3, 7, 5;
  EXPECT_NEAR(estimate_body_mass(a), 125.0, 1e-9);
  a.surface_faces.col(1).swap(a.surface_faces.col(2));  // inside out
  EXPECT_THROW(estimate_body_mass(a), Error);
}

TEST(SkeletonTerms, SubtreeInertiaGrowsTowardsTheRoot) {
  const Avatar a = test::make_tpose_skeleton();
  const std::vector<double> I = joint_subtree_inertia(a, bone_bodies(a, kBodyMass));
  // Left leg chain hip → knee → ankle → toes, and the whole body about the root.
  EXPECT_GT(I[1], I[4]);
  EXPECT_GT(I[4], I[7]);
  EXPECT_GT(I[7], I[10]);
  EXPECT_GT(I[10], 0.0);
  EXPECT_GT(I[0], I[3]);
  // Whole body about the pelvis: of the order of M · (0.5 m)²/3.
  EXPECT_GT(I[0], 3.0);
  EXPECT_LT(I[0], 30.0);
}

TEST(SkeletonTerms, AddsTheEnabledTerms) {
  const Avatar a = test::make_tpose_skeleton();
  SkeletonTermsOptions o;
  o.body_mass = kBodyMass;
  std::vector<EnergyTermPtr> terms;
  add_skeleton_terms(terms, a, o);
  std::vector<std::string> names;
  for (const auto& t : terms) names.push_back(t->name());
  EXPECT_EQ(names,
            (std::vector<std::string>{"bone_inertia", "bone_gravity", "joint_constraint", "joint_limit", "tracking"}));
  o.joint_limits = o.tracking = false;
  terms.clear();
  add_skeleton_terms(terms, a, o);
  EXPECT_EQ(terms.size(), 3u);
  o.skeleton_mass_fraction = 0.0;
  EXPECT_THROW(add_skeleton_terms(terms, a, o), Error);
}

/// Mass-weighted centre of the skeleton's bone bodies.
Vec3 skeleton_com(const std::vector<BoneBody>& bodies, const std::vector<Isometry>& bones) {
  Vec3 c = Vec3::Zero();
  for (std::size_t i = 0; i < bodies.size(); ++i) c += bodies[i].mass * (bones[i] * bodies[i].com_rest);
  return c / total_mass(bodies);
}

/// Result of a tumbling free fall of the skeleton (inertia + gravity + joint
/// constraints) with `iterations` Newton iterations per step.
struct FreeFall {
  double max_acc_error = 0;  ///< max over steps of |a_com − g| (m/s²)
  double max_joint_gap = 0;  ///< max joint separation (m)
  double root_turn = 0;      ///< final root rotation relative to the start (rad)
};

FreeFall tumbling_free_fall(int iterations) {
  const Avatar a = test::make_tpose_skeleton();
  SkeletonTermsOptions o;
  o.body_mass = kBodyMass;
  o.joint_limits = o.tracking = false;
  std::vector<EnergyTermPtr> owned;
  add_skeleton_terms(owned, a, o);
  std::vector<EnergyTerm*> terms;
  for (auto& t : owned) terms.push_back(t.get());
  const std::vector<BoneBody> bodies = bone_bodies(a, o.skeleton_mass_fraction * kBodyMass);

  std::mt19937 rng(51);
  const BodyPose pose = test::random_pose(rng, 0.5);
  BodyPose before = pose;  // one step earlier: turned about an oblique axis and shifted
  before.axis_angle.row(0) =
      rotation_log(rodrigues(Vec3(-0.05, 0.03, 0.04)) * rodrigues(pose.axis_angle.row(0).transpose())).transpose();
  before.translation -= Vec3(0.02, -0.03, 0.01);
  const double h = 1.0 / 60.0;
  StepContext ctx =
      test::skeleton_context(a, test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, pose)), h);
  ctx.q_prev2 = test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, before));
  NewtonOptions newton;
  newton.iterations = iterations;
  std::vector<Vec3> com = {skeleton_com(bodies, ctx.q_prev2.bones), skeleton_com(bodies, ctx.q_prev.bones)};
  FreeFall out;
  for (int step = 0; step < 20; ++step) {
    Configuration q = ctx.q_prev;
    newton_minimize(terms, ctx, q, newton);
    com.push_back(skeleton_com(bodies, q.bones));
    const Points x = joint_world_positions(q.bones, a.joints_rest);
    for (int j = 1; j < 24; ++j)
      out.max_joint_gap = std::max(
          out.max_joint_gap, (x.row(j).transpose() - q.bones[a.parents[j]] * Vec3(a.joints_rest.row(j).transpose())).norm());
    ctx.q_prev2 = ctx.q_prev;
    ctx.q_prev = q;
  }
  for (std::size_t n = 1; n + 1 < com.size(); ++n)
    out.max_acc_error =
        std::max(out.max_acc_error, ((com[n + 1] - 2 * com[n] + com[n - 1]) / (h * h) - ctx.gravity).norm());
  out.root_turn = rotation_log(ctx.q_prev.bones[0].linear() * rodrigues(pose.axis_angle.row(0).transpose()).transpose()).norm();
  return out;
}

TEST(SkeletonTerms, TumblingFreeFallAcceleratesTheCentreOfMassByG) {
  // Joint forces are internal, so with each step solved to convergence the
  // centre of mass falls with exactly g while the connected skeleton tumbles.
  const FreeFall converged = tumbling_free_fall(8);
  EXPECT_LT(converged.max_acc_error, 1e-6 * 9.81);
  EXPECT_GT(converged.root_turn, 0.5);      // it really rotates (not a rigid translation)
  EXPECT_LT(converged.max_joint_gap, 1e-4);  // joints stay connected (penalty: ~g h²/ratio)
}

/// Synthetic box avatar (simulator tests) carrying the T-pose skeleton.
std::shared_ptr<const Avatar> simulator_avatar() {
  Avatar a = test::make_synthetic_avatar();
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  return std::make_shared<const Avatar>(std::move(a));
}

TEST(SkeletonTerms, SimulatorSkeletonFallsFromRestWithG) {
  const auto avatar = simulator_avatar();
  SimulatorOptions so;
  so.bones_dynamic = true;
  so.soft_tissue_terms = false;  // the skeleton alone
  SkeletonTermsOptions o;
  o.body_mass = kBodyMass;
  o.joint_limits = o.tracking = false;
  Simulator sim(avatar_model(avatar, so, &o));
  const std::vector<BoneBody> bodies = bone_bodies(*avatar, o.skeleton_mass_fraction * kBodyMass);
  const Vec3 c0 = skeleton_com(bodies, sim.state().bones);
  const int steps = 30;
  for (int n = 0; n < steps; ++n) sim.step(sim.state().bones);
  // Backward Euler from rest: c_n = c_0 + g h² n(n+1)/2 (one Newton step is exact here).
  const double h = so.h;
  const Vec3 expected = c0 + so.gravity * h * h * steps * (steps + 1) / 2.0;
  EXPECT_LT((skeleton_com(bodies, sim.state().bones) - expected).norm(), 1e-9);
  EXPECT_NEAR(sim.time(), steps * h, 1e-12);
}

/// A walking-like target within the joint ranges at `f` Hz (t in s), walking
/// forward at 0.8 m/s from `start` (m).
BodyPose walking_target(double t, double f, const Vec3& start) {
  const double s = std::sin(2 * M_PI * f * t), c = std::cos(2 * M_PI * f * t);
  BodyPose p;
  p.axis_angle.row(0) << 0.0, 0.2 * s, 0.0;
  p.axis_angle.row(1) << -0.5 * s, 0.0, 0.05;
  p.axis_angle.row(2) << 0.5 * s, 0.0, -0.05;
  p.axis_angle.row(3) << 0.1 * s, 0.0, 0.0;
  p.axis_angle.row(4) << 0.3 * (1 - c), 0.0, 0.0;
  p.axis_angle.row(5) << 0.3 * (1 + c), 0.0, 0.0;
  p.axis_angle.row(16) << 0.0, 0.4 * s, -1.2;
  p.axis_angle.row(17) << 0.0, 0.4 * s, 1.2;
  p.axis_angle.row(18) << 0.0, -0.25 * (1 - c), 0.0;
  p.axis_angle.row(19) << 0.0, 0.25 * (1 + c), 0.0;
  p.translation = start + Vec3(0.0, 0.05 * s, 0.8 * t);
  return p;
}

/// States (one per step, 120 steps of 1/60 s) of a skeleton tracking
/// walking_target(f, start) with all skeletal terms at their defaults, one
/// Newton step per time step (the runtime's default), through the Simulator;
/// the soft tissue of the synthetic box rides along when `soft_tissue`.
std::vector<Configuration> walk(double f, const Vec3& start, bool soft_tissue) {
  const auto avatar = simulator_avatar();
  SimulatorOptions so;
  so.bones_dynamic = true;
  so.soft_tissue_terms = soft_tissue;
  SkeletonTermsOptions o;
  o.body_mass = kBodyMass;
  // The synthetic box carries flesh only on bones 0, 3 and 6: with the
  // default carried-inertia springs its bare limbs would get springs sized by
  // the skeleton's 15 % alone. The figures below are for springs sized by a
  // whole body's segments, as on a real avatar whose limbs carry their flesh.
  o.spring_inertia = SkeletonTermsOptions::SpringInertia::Segments;
  Simulator sim(avatar_model(avatar, so, &o));
  const Points& J = avatar->joints_rest;
  const auto& parents = avatar->parents;
  Configuration q0, q_1;
  q0.bones = bone_transforms_from_pose(J, parents, walking_target(0.0, f, start));
  q_1.bones = bone_transforms_from_pose(J, parents, walking_target(-so.h, f, start));
  q0.z = q_1.z = VecX::Zero(avatar->num_reduced());
  sim.reset(q0, q_1);
  std::vector<Configuration> states;
  for (int n = 1; n <= 120; ++n) {
    const BodyPose target = walking_target(n * so.h, f, start);
    sim.step(bone_transforms_from_pose(J, parents, target), target);
    states.push_back(sim.state());
  }
  return states;
}

/// Max joint position (m) and local rotation (rad) error of the skeleton alone
/// tracking walking_target(f, start) for 2 s (walk()).
std::pair<double, double> tracking_error(double f, const Vec3& start) {
  const Avatar a = *simulator_avatar();
  const Points& J = a.joints_rest;
  const std::vector<Configuration> states = walk(f, start, false);
  double max_pos = 0, max_angle = 0;
  for (int n = 1; n <= int(states.size()); ++n) {
    const BodyPose target = walking_target(n * (1.0 / 60.0), f, start);
    const std::vector<Isometry> target_bones = bone_transforms_from_pose(J, a.parents, target);
    const std::vector<Isometry>& bones = states[n - 1].bones;
    const Points x = joint_world_positions(bones, J), x_target = joint_world_positions(target_bones, J);
    max_pos = std::max(max_pos, (x - x_target).rowwise().norm().maxCoeff());
    const BodyPose pose = pose_from_bone_transforms(bones, J, a.parents);
    for (int j = 0; j < 24; ++j)
      max_angle = std::max(max_angle, rotation_log(rodrigues(pose.axis_angle.row(j).transpose()).transpose() *
                                                   rodrigues(target.axis_angle.row(j).transpose()))
                                          .norm());
  }
  return {max_pos, max_angle};
}

TEST(SkeletonTerms, SimulationDoesNotDependOnTheDistanceFromTheOrigin) {
  // The Simulator solves each step in a pelvis-centred frame: the same walk
  // (bones and soft tissue) 14 m from the origin is the same motion, shifted.
  const Vec3 far(10.0, 0.0, -9.8);
  const std::vector<Configuration> near_states = walk(1.0, Vec3::Zero(), true), far_states = walk(1.0, far, true);
  ASSERT_EQ(near_states.size(), far_states.size());
  double max_rot = 0, max_pos = 0, max_z = 0, z_scale = 0;
  for (std::size_t n = 0; n < near_states.size(); ++n) {
    const Configuration &a = near_states[n], &b = far_states[n];
    for (int j = 0; j < 24; ++j) {
      max_rot = std::max(max_rot, (a.bones[j].linear() - b.bones[j].linear()).norm());
      max_pos = std::max(max_pos, (a.bones[j].translation() + far - b.bones[j].translation()).norm());
    }
    max_z = std::max(max_z, (a.z - b.z).cwiseAbs().maxCoeff());
    z_scale = std::max(z_scale, a.z.cwiseAbs().maxCoeff());
  }
  ASSERT_GT(z_scale, 1e-4);  // the soft tissue really moves
  EXPECT_LT(max_rot, 1e-9);
  EXPECT_LT(max_pos, 1e-9);  // m, on a 1.6 m walk 14 m away
  EXPECT_LT(max_z, 1e-9 * z_scale);
}

TEST(SkeletonTerms, TrackedSkeletonFollowsAWalk) {
  const auto [pos1, angle1] = tracking_error(1.0, Vec3::Zero());
  const auto [pos2, angle2] = tracking_error(2.0, Vec3::Zero());
  std::printf("tracking a walk (0.8 m/s), default springs, h = 1/60 s, 1 Newton step: max joint error "
              "%.2f mm / %.4f rad at 1 Hz, %.2f mm / %.4f rad at 2 Hz\n",
              1e3 * pos1, angle1, 1e3 * pos2, angle2);
  EXPECT_LT(pos1, 0.002);
  EXPECT_LT(angle1, 0.008);
  EXPECT_LT(pos2, 0.008);
  EXPECT_LT(angle2, 0.03);
}

}  // namespace
}  // namespace sflsh
