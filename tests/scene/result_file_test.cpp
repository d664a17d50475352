#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {
SimulationResult small_result() {
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "builtin:jump";
  r.dt = 1.0 / 60;
  r.bones_dynamic = true;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Random(3, 3);
  for (int f = 0; f < 4; ++f) {
    r.frame_time.push_back(f / 30.0);
    r.frame_step_ms.push_back(1.0 + f);
    r.frame_positions.push_back(Points::Constant(3, 3, 0.25 * f));
    r.frame_displacement.push_back(Points::Constant(3, 3, 0.001 * f));
    r.frame_joints.push_back(Points::Constant(24, 3, -0.5 * f));
    r.frame_reduced.push_back(VecX::Constant(6, 0.01 * f));
  }
  r.num_frames = 4;
  for (int s = 0; s < 8; ++s) {
    r.step_time.push_back((s + 1) / 60.0);
    r.step_energy.push_back(s);
    r.step_grad_norm.push_back(0.5 * s);
    r.step_decrement.push_back(0.1 * s);
    r.step_outcome.push_back(s == 3 ? 1 : 0);
    r.step_ms.push_back(1.5);
  }
  return r;
}
}  // namespace

TEST(ResultFile, RoundTripKeepsFramesAndDiagnostics) {
  test::TempDir tmp;
  const SimulationResult r = small_result();
  write_simulation_result(r, tmp.file("r.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  ASSERT_EQ(b.num_frames, 4);
  EXPECT_EQ(b.frame_time, r.frame_time);
  EXPECT_EQ(b.frame_joints[3], r.frame_joints[3]);
  EXPECT_EQ(b.frame_reduced[2], r.frame_reduced[2]);
  // Positions are stored as float32.
  EXPECT_LT((b.frame_positions[2] - r.frame_positions[2]).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(b.step_energy, r.step_energy);
  EXPECT_EQ(b.damped, 1);
  EXPECT_EQ(b.accepted, 7);
  EXPECT_TRUE(b.bones_dynamic);
  io::Hdf5File f(tmp.file("r.h5"), io::Hdf5File::Mode::Read);
  EXPECT_EQ(f.shape("/frames/positions"), (std::vector<std::int64_t>{4, 3, 3}));
  EXPECT_EQ(f.shape("/frames/joints"), (std::vector<std::int64_t>{4, 24, 3}));
}

TEST(ResultFile, EveryFrameFieldComesBackFromItsOwnDataset) {
  // small_result() gives each per-frame field its own value at frame f
  // (positions 0.25 f, displacement 0.001 f, joints −0.5 f, reduced 0.01 f,
  // step 1 + f ms): a reader taking one dataset for another shows here.
  test::TempDir tmp;
  write_simulation_result(small_result(), tmp.file("r.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  ASSERT_EQ(b.num_frames, 4);
  for (int f = 0; f < 4; ++f) {
    EXPECT_DOUBLE_EQ(b.frame_time[f], f / 30.0);
    // float32 storage: relative error <= 6e-8.
    EXPECT_NEAR(b.frame_positions[f].maxCoeff(), 0.25 * f, 1e-7);
    EXPECT_NEAR(b.frame_positions[f].minCoeff(), 0.25 * f, 1e-7);
    EXPECT_NEAR(b.frame_displacement[f].maxCoeff(), 0.001 * f, 1e-9);
    EXPECT_NEAR(b.frame_displacement[f].minCoeff(), 0.001 * f, 1e-9);
    EXPECT_EQ(b.frame_joints[f], Points::Constant(24, 3, -0.5 * f));
    EXPECT_EQ(b.frame_reduced[f], VecX::Constant(6, 0.01 * f));
  }
}

TEST(ResultFile, UnfinishedStreamLeavesNoFile) {
  test::TempDir tmp;
  const SimulationResult r = small_result();
  {
    ResultWriter w(tmp.file("r.h5"), r.faces, r.surface_rest, 6);
    w.add_frame({0.0, 1.0, r.frame_positions[0], r.frame_displacement[0], r.frame_joints[0], r.frame_reduced[0], Vec3::Zero(), {}});
    // no finish(): e.g. the simulation threw
  }
  EXPECT_FALSE(std::filesystem::exists(tmp.file("r.h5")));
}

TEST(ResultFile, RejectsOtherFiles) {
  test::TempDir tmp;
  {
    io::Hdf5File f(tmp.file("x.h5"), io::Hdf5File::Mode::Write);
    f.write_scalar("/something", 1.0);
    f.commit();
  }
  EXPECT_THROW(read_simulation_result(tmp.file("x.h5")), Error);
}

// ---- scenes: several bodies and rigid objects (format version 2) ----------

namespace {

Isometry pose(double angle, const Vec3& axis, const Vec3& t) {
  Isometry T = Isometry::Identity();
  T.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

/// Two bodies (a triangle each) and two objects with poses that differ per frame.
SimulationResult scene_result() {
  SimulationResult r;
  r.avatar = "two.h5";
  r.motion = "scene:bump.yaml";
  r.dt = 1.0 / 120;
  r.newton_iters = 3;
  r.body_names = {"alice", "bob"};
  r.body_vertex_offsets = {0, 3, 6};
  r.faces.resize(2, 3);
  r.faces << 0, 1, 2, 3, 5, 4;
  r.surface_rest.resize(6, 3);
  for (int i = 0; i < 18; ++i) r.surface_rest.data()[i] = 0.1 * i - 0.7;
  ObjectTrack ball{"ball", "sphere", "dynamic", Points(), Triangles(), {}};
  ball.vertices.resize(4, 3);
  ball.vertices << 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1, -0.05, -0.05, -0.05;
  ball.faces.resize(4, 3);
  ball.faces << 0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0;
  ObjectTrack box{"crate", "box", "kinematic", Points::Constant(3, 3, 0.25), Triangles(), {}};
  box.vertices(1, 0) = -0.25, box.vertices(2, 1) = -0.25;
  box.faces.resize(1, 3);
  box.faces << 2, 1, 0;
  for (int f = 0; f < 3; ++f) {
    r.frame_time.push_back(0.1 * f);
    r.frame_step_ms.push_back(2.0 + f);
    r.frame_positions.push_back(Points::Constant(6, 3, 0.5 + f));
    r.frame_displacement.push_back(Points::Constant(6, 3, 0.002 * f));
    Points J(48, 3);
    for (int i = 0; i < J.size(); ++i) J.data()[i] = 0.01 * i + f;
    r.frame_joints.push_back(J);
    r.frame_reduced.push_back(VecX::LinSpaced(5, f, f + 1));
    ball.poses.push_back(pose(0.4 * f + 0.1, Vec3(0, 0, 1), Vec3(1.0 + f, 0.2, -0.3 * f)));
    box.poses.push_back(pose(-0.7 - 0.2 * f, Vec3(1, 2, -0.5), Vec3(-0.5, 0.1 * f, 2.0)));
  }
  r.objects = {ball, box};
  r.num_frames = 3;
  r.step_time = {0.1, 0.2};
  r.step_energy = {1, 2};
  r.step_grad_norm = {0.1, 0.2};
  r.step_decrement = {0.01, 0.02};
  r.step_outcome = {0, 2};
  r.step_ms = {3, 4};
  return r;
}

}  // namespace

TEST(ResultFile, ScenesKeepBodiesObjectsAndPoses) {
  test::TempDir tmp;
  const SimulationResult r = scene_result();
  write_simulation_result(r, tmp.file("s.h5"));
  {
    // The stored pose row of the ball at frame 2 from the closed form: a turn
    // by θ = 0.9 about +Z is the quaternion (cos θ/2, 0, 0, sin θ/2).
    io::Hdf5File f(tmp.file("s.h5"), io::Hdf5File::Mode::Read);
    EXPECT_EQ(f.read_scalar("/meta/format_version"), 2.0);
    EXPECT_EQ(f.shape("/frames/joints"), (std::vector<std::int64_t>{3, 48, 3}));
    std::vector<std::int64_t> shape;
    const std::vector<double> p = f.read_nd("/frames/object_poses", {}, &shape);
    ASSERT_EQ(shape, (std::vector<std::int64_t>{3, 2, 7}));
    const double expected[7] = {3.0, 0.2, -0.6, std::cos(0.45), 0, 0, std::sin(0.45)};
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(p[size_t((2 * 2 + 0) * 7 + k)], expected[k], 1e-15) << k;
    EXPECT_EQ(f.read_strings("/bodies/names"), (std::vector<std::string>{"alice", "bob"}));
  }
  const SimulationResult b = read_simulation_result(tmp.file("s.h5"));
  EXPECT_EQ(b.body_names, r.body_names);
  EXPECT_EQ(b.body_vertex_offsets, r.body_vertex_offsets);
  EXPECT_EQ(b.frame_joints[1], r.frame_joints[1]);
  EXPECT_EQ(b.faces, r.faces);
  EXPECT_EQ(b.newton_iters, 3);
  EXPECT_EQ(b.rejected, 1);
  ASSERT_EQ(b.objects.size(), 2u);
  for (size_t o = 0; o < 2; ++o) {
    const ObjectTrack &w = r.objects[o], &g = b.objects[o];
    EXPECT_EQ(g.name, w.name);
    EXPECT_EQ(g.shape, w.shape);
    EXPECT_EQ(g.kind, w.kind);
    EXPECT_EQ(g.vertices, w.vertices);
    EXPECT_EQ(g.faces, w.faces);
    ASSERT_EQ(g.poses.size(), 3u);
    for (size_t i = 0; i < 3; ++i) EXPECT_LT((g.poses[i].matrix() - w.poses[i].matrix()).norm(), 1e-14) << o << " " << i;
  }
  EXPECT_GT((b.objects[0].poses[1].matrix() - b.objects[1].poses[1].matrix()).norm(), 0.5);
  const std::string d = describe_scene_parts(b);
  EXPECT_NE(d.find("bodies: alice (3 skin vertices), bob (3 skin vertices)"), std::string::npos) << d;
  EXPECT_NE(d.find("objects: ball (sphere, dynamic), crate (box, kinematic)"), std::string::npos) << d;
  EXPECT_EQ(describe_scene_parts(small_result()), "");
}

TEST(ResultFile, ToolsKeepPosesClosuresForcesTorquesAndEvents) {
  // Two tools, every value distinct and none a default: poses turning about
  // different axes, closures, forces and torques changing per frame, and a
  // grasp and a release.
  test::TempDir tmp;
  SimulationResult r = scene_result();
  for (int t = 0; t < 2; ++t) {
    ToolTrack track{t == 0 ? "gripper" : "probe", {}};
    for (int f = 0; f < 3; ++f) {
      ToolFrame tf;
      tf.pose = pose(0.3 + 0.2 * f + t, Vec3(t, 1, 0.5), Vec3(0.1 * f, 1.05 - 0.01 * t, 0.118 + 0.003 * f));
      tf.closure = 0.8 - 0.25 * f + 0.05 * t;
      tf.force = Vec3(0.5 * f - t, 2.5 + f, -1.25 * (t + 1));
      tf.torque = Vec3(0.01 * (f + 1), -0.02 * t, 0.003 * f + 0.007);
      track.frames.push_back(tf);
    }
    r.tools.push_back(track);
  }
  r.tool_events = {{0.125, "gripper", "alice", "grasp", 7}, {0.2, "probe", "bob", "release", 3}};
  write_simulation_result(r, tmp.file("t.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("t.h5"));
  ASSERT_EQ(b.tools.size(), 2u);
  for (size_t t = 0; t < 2; ++t) {
    EXPECT_EQ(b.tools[t].name, r.tools[t].name);
    ASSERT_EQ(b.tools[t].frames.size(), 3u);
    for (size_t f = 0; f < 3; ++f) {
      const ToolFrame &w = r.tools[t].frames[f], &g = b.tools[t].frames[f];
      EXPECT_LT((g.pose.matrix() - w.pose.matrix()).norm(), 1e-14) << t << " " << f;
      EXPECT_EQ(g.closure, w.closure);
      EXPECT_EQ(g.force, w.force);
      EXPECT_EQ(g.torque, w.torque);
    }
  }
  ASSERT_EQ(b.tool_events.size(), 2u);
  for (size_t e = 0; e < 2; ++e) {
    EXPECT_EQ(b.tool_events[e].time, r.tool_events[e].time);
    EXPECT_EQ(b.tool_events[e].tool, r.tool_events[e].tool);
    EXPECT_EQ(b.tool_events[e].body, r.tool_events[e].body);
    EXPECT_EQ(b.tool_events[e].kind, r.tool_events[e].kind);
    EXPECT_EQ(b.tool_events[e].points, r.tool_events[e].points);
  }
  // The objects are unchanged by the tools next to them; a result without
  // tools has none.
  EXPECT_EQ(b.objects.size(), 2u);
  write_simulation_result(scene_result(), tmp.file("none.h5"));
  const SimulationResult n = read_simulation_result(tmp.file("none.h5"));
  EXPECT_TRUE(n.tools.empty());
  EXPECT_TRUE(n.tool_events.empty());
  // A tool with a frame missing, or a non-finite force, is not written.
  SimulationResult bad = r;
  bad.tools[1].frames.pop_back();
  test::expect_error([&] { write_simulation_result(bad, tmp.file("bad.h5")); }, {"tool 'probe'", "2 frames for 3"});
  bad = r;
  bad.tools[0].frames[1].force.y() = std::nan("");
  test::expect_error([&] { write_simulation_result(bad, tmp.file("bad.h5")); }, {"frame 1", "tool 'gripper'", "non-finite"});
}

TEST(ResultFile, WriterRejectsScenesThatDoNotFit) {
  test::TempDir tmp;
  SimulationResult r = scene_result();
  r.body_vertex_offsets = {0, 4};
  test::expect_error([&] { write_simulation_result(r, tmp.file("a.h5")); }, {"a.h5", "/bodies/vertex_offsets", "3 entries"});
  r = scene_result();
  r.objects[1].shape = "cone";
  test::expect_error([&] { write_simulation_result(r, tmp.file("a.h5")); }, {"crate", "shape 'cone'"});
  r = scene_result();
  r.objects[0].poses[2].linear() *= 1.5;
  test::expect_error([&] { write_simulation_result(r, tmp.file("a.h5")); }, {"frame 2", "'ball'", "rigid"});
  r = scene_result();
  r.objects[0].poses.pop_back();
  test::expect_error([&] { write_simulation_result(r, tmp.file("a.h5")); }, {"'ball' has 2 poses for 3 frames"});
  r = scene_result();
  r.frame_joints[1] = Points::Zero(24, 3);
  test::expect_error([&] { write_simulation_result(r, tmp.file("a.h5")); }, {"frame 1", "joints", "48"});
  EXPECT_FALSE(std::filesystem::exists(tmp.file("a.h5")));
  // Streaming: a frame without the object poses.
  r = scene_result();
  ResultWriter w(tmp.file("b.h5"), r.faces, r.surface_rest, 5, false, result_scene(r));
  test::expect_error([&] { w.add_frame({0.0, 1.0, r.frame_positions[0], r.frame_displacement[0], r.frame_joints[0], r.frame_reduced[0], Vec3::Zero(), {}, {}}); },
                     {"frame 0", "0 object poses for 2 objects"});
}

namespace {

/// A result file written dataset by dataset (not through ResultWriter), in
/// the layout of format `version`, with knobs to break it.
struct RawFile {
  int version = 2;
  std::vector<std::string> body_names;
  std::vector<int> offsets;
  std::int64_t joint_rows = 24;
  int objects = 0;         ///< objects in /frames/object_poses
  int object_groups = -1;  ///< /objects/<i> groups written (-1: = objects)
  double quaternion_scale = 1.0;
  int face_index = 2;      ///< the skin triangle's last index (3 vertices)
  int bone_steps = -1;     ///< entries of /steps/bones (-1: no bones; the file has 3 steps)
  double bone_quaternion_scale = 1.0;
};

void write_raw(const std::string& path, const RawFile& o) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write_scalar("/meta/format_version", std::int64_t(o.version));
  f.write_string("/meta/units", "metres, seconds");
  f.write_string("/meta/avatar", "old.h5");
  f.write_string("/meta/motion", "builtin:walk");
  f.write_scalar("/meta/dt", 0.01);
  f.write_string("/meta/bones", "kinematic");
  f.write_scalar("/meta/newton_iters", std::int64_t(2));
  const int faces[3] = {0, 1, o.face_index};
  f.write("/surface/faces", faces, 1, 3);
  const double rest[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  f.write("/surface/rest", rest, 3, 3);
  if (!o.body_names.empty()) f.write_strings("/bodies/names", o.body_names);
  if (!o.offsets.empty()) f.write_nd("/bodies/vertex_offsets", o.offsets.data(), {std::int64_t(o.offsets.size())});
  const double time[2] = {0.0, 0.5}, ms[2] = {1.5, 2.5};
  f.write_nd("/frames/time", time, {2});
  f.write_nd("/frames/step_ms", ms, {2});
  std::vector<double> pos(18), joints(size_t(2 * o.joint_rows * 3)), reduced(8);
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = 0.125 * double(i);
  for (size_t i = 0; i < joints.size(); ++i) joints[i] = -0.5 * double(i);
  for (size_t i = 0; i < reduced.size(); ++i) reduced[i] = 0.25 * double(i);
  f.write_nd("/frames/positions", pos.data(), {2, 3, 3}, true);
  f.write_nd("/frames/displacement", pos.data(), {2, 3, 3}, true);
  f.write_nd("/frames/joints", joints.data(), {2, o.joint_rows, 3});
  f.write_nd("/frames/reduced", reduced.data(), {2, 4});
  if (o.objects > 0) {
    std::vector<double> poses;
    for (int i = 0; i < 2 * o.objects; ++i)
      for (double x : {0.1 * i, 1.0, 2.0, o.quaternion_scale * std::cos(0.2 * i), 0.0, o.quaternion_scale * std::sin(0.2 * i), 0.0})
        poses.push_back(x);
    f.write_nd("/frames/object_poses", poses.data(), {2, o.objects, 7});
  }
  const int groups = o.object_groups < 0 ? o.objects : o.object_groups;
  for (int i = 0; i < groups; ++i) {
    const std::string g = "/objects/" + std::to_string(i);
    f.write_string(g + "/name", "obj" + std::to_string(i));
    f.write_string(g + "/shape", "box");
    f.write_string(g + "/kind", "static");
    f.write(g + "/vertices", rest, 3, 3);
    f.write(g + "/faces", faces, 1, 3);
  }
  const double steps[3] = {0.01, 0.02, 0.03}, outcome[3] = {0, 1, 0};
  for (const char* n : {"/steps/time", "/steps/energy", "/steps/grad_norm", "/steps/newton_decrement", "/steps/ms"})
    f.write_nd(n, steps, {3});
  f.write_nd("/steps/outcome", outcome, {3});
  if (o.bone_steps >= 0) {
    // Entry s, bone j: at (0.1 j, s, −1), turned 0.1 s j rad about y (half of it in the quaternion).
    std::vector<double> rows;
    for (int s = 0; s < o.bone_steps; ++s)
      for (int j = 0; j < 24; ++j)
        for (double x : {0.1 * j, double(s), -1.0, o.bone_quaternion_scale * std::cos(0.05 * s * j), 0.0,
                         o.bone_quaternion_scale * std::sin(0.05 * s * j), 0.0})
          rows.push_back(x);
    f.write_nd("/steps/bones", rows.data(), {o.bone_steps, 24, 7});
    f.write_nd("/meta/start_bones", rows.data(), {2, 24, 7});
  }
  f.commit();
}

}  // namespace

TEST(ResultFile, VersionOneFilesStillRead) {
  test::TempDir tmp;
  RawFile v1;
  v1.version = 1;
  write_raw(tmp.file("v1.h5"), v1);
  const SimulationResult r = read_simulation_result(tmp.file("v1.h5"));
  EXPECT_EQ(r.avatar, "old.h5");
  EXPECT_EQ(r.num_frames, 2);
  EXPECT_TRUE(r.body_names.empty());
  EXPECT_TRUE(r.objects.empty());
  ASSERT_EQ(r.frame_joints.size(), 2u);
  EXPECT_EQ(r.frame_joints[1].rows(), 24);
  EXPECT_EQ(r.frame_joints[1](0, 0), -0.5 * 72);
  EXPECT_EQ(r.frame_positions[1](2, 2), 0.125 * 17);
  EXPECT_EQ(r.frame_reduced[1][3], 0.25 * 7);
  EXPECT_EQ(r.damped, 1);
  // The same layout with two objects and two bodies is a valid version 2 file.
  RawFile v2;
  v2.body_names = {"a", "b"};
  v2.offsets = {0, 1, 3};
  v2.joint_rows = 48;
  v2.objects = 2;
  write_raw(tmp.file("v2.h5"), v2);
  const SimulationResult s = read_simulation_result(tmp.file("v2.h5"));
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[1].name, "obj1");
  // Object 1 at frame 1 is row 3: q = (cos 0.6, 0, sin 0.6, 0), a turn by
  // 1.2 rad about +Y, at (0.3, 1, 2).
  const Isometry expected = pose(1.2, Vec3::UnitY(), Vec3(0.3, 1, 2));
  EXPECT_LT((s.objects[1].poses[1].matrix() - expected.matrix()).norm(), 1e-14);
}

TEST(ResultFile, ReaderRejectsMalformedScenes) {
  test::TempDir tmp;
  auto expect_rejected = [&](const RawFile& o, std::initializer_list<std::string> fragments) {
    write_raw(tmp.file("bad.h5"), o);
    test::expect_error([&] { read_simulation_result(tmp.file("bad.h5")); }, fragments);
  };
  RawFile o;
  o.version = 3;
  expect_rejected(o, {"bad.h5", "/meta/format_version is 3"});
  o = RawFile();
  o.body_names = {"a", "b"};
  o.offsets = {0, 3};
  o.joint_rows = 48;
  expect_rejected(o, {"bad.h5", "/bodies/names has 2 bodies", "3 entries, got 2"});
  o.offsets = {0, 2, 3};
  o.joint_rows = 24;
  expect_rejected(o, {"bad.h5", "/frames/joints"});
  o = RawFile();
  o.offsets = {0, 3};
  expect_rejected(o, {"/bodies/vertex_offsets given without /bodies/names"});
  o = RawFile();
  o.objects = 2;
  o.quaternion_scale = 1.1;
  expect_rejected(o, {"bad.h5", "/frames/object_poses, frame 0, object 0", "unit quaternion"});
  o.quaternion_scale = 1.0;
  o.object_groups = 1;
  expect_rejected(o, {"bad.h5", "/objects/1 is missing"});
  o.object_groups = 3;
  expect_rejected(o, {"bad.h5", "/objects/2 has no poses"});
  o = RawFile();
  o.face_index = 3;
  expect_rejected(o, {"bad.h5", "/surface/faces"});
}

TEST(ResultFile, EveryStepsBonesComeBackAndBadOnesAreRefused) {
  // Bones with distinct rotations and translations per step, bone and start
  // entry: read back to round-off (stored as position + unit quaternion).
  test::TempDir tmp;
  SimulationResult r = small_result();
  auto bones = [](double k) {
    std::vector<Isometry> g;
    for (int j = 0; j < 24; ++j) {
      Isometry T = Isometry::Identity();
      T.linear() = Eigen::AngleAxisd(0.1 * j + k, Vec3(1, 2, 3 + k).normalized()).toRotationMatrix();
      T.translation() = Vec3(0.01 * j, -k, 0.5 + 0.001 * j * k);
      g.push_back(T);
    }
    return g;
  };
  r.start_bones = {bones(-2.0), bones(-1.0)};
  for (size_t s = 0; s < r.step_time.size(); ++s) r.step_bones.push_back(bones(0.3 * double(s)));
  write_simulation_result(r, tmp.file("r.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  ASSERT_EQ(b.step_bones.size(), r.step_bones.size());
  ASSERT_EQ(b.start_bones.size(), 2u);
  auto same = [](const std::vector<Isometry>& x, const std::vector<Isometry>& y) {
    double d = 0;
    for (size_t j = 0; j < x.size(); ++j) d = std::max(d, (x[j].matrix() - y[j].matrix()).cwiseAbs().maxCoeff());
    return d;
  };
  EXPECT_LT(same(b.start_bones[0], r.start_bones[0]), 1e-14);
  EXPECT_LT(same(b.start_bones[1], r.start_bones[1]), 1e-14);
  for (size_t s = 0; s < r.step_bones.size(); ++s) EXPECT_LT(same(b.step_bones[s], r.step_bones[s]), 1e-14) << s;
  // Without bones (a live run, an older file) neither dataset is written and none is read.
  write_simulation_result(small_result(), tmp.file("none.h5"));
  EXPECT_TRUE(read_simulation_result(tmp.file("none.h5")).step_bones.empty());
  // A step without its bones, and a pose that is not rigid, are refused naming what.
  SimulationResult short_run = r;
  short_run.step_bones.pop_back();
  test::expect_error([&] { write_simulation_result(short_run, tmp.file("bad.h5")); },
                     {"bad.h5", "7 steps of bones for 8 steps"});
  SimulationResult sheared = r;
  sheared.step_bones[2][5].linear()(0, 1) += 0.1;
  test::expect_error([&] { write_simulation_result(sheared, tmp.file("bad.h5")); },
                     {"bad.h5", "/steps/bones entry 2, bone 5", "not a rigid motion"});
  EXPECT_FALSE(std::filesystem::exists(tmp.file("bad.h5")));
  RawFile o;
  o.bone_steps = 3;
  o.bone_quaternion_scale = 1.5;
  write_raw(tmp.file("bad.h5"), o);
  test::expect_error([&] { read_simulation_result(tmp.file("bad.h5")); },
                     {"bad.h5", "/steps/bones, entry 0, bone 0", "unit quaternion"});
  o.bone_quaternion_scale = 1.0;
  o.bone_steps = 2;  // the file has 3 steps
  write_raw(tmp.file("bad.h5"), o);
  test::expect_error([&] { read_simulation_result(tmp.file("bad.h5")); }, {"bad.h5", "/steps/bones"});
  o.bone_steps = 3;
  write_raw(tmp.file("good.h5"), o);
  const SimulationResult g = read_simulation_result(tmp.file("good.h5"));
  ASSERT_EQ(g.step_bones.size(), 3u);
  // Step 2, bone 5 as write_raw makes it: at (0.5, 2, −1), turned 1 rad about y (w = cos 0.5, y = sin 0.5).
  EXPECT_LT((g.step_bones[2][5].translation() - Vec3(0.5, 2, -1)).norm(), 1e-15);
  EXPECT_LT((g.step_bones[2][5].linear() - Eigen::AngleAxisd(1.0, Vec3::UnitY()).toRotationMatrix()).norm(), 1e-14);
}
