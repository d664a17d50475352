// `sflsh stress` (and the new numeric options of bench/precompute): bad input
// gets one clear error and no output; a short run on a small avatar passes.
#include <gtest/gtest.h>

#include <filesystem>

#include "sflsh/asset/avatar_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

int run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q " + args, out);
}

}  // namespace

TEST(StressCli, BadInputFailsWithOneClearLine) {
  test::TempDir dir;
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));
  const std::string a = " --avatar " + dir.file("a.h5") + " --out " + dir.file("s");
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"stress --avatar " + dir.file("none.h5") + " --out " + dir.file("s"), {"none.h5", "not found"}},
      {"stress" + a + " --dt 1/0", {"--dt", "'1/0'", "not a time step"}},
      {"stress" + a + " --dt 0.5", {"--dt", "(0, 0.1]"}},
      {"stress" + a + " --steps 0", {"--steps", ">= 1"}},
      {"stress" + a + " --motion builtin:nope --steps 2", {"nope"}},
      {"precompute --elastic-samples-per-cell 0 --out " + dir.file("p.h5"), {"--elastic-samples-per-cell", "[1, 1000]"}},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_NE(run(c.args, &out), 0) << c.args;
    for (const auto& e : c.expect) EXPECT_NE(out.find(e), std::string::npos) << c.args << "\n" << out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("s") + "/stress.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir.file("p.h5")));
}

TEST(StressCli, ShortRunPassesAndWritesTableAndPlot) {
  test::TempDir dir;
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));
  std::string out;
  ASSERT_EQ(run("stress --avatar " + dir.file("a.h5") + " --steps 150 --out " + dir.file("s"), &out), 0) << out;
  EXPECT_NE(out.find("result: PASSED"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("s") + "/stress.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir.file("s") + "/stress.svg"));
}
