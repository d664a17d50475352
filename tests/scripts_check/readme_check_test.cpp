// scripts/check_readme_figures.py: every figure the README quotes occurs
// literally in the results file its paragraph, item or table caption links;
// the README has at most 300 lines, names no work session or issue, and its
// marked example block equals the compiled file. Crafted READMEs and results
// in a temporary folder (a figure missing from its file must fail, naming the
// README line and the file), then the real README.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "test_support.hpp"

using namespace sflsh;

namespace {

const char* kPython = "/usr/bin/python3";

void write(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

/// A repository root with one results file and one example.
struct CraftedRepo {
  test::TempDir dir;
  CraftedRepo() {
    write(dir.file("scripts/results/bench.md"),
          "| K | rel_err | ms |\n|---|---|---|\n| 96 | 0.175 | 1.72 |\nRMS error 13 % over 2–10 mm; 1.97× from 1 to 2 threads\n");
    write(dir.file("scripts/results/stress.md"), "within 8.8 mm of the root; det F 0.386\n");
    write(dir.file("apps/examples/example.cpp"), "int main() {\n  return 0;\n}\n");
  }
  /// Runs the checker on README text; returns its exit code, its output in *out.
  int check(const std::string& readme, std::string* out) {
    write(dir.file("README.md"), readme);
    return test::run_command(std::string(kPython) + " " + test::source_dir() + "/scripts/check_readme_figures.py --root " +
                                 dir.path().string(),
                             out);
  }
};

const std::string kGood =
    "# tool\n"
    "\n"
    "Defaults, not measured: a 2 mm spacing, 0.1 mm per 10 kPa.\n"
    "\n"
    "<!-- example: apps/examples/example.cpp -->\n"
    "```cpp\n"
    "int main() {\n"
    "  return 0;\n"
    "}\n"
    "```\n"
    "\n"
    "## Results\n"
    "\n"
    "- `jump`: rel_err 0.175, 1.72 ms per step, 16 avatars at K = 96,\n"
    "  RMS error 13 %, 1.97× ([bench.md](scripts/results/bench.md)).\n"
    "- Stability: within 8.8 mm, det F 0.386 ([stress.md](scripts/results/stress.md)).\n"
    "\n"
    "Figures of [bench.md](scripts/results/bench.md):\n"
    "\n"
    "| K | rel_err |\n"
    "|---|---|\n"
    "| 96 | 0.175 |\n";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

bool has_numpy_free_python() {
  std::string out;
  return test::run_command(std::string(kPython) + " -c 'import re, argparse'", &out) == 0;
}

TEST(ReadmeCheck, AReadmeQuotingOnlyLinkedFiguresPasses) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  CraftedRepo repo;
  std::string out;
  EXPECT_EQ(repo.check(kGood, &out), 0) << out;
}

TEST(ReadmeCheck, AFigureMissingFromItsLinkedFileFailsNamingTheLineAndTheFile) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  CraftedRepo repo;
  std::string out;
  // 0.176 is not in bench.md (0.175 is); the continuation line belongs to the item that links bench.md.
  EXPECT_EQ(repo.check(replaced(kGood, "RMS error 13 %", "RMS error 13 %, rel_err 0.176"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:15: '0.176' is not in scripts/results/bench.md"), std::string::npos) << out;
  // A percentage must occur as a percentage; a figure is not a prefix of a longer number.
  EXPECT_EQ(repo.check(replaced(kGood, "RMS error 13 %", "RMS error 12 %, 0.17"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:15: '12 %' is not in scripts/results/bench.md"), std::string::npos) << out;
  EXPECT_NE(out.find("README.md:15: '0.17' is not in scripts/results/bench.md"), std::string::npos) << out;
  // A table row is checked against its caption's link.
  EXPECT_EQ(repo.check(replaced(kGood, "| 96 | 0.175 |", "| 96 | 0.185 |"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:22: '0.185' is not in scripts/results/bench.md"), std::string::npos) << out;
  // A figure of another file: each item is checked against its own links only.
  EXPECT_EQ(repo.check(replaced(kGood, "det F 0.386", "det F 0.386, rel_err 0.175"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:16: '0.175' is not in scripts/results/stress.md"), std::string::npos) << out;
}

TEST(ReadmeCheck, ResultsWithoutALinkOrWithAMissingFileFail) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  CraftedRepo repo;
  std::string out;
  EXPECT_EQ(repo.check(kGood + "\n- Throughput: 549 avatar-steps/s.\n", &out), 1) << out;
  EXPECT_NE(out.find("README.md:24: figures 549 in \"Results\" without a link"), std::string::npos) << out;
  EXPECT_EQ(repo.check(replaced(kGood, "scripts/results/stress.md", "scripts/results/gone.md"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:16: links scripts/results/gone.md, which does not exist"), std::string::npos) << out;
}

TEST(ReadmeCheck, LengthWorkLabelsAndTheExampleAreChecked) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  CraftedRepo repo;
  std::string out;
  std::string long_readme = kGood;
  for (int i = 0; i < 300; ++i) long_readme = "\n" + long_readme;
  EXPECT_EQ(repo.check(long_readme, &out), 1) << out;
  EXPECT_NE(out.find("README.md: 322 lines (at most 300)"), std::string::npos) << out;
  EXPECT_EQ(repo.check(replaced(kGood, "Defaults, not measured", "Since session 12 (issue 13), defaults"), &out), 1)
      << out;
  EXPECT_NE(out.find("README.md:3: names a work session or issue ('session 12')"), std::string::npos) << out;
  EXPECT_NE(out.find("README.md:3: names a work session or issue ('issue 13')"), std::string::npos) << out;
  EXPECT_EQ(repo.check(replaced(kGood, "  return 0;\n", "  return 1;\n"), &out), 1) << out;
  EXPECT_NE(out.find("README.md:6: the code block differs from apps/examples/example.cpp"), std::string::npos) << out;
}

TEST(ReadmeCheck, RequireStampRefusesLinksToFilesTheReproductionDidNotWrite) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  CraftedRepo repo;
  // What scripts/reproduce.sh (a full run, not --quick) puts at the top of a generated Markdown file.
  write(repo.dir.file("scripts/results/stress.md"),
        "<!-- Generated file -->\n> Generated by `scripts/reproduce.sh` (step stress_suite) at commit abc1234, ...\n\n"
        "within 8.8 mm of the root; det F 0.386\n");
  std::string out;
  write(repo.dir.file("README.md"), kGood);
  const std::string cmd = std::string(kPython) + " " + test::source_dir() +
                          "/scripts/check_readme_figures.py --require-stamp --root " + repo.dir.path().string();
  EXPECT_EQ(test::run_command(cmd, &out), 1) << out;
  EXPECT_NE(out.find("README.md:14: links scripts/results/bench.md, which a full scripts/reproduce.sh run did not "
                     "generate (no stamp)"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("stress.md"), std::string::npos) << out;
  EXPECT_EQ(out.find("README.md:18"), std::string::npos) << out;  // one line per file
  EXPECT_EQ(repo.check(kGood, &out), 0) << out;                     // without the option: figures only
}

TEST(ReadmeCheck, TheRealReadmePasses) {
  if (!has_numpy_free_python()) GTEST_SKIP() << kPython << " missing";
  std::string out;
  const int code =
      test::run_command(std::string(kPython) + " " + test::source_dir() + "/scripts/check_readme_figures.py", &out);
  EXPECT_EQ(code, 0) << out;
}

}  // namespace
