// Running scene files on a small synthetic avatar written to a
// temporary folder: a dynamic ball in free fall follows backward Euler's
// closed form until it lands and then rests on the body, a kinematic object's
// poses are its keyframes, several bodies are concatenated in the result, and
// the CLI runs a scene file and refuses the one-avatar flags with it.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "scene/box_avatar_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

using SceneRun = test::BoxAvatarScene;

TEST_F(SceneRun, ABallFallsFreelyAnotherRestsOnTheBody) {
  // "drop", far from the body, falls freely: backward Euler from rest gives
  // v_n = −g h n, y_n = y_0 − g h² n(n+1)/2. "ball" starts 3 mm above the top.
  const double h = 1.0 / 60, g = 9.81, y0 = 0.20, r = 0.05;
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/60, seconds: 1.5, newton_iters: 4, line_search: true}
output: {fps: 60}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - name: ball
    shape: {type: sphere, radius: 0.05}
    kind: dynamic
    mass: 0.2
    position: [0.0, 0.083, 0.0]
  - name: drop
    shape: {type: box, size: [0.1, 0.05, 0.02]}
    kind: dynamic
    density: 700
    position: [2.0, 0.20, 0]
)"));
  SceneContactStats stats;
  SceneRunOptions opt;
  opt.progress = false;
  const SimulationResult res = run_scene(sc, opt, &stats);
  ASSERT_EQ(res.objects.size(), 2u);
  const ObjectTrack &ball = res.objects[0], &drop = res.objects[1];
  EXPECT_EQ(ball.shape, "sphere");
  EXPECT_EQ(drop.shape, "box");
  EXPECT_EQ(ball.kind, "dynamic");
  ASSERT_EQ(drop.poses.size(), res.frame_time.size());
  for (size_t f = 0; f < drop.poses.size(); ++f) {
    const int n = int(std::lround(res.frame_time[f] / h));
    EXPECT_NEAR(drop.poses[f].translation().y(), y0 - g * h * h * n * (n + 1) / 2, 1e-9) << "frame " << f;
    EXPECT_NEAR(drop.poses[f].translation().x(), 2.0, 1e-12);
    EXPECT_LT((drop.poses[f].linear() - Mat3::Identity()).norm(), 1e-12);
  }
  // At the end it rests on the top, held by its weight.
  const Vec3 end = ball.poses.back().translation();
  EXPECT_NEAR(end.y(), 0.03 + r, 0.01);
  ASSERT_FALSE(stats.pairs.empty());
  EXPECT_EQ(stats.pairs[0].term, "contact:ball");
  EXPECT_NEAR(stats.pairs[0].last_force.y(), -0.2 * g, 0.02 * 0.2 * g);
}

TEST_F(SceneRun, KinematicObjectsFollowTheirKeyframesAndBodiesAreConcatenated) {
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/60, seconds: 1.0, gravity: [0, 0, 0]}
output: {fps: 10}
bodies:
  - {name: left, avatar: box.h5, bones: kinematic, placement: {offset: [-0.5, 0, 0]}}
  - {name: right, avatar: box.h5, bones: kinematic, placement: {offset: [0.5, 0, 0], heading_deg: 90}}
