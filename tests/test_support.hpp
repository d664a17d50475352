#pragma once
// Helpers shared by the test executables.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>

#include <Eigen/Geometry>

#include "sflsh/core/error.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh::test {

/// FNV-1a over the bytes of every value added: a golden test's fingerprint,
/// in which any change of a bit shows.
class BitHash {
 public:
  void add(double x) { add_bytes(&x, sizeof x); }
  void add(int x) { add_bytes(&x, sizeof x); }
  void add(long x) { add_bytes(&x, sizeof x); }
  void add(const Eigen::Isometry3d& T) {
    for (int i = 0; i < 16; ++i) add(T.matrix().data()[i]);
  }
  void add(const VecX& v) {
    add(int(v.size()));
    for (Eigen::Index i = 0; i < v.size(); ++i) add(v[i]);
  }
  void add(const Vec3& v) {
    for (int i = 0; i < 3; ++i) add(v[i]);
  }
  /// A matrix: its shape (as longs), then its values column by column.
  template <typename M>
  void add_matrix(const M& m) {
    add(long(m.rows()));
    add(long(m.cols()));
    for (Eigen::Index j = 0; j < m.cols(); ++j)
      for (Eigen::Index i = 0; i < m.rows(); ++i) add(double(m(i, j)));
  }
  std::string hex() const {
    char s[17];
    std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h_));
    return s;
  }

 private:
  void add_bytes(const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ b[i]) * 1099511628211ull;
  }
  std::uint64_t h_ = 1469598103934665603ull;
};

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
