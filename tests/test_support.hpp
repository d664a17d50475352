#pragma once
// Helpers shared by the test executables.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/core/error.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh::test {

/// Golden tests pin fingerprints of a run (weighted sums of its doubles, a
/// distinct weight per entry so that a changed value or two swapped ones
/// show) within this relative tolerance, not bit for bit: builds for
/// different instruction sets (-march=native on CPUs with and without AVX-512:
/// vector widths, summation orders) differ in the last bits, and bit-exact
/// goldens recorded on one CPU failed on another. The build fixes one
/// instruction set (CMakeLists.txt, SFLSH_ARCH = x86-64-v3) for that reason.
constexpr double kGoldenRelative = 1e-9;

/// Σ_k (k mod 7 + 1) m_k over a matrix's entries, column by column: one fingerprint entry.
template <typename M>
double weighted_sum(const M& m) {
  double s = 0;
  long k = 0;
  for (Eigen::Index j = 0; j < m.cols(); ++j)
    for (Eigen::Index i = 0; i < m.rows(); ++i) s += double(k++ % 7 + 1) * double(m(i, j));
  return s;
}

/// "{a, b, ...}" at full precision: a fingerprint as a golden table holds it.
inline std::string print_fingerprint(const std::vector<double>& f) {
  std::string out = "{";
  char buf[32];
  for (size_t i = 0; i < f.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g", f[i]);
    out += (i ? ", " : "") + std::string(buf);
  }
  return out + "}";
}

/// Every entry within `relative` of the golden one (and 1e-15 absolute, for entries that are 0).
inline void expect_fingerprint(const std::vector<double>& got, const std::vector<double>& golden,
                               const std::string& what, double relative = kGoldenRelative) {
  ASSERT_EQ(got.size(), golden.size()) << what;
  for (size_t i = 0; i < got.size(); ++i)
    EXPECT_LE(std::abs(got[i] - golden[i]), relative * std::abs(golden[i]) + 1e-15)
        << what << ", entry " << i << ": " << print_fingerprint(got) << " vs golden " << print_fingerprint(golden);
}

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
