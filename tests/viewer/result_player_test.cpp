// Playback (`sflsh view`): the frame shown at time t is the result file's
// frame at time t (the last frame at or before t), through the server and a
// WebSocket client, to within the 16-bit quantization of positions; the
// result's tools (pose, force, torque, closure per frame, grasp events) and
// contacts (force, point, depth, samples per frame) reach the page with the
// values the file holds.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sflsh/scene/result_file.hpp"
#include "sflsh/viewer/result_player.hpp"
#include "sflsh/viewer/viewer_server.hpp"
#include "sflsh/viewer/web_assets.hpp"
#include "test_support.hpp"
#include "viewer_test_support.hpp"

namespace sflsh::viewer {
namespace {

// Four frames 0.1 s apart; frame k's skin is the rest shape moved by (k cm, 2k cm, 0) and
// its displacement is (k mm, 0, 0) per vertex.
SimulationResult four_frames() {
  const ViewerScene s = test::tiny_scene();
  SimulationResult r;
  r.avatar = "tiny";
  r.motion = "none";
  r.dt = 0.01;
  r.faces = s.faces;
  r.surface_rest = s.rest;
  for (int k = 0; k < 4; ++k) {
    r.frame_time.push_back(0.1 * k);
    r.frame_step_ms.push_back(1.0);
    Points p = s.rest;
    p.col(0).array() += 0.01 * k;
    p.col(1).array() += 0.02 * k;
    r.frame_positions.push_back(p);
    Points u = Points::Zero(s.rest.rows(), 3);
    u.col(0).array() = 0.001 * k;
    r.frame_displacement.push_back(u);
    r.frame_joints.push_back(Points::Zero(24, 3));
    r.frame_reduced.push_back(VecX::Zero(2));
    r.add_step(0.1 * k, StepReport{});
  }
  r.num_frames = 4;
  return r;
}

// four_frames with two tools: "grip", drawn by an object of its name and a jaw
// object "grip/jaw0", and "probe" without a surface; distinct values per frame
// k and tool, and a grasp and a release.
SimulationResult four_frames_with_tools() {
  SimulationResult r = four_frames();
  const ViewerScene s = test::tiny_scene();
  ObjectTrack grip{"grip", "sphere", "kinematic", s.rest, s.faces, {}};
  ObjectTrack jaw{"grip/jaw0", "box", "kinematic", s.rest, s.faces, {}};
  ToolTrack grip_tool{"grip", {}}, probe_tool{"probe", {}};
  for (int k = 0; k < 4; ++k) {
    ToolFrame g;
    g.pose = Isometry::Identity();
    g.pose.linear() = Eigen::AngleAxisd(0.1 * k + 0.05, Vec3::UnitZ()).toRotationMatrix();
    g.pose.translation() = Vec3(0.1 + 0.01 * k, 0.2, 0.3);
    g.closure = 0.05 + 0.1 * k;
    g.force = Vec3(1.0 + k, -2.0, 0.5);
    g.torque = Vec3(0.01, 0.02 * k, -0.03);
    grip_tool.frames.push_back(g);
    ToolFrame p;
    p.pose.translation() = Vec3(-0.2, 0.1 * k, 0.0);
    p.force = Vec3(0.0, 0.0, 3.0 * k + 0.25);
    probe_tool.frames.push_back(p);
    grip.poses.push_back(g.pose);
    Isometry jaw_pose = g.pose;
    jaw_pose.translation().x() += 0.001 * k;
    jaw.poses.push_back(jaw_pose);
  }
  r.objects = {grip, jaw};
  r.tools = {grip_tool, probe_tool};
  r.tool_events = {{0.1, "grip", "body", "grasp", 5}, {0.3, "grip", "body", "release", 4}};
  return r;
}

TEST(ResultPlayer, FrameAtTimeIsTheLastFrameAtOrBefore) {
  const std::vector<double> t = {0.0, 0.1, 0.2, 0.3};
  EXPECT_EQ(frame_at(t, -1.0), 0);
  EXPECT_EQ(frame_at(t, 0.0), 0);
  EXPECT_EQ(frame_at(t, 0.0999), 0);
  EXPECT_EQ(frame_at(t, 0.1), 1);
  EXPECT_EQ(frame_at(t, 0.25), 2);
  EXPECT_EQ(frame_at(t, 7.0), 3);
}

TEST(ResultPlayer, ControlsMoveThePlaybackClock) {
  const SimulationResult r = four_frames();
  ResultPlayer p(r);
  EXPECT_TRUE(p.paused());
  ControlMessage m;
  m.type = ControlType::kPause;
  m.paused = false;
  p.apply(m);
  m.type = ControlType::kSpeed;
  m.value = 0.5;
  p.apply(m);
  p.advance(0.4);  // 0.2 s of result time
  EXPECT_NEAR(p.time(), 0.2, 1e-12);
  EXPECT_EQ(p.frame(), 2);
  p.advance(10);  // past the end: holds the last frame, paused
  EXPECT_EQ(p.frame(), 3);
  EXPECT_TRUE(p.paused());
  m.type = ControlType::kReset;
  p.apply(m);
  m.type = ControlType::kStep;
  p.apply(m);
  EXPECT_EQ(p.frame(), 1);
  m.type = ControlType::kTool;
  EXPECT_FALSE(p.apply(m));
}

TEST(ResultPlayer, TheFrameShownAtTimeTIsTheFilesFrameAtT) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  sflsh::test::TempDir dir;
  write_simulation_result(four_frames(), dir.file("r.h5"));
  const SimulationResult r = read_simulation_result(dir.file("r.h5"));
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  ViewerServer server(viewer_scene(r, {}, 0.05, 0.001), o);
  ResultPlayer player(r);
  test::Client client(server.port());
  client.read();  // the scene
  QuantizedSkin state;
  const Vec3 size = server.scene().box_max - server.scene().box_min;
  for (const double t : {0.0, 0.15, 0.2, 0.29, 0.3}) {
    ControlMessage seek;
    seek.type = ControlType::kSeek;
    seek.value = t;
    player.apply(seek);
    server.publish(player.current());
    const DecodedFrame d = decode_frame(client.read(), server.scene(), &state);
    // The frame at t, by hand: floor(t / 0.1) (t on a frame time shows that frame).
    const int k = int(std::floor(t / 0.1 + 1e-9));
    Points expected = server.scene().rest;  // frame 0's skin
    expected.col(0).array() += 0.01 * k;
    expected.col(1).array() += 0.02 * k;
    for (int c = 0; c < 3; ++c)
      EXPECT_LE((d.positions.col(c) - expected.col(c)).cwiseAbs().maxCoeff(), size[c] / 65535 / 2 + 1e-7) << "t " << t;
    EXPECT_NEAR(d.displacement[0], 0.001 * k, 0.003 / 255) << "t " << t;  // legend 3 mm in 8 bits
    EXPECT_EQ(nlohmann::json::parse(d.info)["frame"], k) << "t " << t;
    EXPECT_NEAR(d.time, t, 1e-12);
  }
}

TEST(ResultPlayer, TheResultsToolsReachThePageWithTheFilesValues) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  sflsh::test::TempDir dir;
  const SimulationResult written = four_frames_with_tools();
  write_simulation_result(written, dir.file("r.h5"));
  const SimulationResult r = read_simulation_result(dir.file("r.h5"));
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  ViewerServer server(playback_scene(r, "r.h5"), o);
  ResultPlayer player(r);
  test::Client client(server.port());
  bool text = false;
  const nlohmann::json scene = nlohmann::json::parse(client.read(&text));
  ASSERT_TRUE(text);
  EXPECT_EQ(scene["mode"], "playback");
  ASSERT_EQ(scene["tools"].size(), 2u);
  EXPECT_EQ(scene["tools"][0]["name"], "grip");
  EXPECT_EQ(scene["tools"][0]["object"], 0);
  EXPECT_EQ(scene["tools"][1]["name"], "probe");
  EXPECT_EQ(scene["tools"][1]["object"], -1);  // no surface: the page draws a marker
  EXPECT_EQ(scene["objects"][0]["kind"], "tool");
  EXPECT_EQ(scene["objects"][1]["kind"], "tool");  // the jaw
  ASSERT_EQ(scene["tool_events"].size(), 2u);
  EXPECT_EQ(scene["tool_events"][0]["kind"], "grasp");
  EXPECT_EQ(scene["tool_events"][0]["tool"], "grip");
  EXPECT_EQ(scene["tool_events"][0]["body"], "body");
  EXPECT_EQ(scene["tool_events"][0]["points"], 5);
  EXPECT_DOUBLE_EQ(scene["tool_events"][1]["time"].get<double>(), 0.3);
  EXPECT_EQ(scene["tool_events"][1]["kind"], "release");
  QuantizedSkin state;
  for (int k : {2, 0, 3}) {
    ControlMessage seek;
    seek.type = ControlType::kSeek;
    seek.value = 0.1 * k;
    player.apply(seek);
    server.publish(player.current());
    const DecodedFrame d = decode_frame(client.read(), server.scene(), &state);
    const nlohmann::json tools = nlohmann::json::parse(d.info)["tools"];
    ASSERT_EQ(tools.size(), 2u) << "frame " << k;
    for (size_t t = 0; t < 2; ++t) {
      const ToolFrame& w = written.tools[t].frames[size_t(k)];
      const nlohmann::json& g = tools[t];
      const Eigen::Quaterniond q(w.pose.rotation());
      const double pose[7] = {w.pose.translation().x(), w.pose.translation().y(), w.pose.translation().z(),
                              q.w(), q.x(), q.y(), q.z()};
      for (int c = 0; c < 7; ++c) EXPECT_NEAR(g["pose"][c].get<double>(), pose[c], 1e-12) << "frame " << k << " tool " << t;
      for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(g["force"][c].get<double>(), w.force[c]) << "frame " << k << " tool " << t;
        EXPECT_DOUBLE_EQ(g["torque"][c].get<double>(), w.torque[c]) << "frame " << k << " tool " << t;
      }
      EXPECT_DOUBLE_EQ(g["closure"].get<double>(), w.closure) << "frame " << k << " tool " << t;
    }
    // The grip's surface and its jaw are posed by the frame's object poses.
    ASSERT_EQ(d.object_poses.size(), 2u);
    EXPECT_LE((d.object_poses[1].translation() - written.objects[1].poses[size_t(k)].translation()).norm(), 1e-6);
  }
}

