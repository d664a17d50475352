// `sflsh run scene.yaml` end to end on the small box avatar: a run
// that records its tools' device poses and a --replay of that recording write
// identical result files; --realtime keeps in step with the clock (RTF
// reported) and runs the same number of steps; the tool log has a row per
// step; bad input (negative --seconds, a missing --replay folder, an unknown
// scene key) is one error line, a non-zero exit and no output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/result_file.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

using RunCli = test::BoxAvatarScene;

const char* kScene = R"(
solver: {dt: 1/250, seconds: 0.4, gravity: [0, 0, 0]}
output: {fps: 50}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.3, position: [0.0, 0.025, 0.0]}
    coupling: {stiffness: 2000, mass: 0.05}
)";

int sflsh_run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q run " + args + " 2>&1", out);
}

int lines(const fs::path& p) {
  std::ifstream in(p);
  std::string l;
  int n = 0;
  while (std::getline(in, l)) ++n;
  return n;
}

}  // namespace

TEST_F(RunCli, ARecordedRunReplaysToTheSameResultAndRealTimeReportsItsFactor) {
  const std::string scene = write_scene(kScene);
  const fs::path rec = dir_ / "rec", a = dir_ / "a.h5", b = dir_ / "b.h5", log = dir_ / "tools.csv";
  std::string out;
  ASSERT_EQ(sflsh_run(scene + " --quiet-status --record " + rec.string() + " --out " + a.string() + " --tool-log " +
                          log.string(),
                      &out),
            0)
      << out;
  EXPECT_NE(out.find("as fast as possible: simulated 0.400 s"), std::string::npos) << out;
  EXPECT_NE(out.find("100 accepted, 0 damped, 0 rejected"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(rec / "probe.csv"));
  EXPECT_EQ(lines(log), 1 + 100);  // header + one row per step (one tool)
  EXPECT_TRUE(fs::exists(dir_ / "tools.svg"));
  ASSERT_EQ(sflsh_run(scene + " --quiet-status --replay " + rec.string() + " --out " + b.string(), &out), 0) << out;
  const SimulationResult ra = read_simulation_result(a.string()), rb = read_simulation_result(b.string());
  ASSERT_EQ(ra.num_frames, 21);
  ASSERT_EQ(rb.num_frames, ra.num_frames);
  EXPECT_EQ(rb.frame_positions.back(), ra.frame_positions.back());
  EXPECT_EQ(rb.objects.at(0).poses.back().matrix(), ra.objects.at(0).poses.back().matrix());
  // The probe pressed into the top: the skin moved.
  EXPECT_GT((ra.frame_positions.back() - ra.frame_positions.front()).cwiseAbs().maxCoeff(), 1e-3);

  ASSERT_EQ(sflsh_run(scene + " --realtime --quiet-status", &out), 0) << out;
  EXPECT_NE(out.find("real time: simulated 0.400 s"), std::string::npos) << out;
  EXPECT_NE(out.find("RTF"), std::string::npos) << out;
}

TEST_F(RunCli, BadInputIsOneErrorLineAndNoOutput) {
  const std::string scene = write_scene(kScene);
  const fs::path out_file = dir_ / "never.h5";
  std::string out;
  EXPECT_NE(sflsh_run(scene + " --seconds -1 --out " + out_file.string(), &out), 0);
  EXPECT_NE(out.find("--seconds"), std::string::npos) << out;
  EXPECT_NE(sflsh_run(scene + " --replay " + (dir_ / "nowhere").string() + " --out " + out_file.string(), &out), 0);
  EXPECT_NE(out.find("--replay"), std::string::npos) << out;
  std::ofstream(dir_ / "bad.yaml") << "solver: {dt: 1/250, seconds: 0.1}\nbodies:\n  - {name: b, avatar: box.h5}\n"
                                      "tools:\n  - {name: t, pose_stream: {port: 70000}}\n";
  EXPECT_NE(sflsh_run((dir_ / "bad.yaml").string() + " --out " + out_file.string(), &out), 0);
  EXPECT_NE(out.find("tools[0].pose_stream.port"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(out_file));
  EXPECT_FALSE(fs::exists(out_file.string() + ".partial"));
}
