// `sflsh simulate` driven by glTF/glb and FBX motions written by assimp's own
// exporter (tests/motion/assimp_export.hpp): the simulated body's joints and
// surface follow the same trajectories as with the BVH the files were made
// from (tests/motion/assimp_export_roundtrip_test.cpp compares the motions).
#include <gtest/gtest.h>

#include <fstream>

#include "motion/assimp_export.hpp"
#include "motion/smpl_like_bvh.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

TEST(AssimpMotionSimulate, ExportedGlbAndFbxDriveTheSameRunAsTheirBvh) {
  test::TempDir dir;
  const std::string bvh = dir.file("source.bvh");
  std::ofstream(bvh) << test::smpl_like_bvh(30, [](int f) {
    auto v = test::rest_frame_values();
    v[0] += 0.5 * f;
    v[6 + 3 * 2 + 2] = -1.5 * f;  // spine1 X
    v[6 + 3 * 5 + 0] = 1.0 * f;   // spine2 Z
    return v;
  });
  const SkeletonMotion src = skeleton_motion_from_bvh(read_bvh(bvh));
  const auto scene = test::skinned_scene(src);
  test::export_scene(*scene, "glb2", dir.file("m.glb"));
  test::export_scene(*scene, "fbxa", dir.file("m.fbx"));
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));

  auto simulate = [&](const std::string& motion, const std::string& out) {
    std::string text;
    const int code = test::run_command(test::sflsh_binary() + " -q simulate --avatar " + dir.file("a.h5") +
                                           " --motion " + motion + " --seconds 0.25 --out " + dir.file(out),
                                       &text);
    EXPECT_EQ(code, 0) << text;
    return read_simulation_result(dir.file(out));
  };
  const SimulationResult ref = simulate(bvh, "bvh.h5");
  ASSERT_GE(ref.frame_time.size(), 5u);
  // The source moves the body's joints: 4 cm of pelvis travel, spine bends.
  EXPECT_GT((ref.frame_joints.back() - ref.frame_joints.front()).rowwise().norm().maxCoeff(), 0.02);
  for (const std::string m : {"m.glb", "m.fbx"}) {
    const SimulationResult r = simulate(dir.file(m), m + ".h5");
    ASSERT_EQ(r.frame_time.size(), ref.frame_time.size()) << m;
    for (size_t f = 0; f < r.frame_time.size(); ++f) {
      // Joints: float32 key storage only (m).
      EXPECT_LT((r.frame_joints[f] - ref.frame_joints[f]).cwiseAbs().maxCoeff(), 1e-6) << m << " frame " << f;
      // Flesh: the same run up to the Newton step's response to that (m).
      EXPECT_LT((r.frame_positions[f] - ref.frame_positions[f]).cwiseAbs().maxCoeff(), 1e-5) << m << " frame " << f;
    }
  }
}

}  // namespace
}  // namespace sflsh
