// Bad numbers and unusable outputs are rejected before any work, with one
// line naming the option and the file, an exit code in 1..127, no output file
// and no .partial left; an interrupted `simulate` removes its partial result
// and exits 128 + signal.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include "sflsh/asset/avatar_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

extern char** environ;

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

struct Outcome {
  int code = 0;
  std::string output;
};

Outcome run(const std::string& args, const std::string& env = "") {
  Outcome o;
  o.code = test::run_command(env + test::sflsh_binary() + " -q " + args, &o.output);
  return o;
}

int count_lines(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) ++n;
  return n;
}

// One failing case: exit in 1..127, exactly one line holding every fragment,
// and none of `outputs` (nor its .partial) left behind.
void expect_clean_failure(const std::string& args, const std::vector<std::string>& fragments,
                          const std::vector<std::string>& outputs, const std::string& env = "") {
  SCOPED_TRACE(args);
  const Outcome o = run(args, env);
  EXPECT_GE(o.code, 1) << o.output;
  EXPECT_LE(o.code, 127) << o.output;
  EXPECT_EQ(count_lines(o.output), 1) << o.output;
  for (const auto& f : fragments) EXPECT_NE(o.output.find(f), std::string::npos) << "missing '" << f << "' in\n" << o.output;
  for (const auto& p : outputs) {
    EXPECT_FALSE(fs::exists(p) && !fs::is_directory(p)) << p << " was written";
    EXPECT_FALSE(fs::exists(p + ".partial")) << p << ".partial was left";
  }
}

class OutputCheckCli : public ::testing::Test {
 protected:
  void SetUp() override {
    write_avatar(test::make_synthetic_avatar(), dir_.file("a.h5"));
    std::ofstream(dir_.file("plain_file")) << "not a folder\n";
    fs::create_directories(dir_.file("folder.h5"));
    fs::create_directories(dir_.file("folder.obj"));
  }
  std::string avatar() const { return " --avatar " + dir_.file("a.h5"); }
  test::TempDir dir_;
};

}  // namespace

TEST_F(OutputCheckCli, SimulateRejectsSecondsThatAreNotPositive) {
  const std::string out = dir_.file("r.h5");
  for (const char* s : {"nan", "-1", "0", "inf"})
    expect_clean_failure("simulate" + avatar() + " --seconds " + s + " --out " + out, {"--seconds"}, {out});
  expect_clean_failure("simulate" + avatar() + " --output-fps nan --out " + out, {"--output-fps"}, {out});
  expect_clean_failure("simulate" + avatar() + " --speed 0 --out " + out, {"--speed"}, {out});
  expect_clean_failure("bench --quick --seconds nan --out " + dir_.file("b"), {"--seconds"}, {dir_.file("b")});
  EXPECT_FALSE(fs::exists(dir_.file("b")));
}

