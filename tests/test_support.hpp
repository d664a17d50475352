#pragma once
// Helpers shared by the test executables.
#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>

#include "sflsh/core/error.hpp"

namespace sflsh::test {

/// A fresh, empty temporary folder for this test (removed at exit of the test).
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// Path of ../shared/data/<rel> ($SFLSH_SHARED_DIR/data/<rel> if set) or "" when absent
/// (tests then GTEST_SKIP() with a message saying so).
std::string shared_data(const std::string& rel);

/// The repository's source folder and the built sflsh executable.
std::string source_dir();
std::string sflsh_binary();

/// Path of a committed fixture in tests/data/.
inline std::string fixture(const std::string& name) { return source_dir() + "/tests/data/" + name; }
/// Path of a fixture generated at build time (tiny_smpl.npz,
/// tiny_smpl_expected.npz: data_tools/smpl_reference.py make-fixtures).
inline std::string generated_fixture(const std::string& name) { return std::string(SFLSH_GENERATED_DIR) + "/" + name; }

/// Expects `fn` to throw sflsh::Error whose message contains every fragment.
template <class Fn>
void expect_error(Fn fn, std::initializer_list<std::string> fragments) {
  try {
    fn();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& e) {
    for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
  }
}

/// Runs a shell command, returns its exit code; stdout+stderr go to *output.
int run_command(const std::string& cmd, std::string* output = nullptr);

}  // namespace sflsh::test
