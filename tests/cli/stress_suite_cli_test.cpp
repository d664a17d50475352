// `sflsh stress-suite` and the light-bone fix: bad input gets
// one clear error and no output; a short suite on a small avatar writes its
// CSV, markdown and plot and skips the CMU cases without data; `shake` at
// dt = 1/30 on the default body, which damped 1,666 of 10,000 steps before
// the joint springs were sized by the flesh they move, has no damped step.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

int run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q " + args, out);
}

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

TEST(StressSuiteCli, BadInputFailsWithOneClearLineAndWritesNothing) {
  test::TempDir dir;
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));
  const std::string a = "stress-suite --avatar " + dir.file("a.h5") + " --out " + dir.file("s");
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {a + " --cases nope", {"--cases", "unknown case 'nope'", "known: shake, torture"}},
      {a + " --cases shake,walkabout@1/30", {"unknown case 'walkabout'"}},
      {a + " --cases shake@1/0", {"shake@1/0", "'1/0'", "not a time step"}},
      {a + " --cases shake@0.5", {"shake@0.5", "(0, 0.1]"}},
      {a + " --cases shake@", {"shake@"}},
      {a + " --cases shake,,torture", {"--cases", "empty case name"}},
      {a + " --steps 0", {"--steps", ">= 1"}},
      {a + " --window 0", {"--window", ">= 1"}},
      {"stress-suite --avatar " + dir.file("none.h5") + " --out " + dir.file("s") + " --cases shake", {"none.h5"}},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_NE(run(c.args, &out), 0) << c.args;
    for (const auto& e : c.expect) EXPECT_NE(out.find(e), std::string::npos) << c.args << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << c.args << "\n" << out;  // one line
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("s")));
}

TEST(StressSuiteCli, ShortSuiteWritesTableAndPlotAndSkipsMissingMocap) {
  test::TempDir dir;
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));
  std::filesystem::create_directories(dir.file("no_mocap"));
  std::string out;
  ASSERT_EQ(run("stress-suite --avatar " + dir.file("a.h5") + " --steps 300 --window 10 --cases torture@1/15,cmu_2x" +
                    " --mocap-dir " + dir.file("no_mocap") + " --out " + dir.file("s"),
                &out),
            0)
      << out;
  const std::string csv = read_text(dir.file("s/stress_suite.csv"));
  const std::string md = read_text(dir.file("s/stress_suite.md"));
  // (A 40-step shake is still in its 0.5 s ease-in: its growth check would fail; torture jumps at once.
  // Since the bones take their full step after a damped iteration, the synthetic body's flesh
  // reaches its swing over ~10 s of torture: 300 steps, not 40, for the growth check.)
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << csv;  // header + 2 cases
  EXPECT_NE(csv.find("torture@1/15,ok,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("cmu_2x,skipped,"), std::string::npos) << csv;
  EXPECT_NE(md.find("no .bvh files"), std::string::npos) << md;
  EXPECT_NE(out.find("skipped"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("s/stress_suite.svg")));
  // 300 steps at 1/15 s: the row ran all its steps, no NaN.
  EXPECT_NE(csv.find("torture@1/15,ok,0.0666667,300,0,"), std::string::npos) << csv;
}

TEST(StressSuiteCli, ShakeOnTheDefaultBodyHasNoDampedStep) {
  // The configuration that damped (the default body, shake, dt = 1/30 s, bones
  // dynamic, 1 rad rotation cap): before the fix the right hand hit the cap
  // from step 14 on, one step in six. Needs the default avatar
  // (SFLSH_TEST_AVATAR or the session's shared copy); skipped without it.
  const char* env = std::getenv("SFLSH_TEST_AVATAR");
  const std::string avatar = env ? env : "/work/shared_tmp/default_avatar.h5";
  if (!std::filesystem::exists(avatar)) GTEST_SKIP() << "no default avatar at " << avatar << " (set SFLSH_TEST_AVATAR)";
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(run("stress --avatar " + avatar + " --steps 300 --dt 1/30 --out " + dir.file("s"), &out), 0) << out;
  EXPECT_NE(out.find("300 steps (300 accepted, 0 damped, 0 rejected)"), std::string::npos) << out;
}
