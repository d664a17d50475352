// The pelvis tracking metric of run_simulation: /frames/target_pelvis in the
// result file and the "pelvis vs motion root" line, on a tiny synthetic avatar
// (the box of tests/sim/synthetic_avatar.hpp carrying a T-pose SMPL skeleton).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/motion/builtin_motions.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

std::shared_ptr<const Avatar> tiny_avatar() {
  Avatar a = test::make_synthetic_avatar();
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  return std::make_shared<const Avatar>(std::move(a));
}

RunOptions tiny_options(bool bones_dynamic) {
  RunOptions o;
  o.progress = false;
  o.sim.bones_dynamic = bones_dynamic;
  o.skeleton.body_mass = 70.0;  // the box alone weighs < 1 kg; springs scale with the mass
  return o;
}

}  // namespace

TEST(PelvisTracking, DynamicBonesFollowTheMotionRootAndTheFileKeepsIt) {
  const auto avatar = tiny_avatar();
  const MotionClip motion = builtin_motion("jump", 1.0, 60);
  std::vector<FrameData> streamed;
  const SimulationResult r =
      run_simulation(avatar, motion, tiny_options(true), [&](const FrameData& f) { streamed.push_back(f); });
  ASSERT_EQ(r.num_frames, 31);
  ASSERT_EQ(r.frame_target_pelvis.size(), 31u);
  ASSERT_EQ(r.pelvis_frames, 31);

  // The target is the motion's pelvis: G_0 J̄_0 = J̄_0 + translation.
  double target_range = 0, mean = 0, max = 0;
  for (int i = 0; i < r.num_frames; ++i) {
    const Vec3 expected =
        avatar->joints_rest.row(0).transpose() + motion.sample(r.frame_time[i]).translation;
    EXPECT_LT((r.frame_target_pelvis[i] - expected).norm(), 1e-12) << "frame " << i;
    EXPECT_EQ(streamed[i].target_pelvis, r.frame_target_pelvis[i]);
    target_range = std::max(target_range, (r.frame_target_pelvis[i] - r.frame_target_pelvis[0]).norm());
    const double e = (r.frame_joints[i].row(0).transpose() - r.frame_target_pelvis[i]).norm();
    mean += e / r.num_frames;
    max = std::max(max, e);
  }
  EXPECT_GT(target_range, 0.05) << "the jump moves the root, so the metric measures something";
  EXPECT_NEAR(r.pelvis_error_mean, mean, 1e-12);
  EXPECT_NEAR(r.pelvis_error_max, max, 1e-12);
  EXPECT_GT(r.pelvis_error_max, 0.0) << "dynamic bones lag their springs a little";
  EXPECT_LT(r.pelvis_error_max, 0.005) << "20 Hz tracking springs keep the pelvis within millimetres";
  EXPECT_NE(r.describe().find("pelvis vs motion root: mean "), std::string::npos) << r.describe();
  std::printf("tiny avatar, builtin:jump 1 s, dynamic bones: pelvis vs motion root mean %.2f mm, max %.2f mm\n",
              1e3 * r.pelvis_error_mean, 1e3 * r.pelvis_error_max);

  test::TempDir tmp;
  write_simulation_result(r, tmp.file("r.h5"));
  {
    io::Hdf5File f(tmp.file("r.h5"), io::Hdf5File::Mode::Read);
    EXPECT_EQ(f.shape("/frames/target_pelvis"), (std::vector<std::int64_t>{31, 3}));
  }
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  ASSERT_EQ(b.frame_target_pelvis.size(), 31u);
  for (int i = 0; i < 31; ++i) EXPECT_EQ(b.frame_target_pelvis[i], r.frame_target_pelvis[i]);
  EXPECT_EQ(b.pelvis_frames, 31);
  EXPECT_NEAR(b.pelvis_error_mean, r.pelvis_error_mean, 1e-12);
  EXPECT_NEAR(b.pelvis_error_max, r.pelvis_error_max, 1e-12);
}

