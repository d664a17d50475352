#pragma once
// The fuzz targets' "parse one input" functions, shared by the libFuzzer
// executables (fuzz/fuzz_main.cpp, built by scripts/fuzz.sh with clang) and by
// the regression replay test (tests/fuzz/, every build). The contract of every
// reader: an input either parses or throws sflsh::Error (caught here). Any
// other exception escapes, and a crash, sanitizer report, hang or huge
// allocation is a finding.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sflsh::fuzz {

using TargetFn = void (*)(const std::uint8_t* data, std::size_t size);

/// BVH text: parse, convert to a skeleton motion and retarget it to SMPL.
void bvh(const std::uint8_t* data, std::size_t size);
/// An .npz archive (read_npz_bytes) and the same bytes as one .npy (read_npy_bytes).
void npz(const std::uint8_t* data, std::size_t size);
/// An SMPL-format body-model HDF5 image (read_body_model_hdf5).
void body_model_h5(const std::uint8_t* data, std::size_t size);
/// An avatar HDF5 image (read_avatar).
void avatar_h5(const std::uint8_t* data, std::size_t size);
/// A simulation-result HDF5 image (read_simulation_result, as `sflsh view`/`fit` read it).
void result_h5(const std::uint8_t* data, std::size_t size);

struct Target {
  std::string name;  ///< folder name under tests/fuzz_regressions/ and scripts/fuzz.sh's name
  TargetFn run;
};
/// Every target, in the order scripts/fuzz.sh runs them.
const std::vector<Target>& all_targets();

}  // namespace sflsh::fuzz
