// libFuzzer target for the BVH parser (scripts/fuzz_bvh.sh builds and runs
// it). Every input must either parse or throw sflsh::Error; parsed files are
// also pushed through the conversion and retargeting to SMPL, whose inputs
// (joint trees, offsets, channel values) come straight from the file.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sflsh/core/error.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/motion/retarget.hpp"
#include "sflsh/motion/skeleton_motion.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const sflsh::BvhMotion bvh = sflsh::parse_bvh(text, "fuzz.bvh");
    if (size_t(bvh.num_frames) * bvh.joints.size() > 20000) return 0;  // keep runs fast
    const sflsh::SkeletonMotion sk = sflsh::skeleton_motion_from_bvh(bvh);
    sflsh::retarget_to_smpl(sk, sflsh::best_builtin_joint_map(sk.names), sflsh::RetargetOptions{});
  } catch (const sflsh::Error&) {
    // Expected for malformed input.
  }
  return 0;
}