TEST(PelvisTracking, KinematicBonesAreExactlyOnTheTarget) {
  const SimulationResult r = run_simulation(tiny_avatar(), builtin_motion("jump", 0.5, 60), tiny_options(false));
  ASSERT_GT(r.pelvis_frames, 10);
  EXPECT_LT(r.pelvis_error_max, 1e-12);
}

TEST(PelvisTracking, StartsMovingWithTheMotion) {
  // A clip already moving at 3 m/s (a run) when it starts: starting at rest,
  // the springs need time to catch up; starting with the motion's velocity
  // (the default), the pelvis is on the target from the first frame.
  MotionClip run;
  run.name = "run";
  run.fps = 120;
  for (int f = 0; f <= 60; ++f) {
    run.rotations.emplace_back(24, Eigen::Quaterniond::Identity());
    run.translations.emplace_back(0.0, 0.0, 3.0 * f / run.fps);
  }
  RunOptions o = tiny_options(true);
  // Soft springs (5 Hz) and no gravity: the lag of a late start is then
  // centimetres and nothing else pulls the pelvis off the target.
  o.skeleton.tracking_frequency_hz = 5;
  o.sim.gravity = Vec3::Zero();
  const SimulationResult moving = run_simulation(tiny_avatar(), run, o);
  o.start_at_rest = true;
  const SimulationResult rest = run_simulation(tiny_avatar(), run, o);
  std::printf("3 m/s from t = 0: pelvis max %.2f mm starting with the motion, %.2f mm starting at rest\n",
              1e3 * moving.pelvis_error_max, 1e3 * rest.pelvis_error_max);
  EXPECT_LT(moving.pelvis_error_max, 0.001);
  EXPECT_GT(rest.pelvis_error_max, 0.01);
}

TEST(PelvisTracking, MetricSeesAPelvisOffTheTarget) {
  // A result whose simulated pelvis is 3 cm / 4 cm from the target: the metric
  // read back from the file says so (it can fail).
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "m";
  r.dt = 1.0 / 60;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Zero(3, 3);
  for (int f = 0; f < 2; ++f) {
    r.frame_time.push_back(f / 30.0);
    r.frame_step_ms.push_back(1.0);
    r.frame_positions.push_back(Points::Zero(3, 3));
    r.frame_displacement.push_back(Points::Zero(3, 3));
    r.frame_joints.push_back(Points::Zero(24, 3));
    r.frame_reduced.push_back(VecX::Zero(3));
    r.frame_target_pelvis.push_back(Vec3(0, f ? 0.04 : 0.03, 0));
  }
  r.num_frames = 2;
  r.step_time = {1.0 / 60, 2.0 / 60};
  r.step_energy = r.step_grad_norm = r.step_decrement = r.step_ms = {0.0, 0.0};
  r.step_outcome = {0, 0};
  test::TempDir tmp;
  write_simulation_result(r, tmp.file("r.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  EXPECT_NEAR(b.pelvis_error_mean, 0.035, 1e-12);
  EXPECT_NEAR(b.pelvis_error_max, 0.04, 1e-12);
  EXPECT_NE(b.describe().find("pelvis vs motion root: mean 35.0 mm, max 40.0 mm"), std::string::npos) << b.describe();
}

TEST(PelvisTracking, FilesWithoutTheDatasetStillRead) {
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "m";
  r.dt = 1.0 / 60;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Zero(3, 3);
  r.frame_time = {0.0};
  r.frame_step_ms = {0.0};
  r.frame_positions = r.frame_displacement = {Points::Zero(3, 3)};
  r.frame_joints = {Points::Zero(24, 3)};
  r.frame_reduced = {VecX::Zero(3)};
  r.num_frames = 1;
  test::TempDir tmp;
  write_simulation_result(r, tmp.file("r.h5"));
  {
    io::Hdf5File f(tmp.file("r.h5"), io::Hdf5File::Mode::Read);
    EXPECT_FALSE(f.has("/frames/target_pelvis"));
  }
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  EXPECT_TRUE(b.frame_target_pelvis.empty());
  EXPECT_EQ(b.pelvis_frames, 0);
  EXPECT_EQ(b.describe().find("pelvis"), std::string::npos);
}
