// Golden results of `sflsh simulate --avatar --motion` end to end (flags,
// model, start, stepping, frame output, result file, checkpoint and resume),
// recorded at commit 3da039e on a small synthetic avatar (the box of
// tests/sim/synthetic_avatar.hpp carrying a T-pose skeleton). The result
// file's frames, steps and bones are pinned as fingerprints (weighted sums of
// every double, within 1e-9 relative: test_support.hpp, kGoldenRelative), so
// any change of the one-avatar run — its model, its start, its loop or what it
// writes — shows.
//
// To re-record after an intended change of the physics (never for a refactor):
//   SFLSH_PRINT_GOLDEN=1 build/test_cli --gtest_filter='SimulateGoldenCli.*'
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sim/skeleton_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

struct Golden {
  std::vector<double> state;   ///< frames: times, positions, displacement, joints, z
  std::vector<double> target;  ///< frames: the motion's pelvis
  std::vector<double> steps;   ///< steps: time, energy, gradient norm, decrement, outcome; bones at the start and per step
  long frames = 0, steps_taken = 0;
};

double bones_sum(const std::vector<std::vector<Isometry>>& seq) {
  double s = 0;
  for (size_t i = 0; i < seq.size(); ++i)
    for (size_t j = 0; j < seq[i].size(); ++j) s += double((i + j) % 5 + 1) * test::weighted_sum(seq[i][j].matrix());
  return s;
}

Golden fingerprint(const SimulationResult& r) {
  Golden g;
  double t = 0, x = 0, u = 0, J = 0, z = 0, pelvis = 0;
  for (size_t i = 0; i < r.frame_time.size(); ++i) {
    const double w = double(i % 5 + 1);
    t += w * r.frame_time[i];
    x += w * test::weighted_sum(r.frame_positions[i]);
    u += w * test::weighted_sum(r.frame_displacement[i]);
    J += w * test::weighted_sum(r.frame_joints[i]);
    z += w * test::weighted_sum(r.frame_reduced[i]);
  }
  for (size_t i = 0; i < r.frame_target_pelvis.size(); ++i)
    pelvis += double(i % 5 + 1) * test::weighted_sum(r.frame_target_pelvis[i]);
  auto series = [](const auto& v) {
    double s = 0;
    for (size_t i = 0; i < v.size(); ++i) s += double(i % 5 + 1) * double(v[i]);
    return s;
  };
  g.state = {t, x, u, J, z};
  g.target = {pelvis};
  g.steps = {series(r.step_time),     series(r.step_energy),  series(r.step_grad_norm), series(r.step_decrement),
             series(r.step_outcome),  bones_sum(r.start_bones), bones_sum(r.step_bones)};
  g.frames = long(r.frame_time.size());
  g.steps_taken = long(r.step_time.size());
  return g;
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
  const Golden g = fingerprint(r);
  if (std::getenv("SFLSH_PRINT_GOLDEN")) {
    std::printf("GOLDEN %s | %s | %s | %s | %ld | %ld\n", name, test::print_fingerprint(g.state).c_str(),
                test::print_fingerprint(g.target).c_str(), test::print_fingerprint(g.steps).c_str(), g.frames,
                g.steps_taken);
    return;
  }
  EXPECT_EQ(g.frames, golden.frames) << name;
  EXPECT_EQ(g.steps_taken, golden.steps_taken) << name;
  test::expect_fingerprint(g.state, golden.state, std::string(name) + ": the frames");
  test::expect_fingerprint(g.target, golden.target, std::string(name) + ": the motion's pelvis in the frames");
  test::expect_fingerprint(g.steps, golden.steps, std::string(name) + ": the steps' energies, outcomes or bones");
}

const Golden GOLDEN_DYNAMIC{
    {12.000000000000002, 166.61519442043755, -6.0158347984898271, 4778.3389406374235, -1.1926531717444551},
    {89.46196748214399},
    {24.249999999999996, -568.41040732286058, 34948.233817236112, 154.98719852793224, 0, 1871.7380172264575, 28907.272959046557},
    16, 30};
const Golden GOLDEN_KINEMATIC_AT_REST{
    {11.733333333333333, 316.99871647416239, -10.383239941553484, 5461.1501227129293, -2.0311784458031283},
    {104.40165072955526},
    {14.999999999999998, -489.88512667048565, 423.12927971704136, 5.6040042163792334, 0, 1872, 22710.693714828576},
    19, 24};
const Golden GOLDEN_RESUMED{
    {6.25, -33.043906994518693, -1.8539945331904164, 1620.3719430466952, -0.33863772807862474},
    {31.006390898995548},
    {34.624999999999993, -593.47582898674159, 58255.535615585242, 139.41744665077431, 0, 1959.304539124053, 29202.062994508673},
    6, 30};

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
