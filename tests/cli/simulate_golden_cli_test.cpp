// Golden results of `sflsh simulate --avatar --motion` end to end (flags,
// model, start, stepping, frame output, result file, checkpoint and resume),
// recorded at commit 3da039e on a small synthetic avatar (the box of
// tests/sim/synthetic_avatar.hpp carrying a T-pose skeleton). The result
// file's frames and steps are pinned bit for bit (a hash of every double), so
// any change of the one-avatar run — its model, its start, its loop or what it
// writes — shows; sums print next to the hashes to tell how far a change went.
//
// To re-record after an intended change of the physics (never for a refactor):
//   SFLSH_PRINT_GOLDEN=1 build/test_cli --gtest_filter='SimulateGoldenCli.*'
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sim/skeleton_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using test::BitHash;

struct Golden {
  std::string state_hash;   ///< frames: positions, displacement, joints, z, times
  std::string target_hash;  ///< frames: the motion's pelvis
  std::string steps_hash;   ///< steps: time, energy, gradient norm, decrement, outcome
  long frames = 0, steps = 0;
};

Golden fingerprint(const SimulationResult& r, double* z_sum) {
  BitHash state, target, steps;
  *z_sum = 0;
  for (size_t i = 0; i < r.frame_time.size(); ++i) {
    state.add(r.frame_time[i]);
    state.add_matrix(r.frame_positions[i]);
    state.add_matrix(r.frame_displacement[i]);
    state.add_matrix(r.frame_joints[i]);
    state.add_matrix(r.frame_reduced[i]);
    *z_sum += r.frame_reduced[i].sum();
  }
  for (const Vec3& p : r.frame_target_pelvis) target.add_matrix(p);
  for (size_t i = 0; i < r.step_time.size(); ++i) {
    steps.add(r.step_time[i]);
    steps.add(r.step_energy[i]);
    steps.add(r.step_grad_norm[i]);
    steps.add(r.step_decrement[i]);
    steps.add(long(r.step_outcome[i]));
  }
  return {state.hex(), target.hex(), steps.hex(), long(r.frame_time.size()), long(r.step_time.size())};
}

/// Synthetic box (8 hat handles, sampled cubature) carrying the T-pose skeleton.
std::string write_golden_avatar(const test::TempDir& dir) {
  const std::string path = dir.file("a.h5");
  write_avatar(*test::make_tpose_box(8, 12), path);
  return path;
}

void simulate(const std::string& args) {
  std::string out;
  ASSERT_EQ(test::run_command(test::sflsh_binary() + " -q simulate " + args, &out), 0) << args << "\n" << out;
}

void expect_golden(const char* name, const std::string& result_file, const Golden& golden) {
  const SimulationResult r = read_simulation_result(result_file);
  double z_sum = 0;
  const Golden g = fingerprint(r, &z_sum);
  if (std::getenv("SFLSH_PRINT_GOLDEN")) {
    std::printf("%s: {\"%s\", \"%s\", \"%s\", %ld, %ld}  (z sum %.17g, pelvis error mean %.17g)\n", name,
                g.state_hash.c_str(), g.target_hash.c_str(), g.steps_hash.c_str(), g.frames, g.steps, z_sum,
                r.pelvis_error_mean);
    return;
  }
  EXPECT_EQ(g.frames, golden.frames) << name;
  EXPECT_EQ(g.steps, golden.steps) << name;
  EXPECT_EQ(g.state_hash, golden.state_hash) << name << ": the frames changed (z sum " << z_sum << ")";
  EXPECT_EQ(g.target_hash, golden.target_hash) << name << ": the motion's pelvis in the frames changed";
  EXPECT_EQ(g.steps_hash, golden.steps_hash) << name << ": the steps' energies or outcomes changed";
}

const Golden GOLDEN_DYNAMIC{"0b82acf1afa56b46", "b46424bd4e75786c", "4dda7b2b20bb9d20", 16, 30};
const Golden GOLDEN_KINEMATIC_AT_REST{"95dc5f2e82c0011e", "34a169f6e3428336", "5a8bdb05eb4ce545", 19, 24};
const Golden GOLDEN_RESUMED{"10f9526446b319b2", "7c4cddd95bd91c11", "6b90f28ff881bdb2", 6, 30};

}  // namespace

TEST(SimulateGoldenCli, DynamicBonesJump) {
  test::TempDir dir;
  const std::string avatar = write_golden_avatar(dir);
  simulate("--avatar " + avatar + " --motion builtin:jump --seconds 0.5 --out " + dir.file("r.h5"));
  expect_golden("GOLDEN_DYNAMIC", dir.file("r.h5"), GOLDEN_DYNAMIC);
}

TEST(SimulateGoldenCli, KinematicBonesFromRestWithDampingAndOutputRate) {
  test::TempDir dir;
  const std::string avatar = write_golden_avatar(dir);
  simulate("--avatar " + avatar + " --motion builtin:shake --seconds 0.4 --bones kinematic --start-at-rest " +
           "--damping 0.01 --output-fps 45 --newton-iters 2 --out " + dir.file("r.h5"));
  expect_golden("GOLDEN_KINEMATIC_AT_REST", dir.file("r.h5"), GOLDEN_KINEMATIC_AT_REST);
}

TEST(SimulateGoldenCli, CheckpointThenResume) {
  test::TempDir dir;
  const std::string avatar = write_golden_avatar(dir);
  const std::string common = "--avatar " + avatar + " --motion builtin:jump --dt 1/120 --output-fps 20 ";
  simulate(common + "--seconds 0.25 --checkpoint " + dir.file("c.h5") + " --out " + dir.file("first.h5"));
  simulate(common + "--seconds 0.5 --resume " + dir.file("c.h5") + " --out " + dir.file("r.h5"));
  expect_golden("GOLDEN_RESUMED", dir.file("r.h5"), GOLDEN_RESUMED);
}
