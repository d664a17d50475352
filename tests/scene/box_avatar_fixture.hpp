#pragma once
// A temporary folder with a small synthetic avatar file box.h5 (a 6 cm box of
// 1 cm cells whose top is at y = 0.03 m) and a helper writing scene.yaml next
// to it, for scene tests.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "sflsh/asset/avatar_file.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh::test {

class BoxAvatarScene : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("sflsh_scene_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    SyntheticAvatarOptions o;
    o.nx = o.nz = 6;
    o.cell = 0.01;
    o.handles = 6;
    o.handle_radius = 0.1;
    o.all_tets = false;
    o.samples = 10;
    Avatar a = make_synthetic_avatar(o);
    a.joints_rest = make_tpose_skeleton().joints_rest;
    a.capsules = {{3, Vec3(0, 0.005, 0), Vec3(0, 0.025, 0), 0.025}};
    write_avatar(a, (dir_ / "box.h5").string());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write_scene(const std::string& text) {
    const std::string p = (dir_ / "scene.yaml").string();
    std::ofstream(p) << text;
    return p;
  }
  std::filesystem::path dir_;
};

/// A kinematic tool without a shape whose grasp sensor looks down at the
/// box's top from 1 cm above it: it closes at 0.05 s, lifts 3 mm by 0.15 s,
/// holds, and opens at 0.25 s (dt 1/100, 0.3 s, gravity off, hardness 2e3 N/m).
inline constexpr const char* kBoxPinchScene = R"(solver: {dt: 1/100, seconds: 0.3, gravity: [0, 0, 0]}
output: {fps: 20}
bodies:
  - {name: base, avatar: box.h5, motion: none, bones: kinematic}
tools:
  - name: gripper
    keyframes:
      - {time: 0.0, position: [0.002, 0.04, 0.001], closure: 0.8}
      - {time: 0.05, position: [0.002, 0.04, 0.001], closure: 0.0}
      - {time: 0.15, position: [0.002, 0.043, 0.001], closure: 0.0}
      - {time: 0.24, position: [0.002, 0.043, 0.001], closure: 0.0}
      - {time: 0.25, position: [0.002, 0.043, 0.001], closure: 0.8}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.03}]
      hardness: 2.0e3
      damping: 1.0
)";

}  // namespace sflsh::test
