// `sflsh bench-contact`: bad input gets one clear line, a non-zero exit and no
// output folder (checked before any precompute or simulation starts).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
      {"bench-contact --out " + dir.file("plain_file"), {"--out", "plain_file", "not a folder"}},
  };
  for (const auto& c : cases) {
    std::string text;
    EXPECT_NE(test::run_command(test::sflsh_binary() + " -q " + c.args, &text), 0) << c.args;
    for (const auto& e : c.expect) EXPECT_NE(text.find(e), std::string::npos) << c.args << "\n" << text;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("b")));
}
