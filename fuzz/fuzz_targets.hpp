#pragma once
// The fuzz targets' "parse one input" functions, shared by the libFuzzer
// executables (fuzz/fuzz_main.cpp, built by scripts/fuzz.sh with clang) and by
// the regression replay test (tests/fuzz/, every build). The contract of every
// reader: an input either parses or throws sflsh::Error (caught here). Any
// other exception escapes, and a crash, sanitizer report, hang or huge
// allocation is a finding.
#include <array>
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

/// Material-override YAML (apply_material_text) on regions named kMaterialRegions.
void material(const std::uint8_t* data, std::size_t size);
/// A YAML scene (parse_scene_description) in a folder holding the files
/// kSceneFiles (empty); what parses is written back and parsed again.
void scene_yaml(const std::uint8_t* data, std::size_t size);
/// A tool/obstacle mesh: byte 0 picks the format (0 obj, 1 stl, 2 ply by value
/// mod 3), the rest is the file (io::read_mesh_from_memory); a closed mesh is
/// baked into a grid SDF of about kMeshGridCells cells along its longest side
/// (bounded: a tiny file cannot request a giant grid) and sampled.
void mesh(const std::uint8_t* data, std::size_t size);
/// Pose-stream datagrams (decode_pose, decode_feedback, PoseStreamFilter):
/// each chunk is one length byte, then that many bytes.
void stream(const std::uint8_t* data, std::size_t size);
/// Pose-file text as CSV and as JSON lines (parse_pose_text); what parses is
/// written back and must read back to the same samples.
void pose_file(const std::uint8_t* data, std::size_t size);
/// One browser-viewer control message (viewer::parse_control_message, the
/// WebSocket text the page sends): it never throws, gives either a message or
/// an error sentence, and a message holds only in-range, finite values.
void control_message(const std::uint8_t* data, std::size_t size);

inline constexpr std::array<const char*, 4> kMaterialRegions = {"belly", "thigh", "upper_arm", "chest"};
inline constexpr std::array<const char*, 6> kSceneFiles = {"avatar.h5", "pinch.csv", "soft.yaml",
                                                           "tool.obj", "walk.bvh", "pinch.jsonl"};
inline constexpr int kMeshGridCells = 24;

struct Target {
  std::string name;  ///< folder name under tests/fuzz_regressions/ and scripts/fuzz.sh's name
  TargetFn run;
};
/// Every target, in the order scripts/fuzz.sh runs them.
const std::vector<Target>& all_targets();

}  // namespace sflsh::fuzz
