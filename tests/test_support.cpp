#include "test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sys/wait.h>

namespace sflsh::test {

TempDir::TempDir() {
  std::random_device rd;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "sflsh";
  for (auto& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  path_ = std::filesystem::temp_directory_path() / ("sflsh_test_" + name + "_" + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string shared_data(const std::string& rel) {
  // $SFLSH_SHARED_DIR overrides the build-time ../shared (a git worktree elsewhere).
  const char* env = std::getenv("SFLSH_SHARED_DIR");
  std::filesystem::path p = std::filesystem::path(env && *env ? env : SFLSH_SHARED_DIR) / "data" / rel;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

std::string source_dir() { return SFLSH_SOURCE_DIR; }
std::string sflsh_binary() { return SFLSH_BINARY; }

int run_command(const std::string& cmd, std::string* output) {
  std::string full = cmd + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf;
  std::string out;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace sflsh::test