TEST_F(OutputCheckCli, UnwritableOutputsFailBeforeTheWorkStarts) {
  const std::string folder_h5 = dir_.file("folder.h5"), under_file = dir_.file("plain_file") + "/x";
  const std::string r = dir_.file("r.h5");
  struct Case {
    std::string args;
    std::vector<std::string> fragments, outputs;
  } cases[] = {
      {"simulate" + avatar() + " --out " + folder_h5, {"--out", folder_h5, "is a folder"}, {}},
      {"simulate" + avatar() + " --out " + under_file + ".h5", {"--out", "plain_file", "not a folder"}, {}},
      {"simulate" + avatar() + " --out " + r + " --render " + folder_h5, {"--render", folder_h5, "is a folder"}, {r}},
      {"simulate" + avatar() + " --out " + r + " --export " + under_file + ".pc2", {"--export", "plain_file"}, {r}},
      {"stress" + avatar() + " --out " + dir_.file("plain_file"), {"--out", "plain_file", "not a folder"}, {}},
      {"stress" + avatar() + " --out " + under_file, {"--out", "plain_file", "not a folder"}, {}},
      {"bench --quick --out " + dir_.file("plain_file"), {"--out", "plain_file", "not a folder"}, {}},
      {"precompute --out " + folder_h5, {"--out", folder_h5, "is a folder"}, {}},
      {"precompute --out " + under_file + ".h5", {"--out", "plain_file", "not a folder"}, {}},
      {"precompute --batch " + dir_.file("none.csv") + " --out-dir " + dir_.file("plain_file"),
       {"--out-dir", "plain_file", "not a folder"}, {}},
      {"body export --out " + dir_.file("folder.obj"), {"--out", "folder.obj", "is a folder"}, {}},
      {"body export --out " + dir_.file("b.obj") + " --joints " + under_file + ".json",
       {"--joints", "plain_file", "not a folder"}, {dir_.file("b.obj")}},
      {"body render --out " + under_file + ".png", {"--out", "plain_file", "not a folder"}, {}},
  };
  // Before the work: precompute and bench would build the template stage into
  // the cache folder ($SFLSH_CACHE_DIR), which must stay empty.
  const std::string cache = dir_.file("cache");
  for (const auto& c : cases) {
    expect_clean_failure(c.args, c.fragments, c.outputs, "SFLSH_CACHE_DIR=" + cache + " ");
    EXPECT_TRUE(!fs::exists(cache) || fs::is_empty(cache)) << c.args << ": the template stage was started";
  }
  fs::remove_all(cache);
  EXPECT_TRUE(fs::is_directory(folder_h5)) << "an output check must not touch what is there";
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_.path()), fs::directory_iterator()), 4)
      << "no file or folder was created next to the inputs";
}

TEST_F(OutputCheckCli, StressWithAMissingMotionLeavesNoOutputFolder) {
  const std::string out = dir_.file("stress_out");
  expect_clean_failure("stress" + avatar() + " --steps 5 --motion " + dir_.file("missing.bvh") + " --out " + out,
                       {"missing.bvh"}, {});
  EXPECT_FALSE(fs::exists(out)) << "an empty --out folder was left behind";
}

// Starts `sflsh simulate` on a long run, waits until the partial result exists
// and a few frames are in, sends `sig`, and checks what is left.
void interrupt_simulation(const test::TempDir& dir, int sig, int expected_code) {
  const std::string out = dir.file("long.h5"), log = dir.file("log.txt");
  const std::string bin = test::sflsh_binary();
  std::vector<std::string> args = {bin, "-q", "simulate", "--avatar", dir.file("a.h5"), "--motion", "builtin:shake",
                                   "--seconds", "600", "--out", out};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, bin.c_str(), &fa, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  bool started = false;
  for (int i = 0; i < 600 && !started; ++i) {  // up to 60 s for loading and the first frames
    std::error_code ec;
    started = fs::exists(out + ".partial") && fs::file_size(out + ".partial", ec) > 0;
    if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(pid, sig);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  std::ifstream log_in(log);
  const std::string output((std::istreambuf_iterator<char>(log_in)), std::istreambuf_iterator<char>());
  ASSERT_TRUE(started) << "the run never wrote its partial file:\n" << output;
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of handling it:\n" << output;
  EXPECT_EQ(WEXITSTATUS(status), expected_code) << output;
  // The run had printed its motion report; the interruption adds one line, the last.
  std::vector<std::string> lines;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);)
    if (line.find_first_not_of(" \t\r") != std::string::npos) lines.push_back(line);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(std::count_if(lines.begin(), lines.end(), [](const std::string& l) { return l.rfind("sflsh:", 0) == 0; }), 1)
      << output;
  EXPECT_EQ(lines.back().rfind("sflsh: interrupted by", 0), 0u) << output;
  EXPECT_NE(lines.back().find("removed " + out + ".partial"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(out + ".partial"));
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(OutputCheckCli, SigintDuringSimulateRemovesThePartialResult) { interrupt_simulation(dir_, SIGINT, 130); }

TEST_F(OutputCheckCli, SigtermDuringSimulateRemovesThePartialResult) { interrupt_simulation(dir_, SIGTERM, 143); }
