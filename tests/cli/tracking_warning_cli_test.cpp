// `sflsh simulate` with dynamic bones warns when the pelvis strays from the
// motion's root by more than --tracking-tolerance (mm), quoting the same
// maximum the run reports; --strict makes it an error (exit != 0) after the
// result is written; within the tolerance nothing is said.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <regex>

#include "sflsh/asset/avatar_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

TEST(TrackingWarningCli, WarnsBeyondTheToleranceAndStrictFails) {
  const fs::path dir = fs::temp_directory_path() / ("sflsh_tracking_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_avatar(test::make_synthetic_avatar(), (dir / "a.h5").string());
  const std::string base = test::sflsh_binary() + " -q simulate --avatar " + (dir / "a.h5").string() +
                           " --motion builtin:shake --dt 1/30 --seconds 1 --out " + (dir / "r.h5").string();
  std::string out;
  ASSERT_EQ(test::run_command(base + " 2>&1", &out), 0) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("pelvis vs motion root: mean [0-9.]+ mm, max ([0-9.]+) mm"))) << out;
  const double max_mm = std::stod(m[1]);
  ASSERT_GT(max_mm, 0.05);
  EXPECT_EQ(out.find("warning: the pelvis"), std::string::npos) << out;  // default 20 mm: within
  const std::string tight = " --tracking-tolerance " + std::to_string(0.5 * max_mm);
  ASSERT_EQ(test::run_command(base + tight + " 2>&1", &out), 0) << out;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("warning: the pelvis strayed up to ([0-9.]+) mm"))) << out;
  EXPECT_NEAR(std::stod(m[1]), max_mm, 0.051);
  fs::remove(dir / "r.h5");
  EXPECT_NE(test::run_command(base + tight + " --strict 2>&1", &out), 0) << out;
  EXPECT_NE(out.find("simulate --strict: the pelvis strayed"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(dir / "r.h5"));  // the result is kept: it is valid, only off its motion
  EXPECT_EQ(test::run_command(base + " --tracking-tolerance " + std::to_string(2 * max_mm) + " --strict 2>&1", &out), 0)
      << out;
  fs::remove_all(dir);
}
