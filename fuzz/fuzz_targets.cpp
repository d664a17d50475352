#include "fuzz_targets.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string_view>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/geometry/grid_sdf.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/meshing/mesh_sdf_bake.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/motion/retarget.hpp"
#include "sflsh/motion/skeleton_motion.hpp"
#include "sflsh/scene/material_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/pose_stream_filter.hpp"
#include "sflsh/teleop/stream_message.hpp"
#include "sflsh/viewer/control_message.hpp"

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

void material(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<RegionMaterial> materials(kMaterialRegions.size());
  for (std::size_t i = 0; i < materials.size(); ++i) materials[i].name = kMaterialRegions[i];
  expect_parse_or_error([&] { apply_material_text(text, "fuzz-material.yaml", materials); });
}

const std::string& scene_folder() {
  // The files a scene may name, once (empty: reading checks only that they exist).
  static const std::string folder = [] {
    const auto dir = std::filesystem::temp_directory_path() / "sflsh-fuzz-scene";
    std::filesystem::create_directories(dir);
    for (const char* f : kSceneFiles)
      if (!std::filesystem::exists(dir / f)) std::ofstream(dir / f) << "";
    return dir.string();
  }();
  return folder;
}

void scene_yaml(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string path = scene_folder() + "/fuzz-scene.yaml";
  expect_parse_or_error([&] {
    const SceneDescription scene = parse_scene_description(text, path);
    // What reading accepts must write and read back.
    parse_scene_description(scene_description_yaml(scene), path);
  });
}

void mesh(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return;
  static const char* const formats[] = {"obj", "stl", "ply"};
  const char* format = formats[data[0] % 3];
  expect_parse_or_error([&] {
    const io::ImportedMesh m = io::read_mesh_from_memory(data + 1, size - 1, format, std::string("fuzz-mesh.") + format);
    require_closed_mesh(m.vertices, m.faces, "fuzz mesh");
    if (m.faces.rows() > 20000) return;  // keep runs fast: the bake is O(nodes · log F)
    // A bounded grid: about kMeshGridCells cells along the longest side.
    MeshSdfBakeOptions o;
    const double extent = (m.vertices.colwise().maxCoeff() - m.vertices.colwise().minCoeff()).maxCoeff();
    o.voxel_size = extent > 0 && std::isfinite(extent) ? extent / kMeshGridCells : 1.0;
    o.padding = 2 * o.voxel_size;
    o.max_nodes = 64 * 64 * 64;
    const geometry::GridSdf grid = bake_mesh_sdf(m.vertices, m.faces, o, "fuzz mesh");
    const Vec3 centre = 0.5 * (m.vertices.colwise().maxCoeff() + m.vertices.colwise().minCoeff()).transpose();
    for (int k = 0; k < 4; ++k) grid.evaluate(centre + Vec3(k, -k, 0.5 * k) * o.voxel_size, k % 2 == 0);
  });
}

void stream(const std::uint8_t* data, std::size_t size) {
  // The bytes as a sequence of datagrams: the first byte of each chunk gives
  // its length (0..kPoseMessageSize + 8), so sizes other than 88 occur too.
  teleop::PoseStreamFilter filter;
  std::string detail;
  std::size_t at = 0;
  while (at < size) {
    const std::size_t n = std::min<std::size_t>(data[at] % (teleop::kPoseMessageSize + 9), size - at - 1);
    const std::uint8_t* d = data + at + 1;
    const auto pose = teleop::decode_pose(d, n);
    if (pose.message) filter.check(*pose.message, &detail);
    teleop::decode_feedback(d, n);
    at += n + 1;
  }
}

void pose_file(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (const auto format : {teleop::PoseFileFormat::kCsv, teleop::PoseFileFormat::kJsonLines})
    expect_parse_or_error([&] {
      const auto samples = teleop::parse_pose_text(text, format, "fuzz-pose");
      // Rows written back must read back to the same samples.
      std::string again = teleop::pose_file_header(format);
      for (const auto& s : samples) again += (again.empty() ? "" : "\n") + teleop::format_pose_row(s, format);
      const auto back = teleop::parse_pose_text(again, format, "fuzz-pose-again");
      if (back.size() != samples.size()) std::abort();
      for (std::size_t i = 0; i < back.size(); ++i)
        if (back[i].time != samples[i].time || back[i].position != samples[i].position ||
            back[i].closure != samples[i].closure)
          std::abort();
    });
}

void control_message(const std::uint8_t* data, std::size_t size) {
  using viewer::ControlType;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const viewer::ControlParse r = viewer::parse_control_message(text);
  // Exactly one of a message and an error sentence.
  if (r.message.has_value() != r.error.empty()) std::abort();
  if (!r.message) return;
  const viewer::ControlMessage& m = *r.message;
  if (size > viewer::kMaxControlMessageBytes || double(m.seq) >= 9007199254740992.0) std::abort();
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  switch (m.type) {
    case ControlType::kTool:
      if (m.tool < 0 || m.tool > 1000 || !std::isfinite(m.pose.time) || !m.pose.position.allFinite() ||
          m.pose.position.cwiseAbs().maxCoeff() > 1e4 || std::abs(m.pose.orientation.norm() - 1.0) > 1e-9 ||
          !in(m.pose.closure, 0.0, teleop::kMaxClosure))
        std::abort();
      break;
    case ControlType::kStiffness:
      if (!in(m.value, viewer::kMinStiffnessScale, viewer::kMaxStiffnessScale)) std::abort();
      break;
    case ControlType::kSeek:
      if (!in(m.value, 0.0, 1e9)) std::abort();
      break;
    case ControlType::kSpeed:
      if (!in(m.value, viewer::kMinPlaybackSpeed, viewer::kMaxPlaybackSpeed)) std::abort();
      break;
    case ControlType::kPause:
    case ControlType::kStep:
    case ControlType::kReset:
      break;
  }
}

const std::vector<Target>& all_targets() {
  static const std::vector<Target> targets = {
      {"bvh", bvh},       {"npz", npz},           {"body_model_h5", body_model_h5}, {"avatar_h5", avatar_h5},
      {"result_h5", result_h5}, {"material", material}, {"scene_yaml", scene_yaml}, {"mesh", mesh},
      {"stream", stream}, {"pose_file", pose_file}, {"control_message", control_message}};
  return targets;
}

}  // namespace sflsh::fuzz
