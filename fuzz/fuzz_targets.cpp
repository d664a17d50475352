#include "fuzz_targets.hpp"

#include <map>
#include <string_view>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/motion/retarget.hpp"
#include "sflsh/motion/skeleton_motion.hpp"
#include "sflsh/scene/result_file.hpp"

namespace sflsh::fuzz {
namespace {

template <class Fn>
void expect_parse_or_error(Fn fn) {
  try {
    fn();
  } catch (const sflsh::Error&) {
    // The contract for malformed input.
  }
}

// Runs `read(name)` with the bytes readable as the HDF5 file `name`.
template <class Read>
void with_hdf5_image(const std::uint8_t* data, std::size_t size, const char* name, Read read) {
  const io::Hdf5MemoryImage image(name, data, size);
  expect_parse_or_error([&] { read(image.name()); });
}

}  // namespace

void bvh(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  expect_parse_or_error([&] {
    const BvhMotion motion = parse_bvh(text, "fuzz.bvh");
    if (size_t(motion.num_frames) * motion.joints.size() > 20000) return;  // keep runs fast
    const SkeletonMotion sk = skeleton_motion_from_bvh(motion);
    retarget_to_smpl(sk, best_builtin_joint_map(sk.names), RetargetOptions{});
  });
}

void npz(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  expect_parse_or_error([&] {
    std::map<std::string, std::vector<std::string>> strings;
    io::read_npz_bytes(bytes, "fuzz.npz", &strings);
  });
  expect_parse_or_error([&] { io::read_npy_bytes(bytes, "fuzz.npy"); });
}

void body_model_h5(const std::uint8_t* data, std::size_t size) {
  with_hdf5_image(data, size, "fuzz-body-model.h5", [](const std::string& n) { read_body_model_hdf5(n); });
}

void avatar_h5(const std::uint8_t* data, std::size_t size) {
  with_hdf5_image(data, size, "fuzz-avatar.h5", [](const std::string& n) { read_avatar(n); });
}

void result_h5(const std::uint8_t* data, std::size_t size) {
  with_hdf5_image(data, size, "fuzz-result.h5", [](const std::string& n) { read_simulation_result(n); });
}

const std::vector<Target>& all_targets() {
  static const std::vector<Target> targets = {
      {"bvh", bvh}, {"npz", npz}, {"body_model_h5", body_model_h5}, {"avatar_h5", avatar_h5}, {"result_h5", result_h5}};
  return targets;
}

}  // namespace sflsh::fuzz