objects:
  - name: lid
    shape: {type: box, size: [0.1, 0.02, 0.1]}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [-0.5, 0.2, 0]}
      - {time: 1.0, position: [-0.5, 0.1, 0], orientation: [0.7071067811865476, 0, 0.7071067811865476, 0]}
)"));
  SceneRunOptions opt;
  opt.progress = false;
  const SimulationResult res = run_scene(sc, opt);
  ASSERT_EQ(res.body_names, (std::vector<std::string>{"left", "right"}));
  const Avatar a = read_avatar((dir_ / "box.h5").string());
  const int V = int(a.surface_rest.rows());
  ASSERT_EQ(res.body_vertex_offsets, (std::vector<int>{0, V, 2 * V}));
  ASSERT_EQ(res.faces.rows(), 2 * a.surface_faces.rows());
  EXPECT_EQ(res.faces.bottomRows(a.surface_faces.rows()).minCoeff(), V);
  // Placement: the right body's skin is the rest skin turned 90° about +Y and moved by +0.5 m in x.
  const Points& x = res.frame_positions.back();
  for (int v = 0; v < V; v += 7) {
    const Vec3 p = a.surface_rest.row(v).transpose();
    EXPECT_LT((x.row(V + v).transpose() - (Vec3(p.z(), p.y(), -p.x()) + Vec3(0.5, 0, 0))).norm(), 1e-9);
    EXPECT_LT((x.row(v).transpose() - (p + Vec3(-0.5, 0, 0))).norm(), 1e-9);
  }
  ASSERT_EQ(res.frame_joints.back().rows(), 48);
  // The lid at t = 0.5 s: halfway down, turned 45° about +Y (slerp).
  const ObjectTrack& lid = res.objects[0];
  size_t f = 0;
  while (std::abs(res.frame_time[f] - 0.5) > 1e-9) ++f;
  EXPECT_LT((lid.poses[f].translation() - Vec3(-0.5, 0.15, 0)).norm(), 1e-12);
  EXPECT_LT((lid.poses[f].linear() - Eigen::AngleAxisd(M_PI / 4, Vec3::UnitY()).toRotationMatrix()).norm(), 1e-12);
  // Kinematic bodies and a kinematic lid above them: no contact terms act, nothing moves softly.
  EXPECT_LT(res.frame_displacement.back().cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(SceneRun, AMeshObjectIsBakedAndPressesTheBody) {
  // A closed cube (OBJ, 4 cm, in cm: scale 0.01) lowered 5 mm into the 6 cm top.
  std::ofstream((dir_ / "cube.obj").string()) << R"(v -2 -2 -2
v 2 -2 -2
v 2 2 -2
v -2 2 -2
v -2 -2 2
v 2 -2 2
v 2 2 2
v -2 2 2
f 1 4 3
f 1 3 2
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 4 8 7
f 4 7 3
f 1 5 8
f 1 8 4
f 2 3 7
f 2 7 6
)";
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/60, seconds: 0.5, gravity: [0, 0, 0]}
output: {fps: 10}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - name: block
    shape: {type: mesh, file: cube.obj, scale: 0.01, voxel_size: 0.002, padding: 0.01}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [0, 0.06, 0]}
      - {time: 0.5, position: [0, 0.045, 0]}
)"));
  prepare_scene_assets(sc, "", false);  // bakes the cube's SDF (the runtime does not bake)
  SceneContactStats stats;
  SceneRunOptions opt;
  opt.progress = false;
  const SimulationResult res = run_scene(sc, opt, &stats);
  ASSERT_EQ(res.objects.size(), 1u);
  EXPECT_EQ(res.objects[0].shape, "mesh");
  EXPECT_EQ(res.objects[0].vertices.rows(), 8);
  EXPECT_NEAR(res.objects[0].vertices.cwiseAbs().maxCoeff(), 0.02, 1e-12);
  // The cube's bottom ends 5 mm below the top (y = 0.03): the skin under it is pushed down.
  ASSERT_FALSE(stats.pairs.empty());
  EXPECT_EQ(stats.pairs[0].term, "contact:block");
  EXPECT_GT(stats.pairs[0].max_force, 0);
  EXPECT_LT(stats.pairs[0].max_penetration, 0.005);
  const Points& x = res.frame_positions.back();
  double lowest_top = 1;
  for (int v = 0; v < x.rows(); ++v)
    if (std::abs(x(v, 0)) < 0.015 && std::abs(x(v, 2)) < 0.015 && x(v, 1) > 0.02) lowest_top = std::min(lowest_top, x(v, 1));
  EXPECT_LT(lowest_top, 0.03 - 0.002) << "the skin under the block did not move down";
  // An open mesh (one face removed) is refused, naming the file.
  std::ofstream((dir_ / "open.obj").string()) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n";
  SceneDescription bad = read_scene_description(write_scene(R"(
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
solver: {seconds: 0.1}
objects:
  - {name: lid, shape: {type: mesh, file: open.obj}}
)"));
  try {
    prepare_scene_assets(bad, "", false);
    ADD_FAILURE() << "an open mesh was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("open.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("objects[0].shape"), std::string::npos) << e.what();
  }
}

