// `sflsh simulate scene.yaml --checkpoint / --resume` end to end on the small
// box avatar with a grasping tool: a run stopped while the tool holds the
// skin and resumed from its checkpoint ends as the uninterrupted run, bit for
// bit, with the release in the resumed part; bad flags are one error line, a
// non-zero exit and no output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/result_file.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

using SimulateSceneCheckpointCli = test::BoxAvatarScene;

int sflsh_simulate(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q simulate " + args + " 2>&1", out);
}

/// The box pinch (closes at 0.05 s, lifts, opens at 0.25 s) ending at `seconds`.
std::string pinch(const std::string& seconds) {
  std::string text = test::kBoxPinchScene;
  const std::string key = "seconds: 0.3";
  return text.replace(text.find(key), key.size(), "seconds: " + seconds);
}

}  // namespace

TEST_F(SimulateSceneCheckpointCli, AGraspingRunResumesFromItsCheckpointBitForBit) {
  std::ofstream(dir_ / "first.yaml") << pinch("0.15");
  std::ofstream(dir_ / "whole.yaml") << pinch("0.3");
  const fs::path checkpoint = dir_ / "c.h5", first = dir_ / "first.h5", rest = dir_ / "rest.h5",
                 whole = dir_ / "whole.h5";
  std::string out;
  ASSERT_EQ(sflsh_simulate((dir_ / "first.yaml").string() + " --checkpoint " + checkpoint.string() + " --out " +
                               first.string(),
                           &out),
            0)
      << out;
  EXPECT_NE(out.find("grasp"), std::string::npos) << out;
  ASSERT_TRUE(fs::exists(checkpoint));
  ASSERT_EQ(sflsh_simulate((dir_ / "whole.yaml").string() + " --resume " + checkpoint.string() + " --out " +
                               rest.string(),
                           &out),
            0)
      << out;
  EXPECT_NE(out.find("15 steps"), std::string::npos) << out;
  EXPECT_NE(out.find("release"), std::string::npos) << out;
  EXPECT_EQ(out.find(": grasp"), std::string::npos) << "the grasp was before the checkpoint\n" << out;
  ASSERT_EQ(sflsh_simulate((dir_ / "whole.yaml").string() + " --out " + whole.string(), &out), 0) << out;
  const SimulationResult r = read_simulation_result(rest.string()), w = read_simulation_result(whole.string());
  EXPECT_EQ(r.frame_time.back(), w.frame_time.back());
  EXPECT_EQ(r.frame_positions.back(), w.frame_positions.back());
  // The grasp lifted the skin: the comparison is of a moved surface.
  EXPECT_GT((w.frame_positions.back() - w.frame_positions.front()).cwiseAbs().maxCoeff(), 1e-5);
}

TEST_F(SimulateSceneCheckpointCli, BadFlagsAreOneErrorLineAndNoOutput) {
  std::ofstream(dir_ / "whole.yaml") << pinch("0.3");
  const std::string scene = (dir_ / "whole.yaml").string();
  const fs::path never = dir_ / "never.h5";
  std::string out;
  EXPECT_NE(sflsh_simulate(scene + " --resume " + (dir_ / "missing.h5").string() + " --out " + never.string(), &out), 0);
  EXPECT_NE(out.find("--resume"), std::string::npos) << out;
  EXPECT_NE(out.find("not found"), std::string::npos) << out;
  EXPECT_NE(sflsh_simulate(scene + " --solver full --checkpoint " + (dir_ / "c.h5").string() + " --out " +
                               never.string(),
                           &out),
            0);
  EXPECT_NE(out.find("reduced solver"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(never));
  EXPECT_FALSE(fs::exists(dir_ / "c.h5"));
}
