// `sflsh bench-contact`: bad input gets one clear line, a non-zero exit and no
// output folder (checked before any precompute or simulation starts); a scene
// file (--scene, on the small box avatar) gets its table, series and plot.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "scene/box_avatar_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;

TEST(ContactBenchCli, BadInputFailsWithOneClearLineAndNoOutput) {
  test::TempDir dir;
  { std::ofstream(dir.file("plain_file")) << "x"; }
  const std::string out = " --out " + dir.file("b");
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"bench-contact --handles 0" + out, {"--handles", "1 to 4096"}},
      {"bench-contact --handles 32,x" + out, {"--handles"}},
      {"bench-contact --newton-iters 0" + out, {"--newton-iters", ">= 1"}},
      {"bench-contact --pressure-stiffness -5" + out, {"--pressure-stiffness", "pressure stiffness -5"}},
      {"bench-contact --pressure-stiffness nan" + out, {"--pressure-stiffness", "pressure stiffness nan"}},
      {"bench-contact --spacing 0" + out, {"--spacing", "spacing 0"}},
      {"bench-contact --patch-radius 0" + out, {"--patch-radius", "positive"}},
      {"bench-contact --patch-radius nan" + out, {"--patch-radius", "positive"}},
      {"bench-contact --max-patch-nodes 0" + out, {"--max-patch-nodes", "1 to 1000000"}},
      {"bench-contact --max-patch-nodes 2.5" + out, {"--max-patch-nodes"}},
      {"bench-contact --out " + dir.file("plain_file"), {"--out", "plain_file", "not a folder"}},
  };
  for (const auto& c : cases) {
    std::string text;
    EXPECT_NE(test::run_command(test::sflsh_binary() + " -q " + c.args, &text), 0) << c.args;
    for (const auto& e : c.expect) EXPECT_NE(text.find(e), std::string::npos) << c.args << "\n" << text;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("b")));
}

namespace {

/// The number of non-empty lines of `text`.
int lines(const std::string& text) {
  int n = 0;
  size_t at = 0;
  while (at < text.size()) {
    const size_t end = std::min(text.find('\n', at), text.size());
    n += end > at;
    at = end + 1;
  }
  return n;
}

}  // namespace

using ContactBenchSceneCli = test::BoxAvatarScene;

TEST_F(ContactBenchSceneCli, BadSceneFilesFailWithOneLineNamingThemAndWriteNothing) {
  const std::string out = (dir_ / "b").string();
  const std::string run = test::sflsh_binary() + " -q bench-contact --out " + out + " --scene ";
  const std::string head = "solver: {dt: 1/100, seconds: 0.1}\nbodies:\n  - {name: base, avatar: box.h5}\n";
  struct Case {
    std::string scene;  // written to scene.yaml unless empty
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"", (dir_ / "missing.yaml").string(), {"--scene", "missing.yaml", "not found"}},
      {"solver: {dt: -1}\n" + head.substr(head.find("bodies")), "", {"scene.yaml:1", "solver.dt"}},
      {head + "  - {name: other, avatar: box.h5, placement: {offset: [0.2, 0, 0]}}\n", "", {"scene.yaml", "one body"}},
      {head + "tools:\n  - name: probe\n    shape: {type: sphere, radius: 0.005}\n"
              "    pose_stream: {port: 7001}\n    coupling: {stiffness: 2000}\n",
       "", {"scene.yaml", "tools 'probe'", "live stream"}},
      {head, "", {"scene.yaml", "touches no object"}},
      {head + "objects:\n  - {name: ball, shape: {type: sphere, radius: 0.01}, position: [0, 0.037, 0]}\n",
       " --handles 32", {"--handles", "built-in scenes"}},
  };
  for (const auto& c : cases) {
    const std::string scene = c.scene.empty() ? "" : write_scene(c.scene);
    const std::string args = scene + c.args;
    std::string text;
    EXPECT_NE(test::run_command(run + args, &text), 0) << args;
    for (const auto& e : c.expect) EXPECT_NE(text.find(e), std::string::npos) << args << "\n" << text;
    EXPECT_EQ(lines(text), 1) << args << "\n" << text;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
}

TEST_F(ContactBenchSceneCli, ASceneFileGetsItsTableSeriesAndPlot) {
  const std::string scene = write_scene(R"(solver: {dt: 1/100, seconds: 0.1, gravity: [0, 0, 0]}
contact: {friction: 0, patch: {radius: 0.02}}
bodies:
  - {name: base, avatar: box.h5, motion: none, bones: kinematic}
tools:
  - name: ball
    shape: {type: sphere, radius: 0.01}
    keyframes:
      - {time: 0.0, position: [0.0, 0.04, 0.0]}
      - {time: 0.1, position: [0.0, 0.036, 0.0]}
)");
  const std::filesystem::path out = dir_ / "b";
  std::string text;
  ASSERT_EQ(test::run_command(test::sflsh_binary() + " -q bench-contact --cpu-time --scene " + scene + " --out " +
                                  out.string(),
                              &text),
            0)
      << text;
  for (const char* f : {"contact_bench.md", "contact_scenes.csv", "contact_scene.csv", "contact_scene.svg"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f << "\n" << text;
  EXPECT_FALSE(std::filesystem::exists(out / "contact_bench.csv"));  // no built-in scene ran
  std::ifstream md((out / "contact_bench.md").string());
  const std::string table((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(table.find("--scene " + scene), std::string::npos) << table;
  EXPECT_NE(table.find("| ball | 1/100 |"), std::string::npos) << table;
  EXPECT_EQ(table.find("| pressed |"), std::string::npos) << table;
}