TEST_F(SceneRun, AToolPinchesLiftsAndReleasesTheFlesh) {
  // A gripper frame 5 mm above the 6 cm top, one sensor looking down: it
  // closes (closure 1 → 0 rad by 0.1 s), lifts 5 mm by 0.4 s, holds, opens at 0.6 s.
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/60, seconds: 1.6, gravity: [0, 0, 0]}
output: {fps: 60}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: gripper
    keyframes:
      - {time: 0.0, position: [0.001, 0.035, 0.002], closure: 1.0}
      - {time: 0.1, position: [0.001, 0.035, 0.002], closure: 0.0}
      - {time: 0.4, position: [0.001, 0.040, 0.002], closure: 0.0}
      - {time: 0.55, position: [0.001, 0.040, 0.002], closure: 0.0}
      - {time: 0.6, position: [0.001, 0.040, 0.002], closure: 1.0}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.01}]
      closure_threshold: 0.2
      hardness: 2.0e4
      damping: 1.0
)"));
  SceneContactStats stats;
  SceneRunOptions opt;
  opt.progress = false;
  const SimulationResult res = run_scene(sc, opt, &stats);
  // One grasp (closure below 0.2 rad at t = 0.08 s), one release (above at 0.56 s).
  ASSERT_EQ(stats.tool_events.size(), 2u);
  EXPECT_EQ(stats.tool_events[0].kind, "grasp");
  EXPECT_GT(stats.tool_events[0].points, 0);
  EXPECT_NEAR(stats.tool_events[0].time, 0.1, 0.03);
  EXPECT_EQ(stats.tool_events[1].kind, "release");
  EXPECT_NEAR(stats.tool_events[1].time, 0.57, 0.03);
  // Through the lift the anchored skin stays within 1 mm of its jaw offsets,
  // and the tool feels the flesh pulling it down.
  double stretch = 0, pull = 0;
  for (const auto& s : stats.tool_steps)
    if (s.time > 0.1 && s.time < 0.55) {
      EXPECT_GT(s.anchors, 0) << "t = " << s.time;
      stretch = std::max(stretch, s.max_stretch);
      pull = std::min(pull, s.force.y());
    }
  EXPECT_LT(stretch, 1e-3);
  EXPECT_LT(pull, 0);
  // The top under the gripper rose with it (~5 mm), then went back to rest.
  auto top_under_gripper = [&](int frame) {
    const Points& x = res.frame_positions[frame];
    double y = -1;
    for (int v = 0; v < x.rows(); ++v)
      if (std::abs(x(v, 0) - 0.001) < 0.006 && std::abs(x(v, 2) - 0.002) < 0.006) y = std::max(y, x(v, 1));
    return y;
  };
  size_t lifted = 0;
  while (res.frame_time[lifted] < 0.5) ++lifted;
  EXPECT_GT(top_under_gripper(int(lifted)), 0.03 + 0.003);
  EXPECT_LT(std::abs(top_under_gripper(int(res.frame_time.size()) - 1) - 0.03), 1e-3);
  // The tool log has a row per step.
  const std::string log = (dir_ / "tools.csv").string();
  stats.write_tool_log(log);
  std::ifstream in(log);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 1 + int(stats.tool_steps.size()));
  EXPECT_EQ(int(stats.tool_steps.size()), 96);
  // The same gripper from a recorded pose file: the same run, bit for bit.
  std::ofstream((dir_ / "pinch.csv").string()) << "time,x,y,z,qw,qx,qy,qz,closure\n"
                                                  "0.0,0.001,0.035,0.002,1,0,0,0,1.0\n"
                                                  "0.1,0.001,0.035,0.002,1,0,0,0,0.0\n"
                                                  "0.4,0.001,0.040,0.002,1,0,0,0,0.0\n"
                                                  "0.55,0.001,0.040,0.002,1,0,0,0,0.0\n"
                                                  "0.6,0.001,0.040,0.002,1,0,0,0,1.0\n";
  SceneDescription from_file = sc;
  from_file.tools[0].keyframes.clear();
  from_file.tools[0].pose_file = (dir_ / "pinch.csv").string();
  SceneContactStats stats2;
  const SimulationResult res2 = run_scene(from_file, opt, &stats2);
  ASSERT_EQ(stats2.tool_events.size(), stats.tool_events.size());
  ASSERT_EQ(res2.frame_positions.size(), res.frame_positions.size());
  EXPECT_EQ(res2.frame_positions.back(), res.frame_positions.back());
}

TEST_F(SceneRun, CliRunsASceneFileAndRefusesOneAvatarFlagsWithIt) {
  const std::string scene = write_scene(R"(
solver: {dt: 1/60, seconds: 0.2}
output: {out: out.h5, fps: 30}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - {name: ball, shape: {type: sphere, radius: 0.05}, kind: dynamic, density: 500, position: [0, 0.2, 0]}
)");
  const std::string out = (dir_ / "cli.h5").string();
  std::string log;
  ASSERT_EQ(test::run_command(test::sflsh_binary() + " simulate " + scene + " --out " + out, &log), 0) << log;
  const SimulationResult r = read_simulation_result(out);
  ASSERT_EQ(r.objects.size(), 1u);
  EXPECT_EQ(r.objects[0].name, "ball");
  EXPECT_NE(log.find("contact"), std::string::npos);
  // A one-avatar flag with a scene file: one error line, non-zero exit, no output.
  const std::string out2 = (dir_ / "cli2.h5").string();
  EXPECT_NE(test::run_command(test::sflsh_binary() + " simulate " + scene + " --avatar x.h5 --out " + out2, &log), 0);
  EXPECT_NE(log.find("--avatar does not apply to a scene file"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out2));
  // A scene naming a missing avatar: file, line and key path.
  const std::string bad = write_scene("bodies:\n  - {name: a, avatar: nowhere.h5}\nsolver: {seconds: 0.1}\n");
  EXPECT_NE(test::run_command(test::sflsh_binary() + " simulate " + bad + " --out " + out2, &log), 0);
  EXPECT_NE(log.find("scene.yaml:2: bodies[0].avatar"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out2));
}

}  // namespace