TEST(ResultPlayer, TheResultsContactsReachThePageWithTheFilesValues) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  sflsh::test::TempDir dir;
  SimulationResult written = four_frames();
  written.contacts = {{"contact:floor", "body", {}}, {"self_contact", "body", {}}};
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 2; ++c)
      written.contacts[size_t(c)].frames.push_back(
          {Vec3(0.5 + k, -2.0 * (c + 1), 0.25 * k), Vec3(0.01 * k, -0.02, 0.1 * c), 1e-3 * (k + 1) + c, 3 * k + c});
  write_simulation_result(written, dir.file("r.h5"));
  const SimulationResult r = read_simulation_result(dir.file("r.h5"));
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  ViewerServer server(playback_scene(r, "r.h5"), o);
  ResultPlayer player(r);
  test::Client client(server.port());
  const nlohmann::json scene = nlohmann::json::parse(client.read());
  ASSERT_EQ(scene["contacts"].size(), 2u);
  EXPECT_EQ(scene["contacts"][0]["term"], "contact:floor");
  EXPECT_EQ(scene["contacts"][1]["term"], "self_contact");
  EXPECT_EQ(scene["contacts"][1]["body"], "body");
  QuantizedSkin state;
  for (int k : {3, 1}) {
    ControlMessage seek;
    seek.type = ControlType::kSeek;
    seek.value = 0.1 * k;
    player.apply(seek);
    server.publish(player.current());
    const DecodedFrame d = decode_frame(client.read(), server.scene(), &state);
    const nlohmann::json contacts = nlohmann::json::parse(d.info)["contacts"];
    ASSERT_EQ(contacts.size(), 2u) << "frame " << k;
    for (size_t c = 0; c < 2; ++c) {
      const ContactFrame& w = written.contacts[c].frames[size_t(k)];
      for (int i = 0; i < 3; ++i) {
        EXPECT_DOUBLE_EQ(contacts[c]["force"][i].get<double>(), w.force[i]) << "frame " << k << " contact " << c;
        EXPECT_DOUBLE_EQ(contacts[c]["point"][i].get<double>(), w.point[i]) << "frame " << k << " contact " << c;
      }
      EXPECT_DOUBLE_EQ(contacts[c]["depth_mm"].get<double>(), w.max_penetration * 1e3) << "frame " << k;
      EXPECT_EQ(contacts[c]["active"].get<int>(), w.active) << "frame " << k;
    }
  }
}

}  // namespace
}  // namespace sflsh::viewer
