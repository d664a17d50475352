// libFuzzer entry point; scripts/fuzz.sh compiles it once per target with
// -DSFLSH_FUZZ_TARGET=<function in fuzz_targets.hpp>.
#include "fuzz_targets.hpp"

#ifndef SFLSH_FUZZ_TARGET
#error "compile with -DSFLSH_FUZZ_TARGET=<target>, e.g. avatar_h5"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sflsh::fuzz::SFLSH_FUZZ_TARGET(data, size);
  return 0;
}
