// Tools in a scene session on the small box avatar: a coupled probe
// pressed into the flesh is held out by contact while its device goes deeper,
// and the device feels the coupling spring k (c − d) — equal, at rest, to what
// the flesh pushes on the tool — scaled by the haptic gain and clamped at
// max_force; a live UDP stream drives a tool, gets the force back, and a
// malformed or NaN datagram leaves the last good pose; a recorded session
// replays bit-identically.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/teleop/stream_message.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using ToolSession = test::BoxAvatarScene;

SceneSessionOptions quiet() {
  SceneSessionOptions o;
  o.progress = false;
  return o;
}

/// A probe (5 mm sphere) whose device goes from 1.5 cm above the 6 cm box's
/// top to 1 cm below it by 0.3 s and stays there.
const char* kProbeScene = R"(
solver: {dt: 1/250, seconds: 0.8, gravity: [0, 0, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.3, position: [0.0, 0.020, 0.0]}
    coupling: {stiffness: 2000, mass: 0.05, max_force: 100, haptic_gain: 1}
)";

}  // namespace

TEST_F(ToolSession, CoupledProbeIsHeldByTheFleshAndTheDeviceFeelsTheSpring) {
  SceneSession s(read_scene_description(write_scene(kProbeScene)), quiet());
  ASSERT_EQ(s.num_tools(), 1);
  while (s.steps_done() < s.total_steps()) ASSERT_EQ(s.advance().rejected, 0);
  const SceneToolState& ts = s.tool_state(0);
  const Vec3 c = ts.pose.translation(), d = ts.device.position;
  EXPECT_NEAR(d.y(), 0.020, 1e-12);
  // The flesh holds the tool above its device: its centre stays above the
  // top minus its radius plus what it dents (well short of the device's 1 cm).
  EXPECT_GT(c.y() - d.y(), 0.005);
  // (It may settle off-centre by a little: the dent's slope and friction on
  // the 1 cm cells' facets balance some of the spring's lateral pull.)
  EXPECT_LT(std::abs(c.x()) + std::abs(c.z()), 2e-3);
  // At rest the device feels k (c − d), and the flesh pushes the tool up by as much.
  const Vec3 spring = 2000.0 * (c - d);
  EXPECT_LT((ts.feedback_force - spring).norm(), 0.01 * spring.norm()) << ts.feedback_force.transpose() << " vs "
                                                                        << spring.transpose();
  EXPECT_LT((ts.force - spring).norm(), 0.03 * spring.norm()) << ts.force.transpose();
  EXPECT_GT(ts.force.y(), 1.0);
}

TEST_F(ToolSession, FeedbackIsScaledByTheHapticGainAndClampedAtMaxForce) {
  SceneDescription sc = read_scene_description(write_scene(kProbeScene));
  sc.tools[0].coupling.haptic_gain = 0.5;
  SceneSession half(sc, quiet());
  sc.tools[0].coupling.haptic_gain = 1.0;
  sc.tools[0].coupling.max_force = 1.0;
  SceneSession clamped(sc, quiet());
  for (long k = 0; k < half.total_steps(); ++k) half.advance(), clamped.advance();
  const SceneToolState &a = half.tool_state(0), &b = clamped.tool_state(0);
  const Vec3 spring = 2000.0 * (a.pose.translation() - a.device.position);
  ASSERT_GT(spring.norm(), 2.0);
  EXPECT_LT((a.feedback_force - 0.5 * spring).norm(), 0.01 * spring.norm());
  // The clamp changes only what the device is sent, not the physics.
  EXPECT_EQ(a.pose.translation(), b.pose.translation());
  EXPECT_NEAR(b.feedback_force.norm(), 1.0, 1e-12);
  EXPECT_GT(b.feedback_force.normalized().dot(spring.normalized()), 0.999);
}

namespace {

/// A UDP client socket on 127.0.0.1 (the test's "device").
struct Device {
  int fd = -1;
  sockaddr_in to{};
  explicit Device(int port) {
    fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    to.sin_family = AF_INET;
    to.sin_port = htons(std::uint16_t(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~Device() { ::close(fd); }
  void send(const std::uint8_t* data, size_t n) {
    ASSERT_EQ(::sendto(fd, data, n, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to), ssize_t(n));
  }
  void pose(std::uint64_t seq, double t, const Vec3& p, double closure = 0.5) {
    teleop::PoseMessage m;
    m.sequence = seq;
    m.sample.time = t;
    m.sample.position = p;
    m.sample.closure = closure;
    const auto bytes = teleop::encode_pose(m);
    send(bytes.data(), bytes.size());
  }
  /// The newest feedback message waiting (within `timeout` s), if any.
  std::optional<teleop::FeedbackMessage> feedback(double timeout) {
    std::optional<teleop::FeedbackMessage> out;
    pollfd p{fd, POLLIN, 0};
    while (::poll(&p, 1, out ? 0 : int(timeout * 1000)) > 0) {
      std::uint8_t buf[256];
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;
      const auto d = teleop::decode_feedback(buf, size_t(n));
      if (d.message) out = *d.message;
    }
    return out;
  }
};

/// Steps `s` until its tool's device position is `p` (the link's thread got
/// the datagram) or 30 s pass (a guard against a hang, not a time limit); returns whether it got there.
bool step_until_device_at(SceneSession& s, const Vec3& p) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(30)) {
    s.advance();
    if (s.tool_state(0).device.position == p) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

}  // namespace

TEST_F(ToolSession, ALiveStreamDrivesTheToolAndGetsTheForceBackAndBadDatagramsAreIgnored) {
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 10, gravity: [0, 0, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    pose_stream: {port: 0, max_speed: 5}
    keyframes: [{time: 0, position: [0.0, 0.045, 0.0]}]
)"));
  SceneSession s(sc, quiet());
  const int port = s.stream_port(0);
  ASSERT_GT(port, 0);
  s.advance();
  EXPECT_FALSE(s.tool_state(0).live);
  EXPECT_EQ(s.tool_state(0).device.position, Vec3(0.0, 0.045, 0.0));  // keyframe until the first sample
  Device dev(port);
  // The device presses the probe 3 mm into the top in 1 mm steps, 10 ms apart.
  std::uint64_t seq = 1;
  double t = 0;
  for (double y : {0.040, 0.035, 0.031, 0.030, 0.029, 0.028, 0.027}) {
    t += 0.01;
    dev.pose(seq++, t, Vec3(0, y, 0));
    ASSERT_TRUE(step_until_device_at(s, Vec3(0, y, 0))) << "y = " << y;
  }
  EXPECT_TRUE(s.tool_state(0).live);
  for (int i = 0; i < 20; ++i) s.advance();
  // The flesh pushes the kinematic probe up; the reply carries that force.
  const Vec3 force = s.tool_state(0).feedback_force;
  EXPECT_GT(force.y(), 0.1);
  dev.pose(seq++, t += 0.01, Vec3(0, 0.027, 0));
  ASSERT_TRUE(step_until_device_at(s, Vec3(0, 0.027, 0)));
  // A reply comes for every accepted pose, with the force of the latest step
  // (the one published before the link answered).
  // (The link answers right after it stores the pose the session just took:
  // read until the answer to the newest pose is in, within 1 s.)
  std::optional<teleop::FeedbackMessage> fb;
  for (int tries = 0; tries < 100 && !(fb && fb->sequence == seq - 1); ++tries)
    if (auto got = dev.feedback(0.01)) fb = got;
  ASSERT_TRUE(fb.has_value());
  EXPECT_EQ(fb->sequence, seq - 1);
  EXPECT_GT(fb->force.y(), 0.1);
  // A malformed datagram, a NaN pose and a 5 m jump in 10 ms: each rejected,
  // the tool holds its last good pose.
  const std::uint8_t junk[5] = {1, 2, 3, 4, 5};
  dev.send(junk, sizeof junk);
  dev.pose(seq++, t += 0.01, Vec3(std::numeric_limits<double>::quiet_NaN(), 0.02, 0));
  dev.pose(seq++, t += 0.01, Vec3(5.0, 0.027, 0));
  const auto start = std::chrono::steady_clock::now();
  while (s.stream_counters(0).find("rejected 3") == std::string::npos &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(30))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_NE(s.stream_counters(0).find("rejected 3"), std::string::npos) << s.stream_counters(0);
  for (int i = 0; i < 10; ++i) s.advance();
  EXPECT_EQ(s.tool_state(0).device.position, Vec3(0, 0.027, 0));
  EXPECT_TRUE(s.tool_state(0).pose.matrix().allFinite());
}

TEST_F(ToolSession, ARecordedLiveSessionReplaysBitIdentically) {
  // A coupled gripper pushed live (as the viewer or a stream does): it
  // presses, grasps, lifts and lets go; the recording replayed offline gives
  // the same bodies and tools, bit for bit.
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 1, gravity: [0, -9.81, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: gripper
    shape: {type: sphere, radius: 0.003}
    keyframes: [{time: 0, position: [0.001, 0.036, 0.002], closure: 1.0}]
    coupling: {stiffness: 5000, mass: 0.05}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.01}]
      hardness: 2.0e4
)"));
  const std::string rec = (dir_ / "rec").string();
  std::filesystem::create_directories(rec);
  SceneSessionOptions o = quiet();
  o.record_dir = rec;
  SceneSession live(sc, o);
  for (int k = 0; k < 200; ++k) {
    teleop::PoseSample p;
    p.position = Vec3(0.001, 0.036 + (k > 60 ? 0.00005 * std::min(k - 60, 80) : 0.0), 0.002);
    p.closure = k < 30 ? 1.0 - k / 30.0 : k < 170 ? 0.0 : 1.0;
    if (k % 3 == 0) live.set_device_pose(0, p);  // a device slower than the physics
    live.advance();
  }
  const std::vector<std::string> files = live.finish_recording();
  ASSERT_EQ(files.size(), 1u);
  ASSERT_EQ(live.tool_events().size(), 2u);  // grasped and released
  SceneSessionOptions r = quiet();
  r.replay_dir = rec;
  SceneSession replay(sc, r);
  for (int k = 0; k < 200; ++k) replay.advance();
  EXPECT_EQ(replay.body_surface(0), live.body_surface(0));
  EXPECT_EQ(replay.tool_state(0).pose.matrix(), live.tool_state(0).pose.matrix());
  EXPECT_EQ(replay.tool_state(0).feedback_force, live.tool_state(0).feedback_force);
  ASSERT_EQ(replay.tool_events().size(), live.tool_events().size());
  EXPECT_EQ(replay.tool_events()[1].time, live.tool_events()[1].time);
}

TEST_F(ToolSession, GripperJawsTurnAboutTheHingeWithTheClosureAndTouchTheFlesh) {
  // Two capsule jaws hanging 1 cm below a hinge 2 mm above the top, 4 mm
  // either side of it; the device closes them from 1 rad to 0 over 0.2 s.
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 0.3, gravity: [0, 0, 0]}
output: {fps: 50}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: gripper
    keyframes:
      - {time: 0.0, position: [0.0, 0.038, 0.0], closure: 1.0}
      - {time: 0.2, position: [0.0, 0.038, 0.0], closure: 0.0}
    gripper:
      hinge: {origin: [0, 0, 0], axis: [1, 0, 0]}
      jaws:
        - {shape: {type: capsule, radius: 0.002, length: 0.01}, offset: [0, -0.01, 0.004], side: 1}
        - {shape: {type: capsule, radius: 0.002, length: 0.01}, offset: [0, -0.01, -0.004], side: -1}
)"));
  SceneSession s(sc, quiet());
  SimulationResult r = s.result_header();
  ASSERT_EQ(r.objects.size(), 2u);
  EXPECT_EQ(r.objects[0].name, "gripper/jaw0");
  double peak = 0;
  while (s.steps_done() < s.total_steps()) {
    s.advance();
    peak = std::max(peak, s.tool_state(0).force.y());
    if (s.steps_done() == 25) s.record_frame(r, 0.0);  // t = 0.1 s: closure 0.5 rad
  }
  s.record_frame(r, 0.0);
  // At t = 0.1 s jaw 0 is turned by +0.25 rad about x through the hinge (the
  // tool origin), jaw 1 by −0.25 rad: by hand, R_x(±0.25) · offset + tool.
  const Vec3 tool(0.0, 0.038, 0.0);
  for (int j = 0; j < 2; ++j) {
    const double a = (j == 0 ? 1 : -1) * 0.25;
    const Mat3 R = Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix();
    const Vec3 offset(0, -0.01, j == 0 ? 0.004 : -0.004);
    const Isometry& P = r.objects[j].poses.at(0);
    EXPECT_LT((P.linear() - R).norm(), 1e-12) << "jaw " << j;
    EXPECT_LT((P.translation() - (tool + R * offset)).norm(), 1e-12) << "jaw " << j;
  }
  // Shut (closure 0): the jaws hang straight, their tips 2 mm + radius into
  // the top; the flesh pushes the tool up through them.
  EXPECT_LT((r.objects[0].poses.back().translation() - (tool + Vec3(0, -0.01, 0.004))).norm(), 1e-12);
  EXPECT_GT(peak, 0.05);
}

namespace {

/// A coupled probe at rest in free space above the box (no contact), its
/// device's first live pose 1 cm to the side; `ramp` is pose_stream.ramp_in.
std::string take_over_yaml(const std::string& ramp) {
  return std::string(R"(
solver: {dt: 1/250, seconds: 2, gravity: [0, 0, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    keyframes: [{time: 0, position: [0.0, 0.08, 0.0]}]
    pose_stream: {port: 0, ramp_in: )") + ramp + R"(}
    coupling: {stiffness: 2.0e4, mass: 0.1, max_force: 1000}
)";
}

}  // namespace

TEST_F(ToolSession, ALiveDeviceTakesOverAToolWithoutAKick) {
  teleop::PoseSample device;
  device.position = Vec3(0.01, 0.08, 0.0);  // 1 cm from the tool's keyframe pose
  // Without a ramp the coupling jumps: the spring stretched by up to 1 cm
  // plus the damper of a device that seems to move 1 cm in one step (54 N here).
  SceneSession abrupt(read_scene_description(write_scene(take_over_yaml("0"))), quiet());
  abrupt.set_device_pose(0, device);
  abrupt.advance();
  EXPECT_GT(abrupt.tool_state(0).feedback_force.norm(), 30.0);
  // With the default ramp the tool is brought over in 0.5 s: in free space the
  // coupling only accelerates the 0.1 kg tool along a smoothstep of 1 cm
  // (peak 6·0.01/0.5² = 0.24 m/s², i.e. 0.024 N).
  SceneDescription sc = read_scene_description(write_scene(take_over_yaml("0.5")));
  SceneSession s(sc, quiet());
  s.set_device_pose(0, device);
  double peak = 0;
  bool ramping_seen = false;
  for (int k = 0; k < 150; ++k) {  // 0.6 s
    s.advance();
    peak = std::max(peak, s.tool_state(0).feedback_force.norm());
    if (k == 0) ramping_seen = s.tool_state(0).ramping_in;
    EXPECT_EQ(s.tool_state(0).device.position, device.position);  // the device's own sample
  }
  EXPECT_TRUE(ramping_seen);
  EXPECT_FALSE(s.tool_state(0).ramping_in);
  EXPECT_LT(peak, 0.1);
  for (int k = 0; k < 100; ++k) s.advance();
  EXPECT_LT((s.tool_state(0).pose.translation() - device.position).norm(), 1e-4);
}

TEST_F(ToolSession, AfterTheRunEndsTheDeviceGetsZeroForceAndStatusEnded) {
  SceneSession s(read_scene_description(write_scene(take_over_yaml("0.5"))), quiet());
  const int port = s.stream_port(0);
  ASSERT_GT(port, 0);
  Device dev(port);
  std::uint64_t seq = 1;
  dev.pose(seq++, 0.01, Vec3(0.01, 0.08, 0.0));
  ASSERT_TRUE(step_until_device_at(s, Vec3(0.01, 0.08, 0.0)));
  for (int k = 0; k < 5; ++k) s.advance();
  dev.pose(seq++, 0.02, Vec3(0.01, 0.08, 0.0));
  std::optional<teleop::FeedbackMessage> fb;
  for (int tries = 0; tries < 100 && !(fb && fb->sequence == seq - 1); ++tries)
    if (auto got = dev.feedback(0.01)) fb = got;
  ASSERT_TRUE(fb.has_value());
  EXPECT_EQ(fb->status, teleop::FeedbackStatus::kRampIn);  // 6+ steps of a 0.5 s ramp
  const double end_time = s.time();
  s.end_feedback();
  dev.pose(seq++, 0.03, Vec3(0.02, 0.07, 0.0));
  fb.reset();
  for (int tries = 0; tries < 100 && !(fb && fb->sequence == seq - 1); ++tries)
    if (auto got = dev.feedback(0.01)) fb = got;
  ASSERT_TRUE(fb.has_value());
  EXPECT_EQ(fb->sequence, seq - 1);
  EXPECT_EQ(fb->status, teleop::FeedbackStatus::kEnded);
  EXPECT_EQ(fb->force, Vec3::Zero());
  EXPECT_EQ(fb->torque, Vec3::Zero());
  EXPECT_DOUBLE_EQ(fb->sim_time, end_time);
}

TEST_F(ToolSession, WithContactPatchAKinematicToolDentsLikeTheSameObject) {
  // A 1 cm probe pressed 4 mm into the top as a kinematic tool, and the same
  // sphere on the same keyframes as a kinematic object: with contact.patch both
  // are the face-sampled contact with a full-space patch, so the tool feels
  // exactly the force the object puts on the body, and the patch is there.
  const std::string head = R"(
solver: {dt: 1/100, seconds: 0.2, gravity: [0, 0, 0]}
contact: {friction: 0, patch: {radius: 0.015}}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
)";
  const std::string keys = R"(
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.2, position: [0.0, 0.036, 0.0]}
)";
  SceneSession tool(read_scene_description(write_scene(head + "tools:\n  - name: probe\n    shape: {type: sphere, radius: 0.01}" + keys)), quiet());
  SceneSession object(read_scene_description(write_scene(
                          head + "objects:\n  - name: probe\n    kind: kinematic\n    shape: {type: sphere, radius: 0.01}" + keys)),
                      quiet());
  Vec3 object_force = Vec3::Zero();
  double patch_nodes = 0;
  for (int k = 0; k < 20; ++k) {
    tool.advance();
    const StepReport& rep = object.advance();
    object_force.setZero();
    for (const TermQuantityReport& q : rep.quantities)
      if (q.term == "contact:probe" && q.name == "force") object_force = Vec3(q.value[0], q.value[1], q.value[2]);
    for (const TermQuantityReport& q : tool.last_report().quantities)
      if (q.term == "contact:probe" && q.name == "patch_nodes") patch_nodes = std::max(patch_nodes, q.value[0]);
  }
  EXPECT_GT(patch_nodes, 0);
  EXPECT_LT(object_force.y(), -0.1);  // the probe presses the body down
  EXPECT_EQ(tool.tool_state(0).force, -object_force);  // the body pushes the tool up by as much
  EXPECT_EQ(tool.body_surface(0), object.body_surface(0));  // the same dent
}

TEST_F(ToolSession, WithContactPatchAGrippersShapeAndAnchorsShareOnePatch) {
  // A kinematic sphere tool with a grasp sensor presses 3 mm into the top,
  // closes and lifts off the skin: with contact.patch its contact and its anchors are
  // one term on the body (one patch, whose displacement both share), and the
  // tool feels minus that term's force.
  const std::string scene = R"(
solver: {dt: 1/100, seconds: 0.3, gravity: [0, 0, 0]}
contact: {friction: 0, patch: {radius: 0.015}}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.01}
    keyframes:
      - {time: 0.0, position: [0.0, 0.042, 0.0], closure: 0.8}
      - {time: 0.1, position: [0.0, 0.037, 0.0], closure: 0.8}
      - {time: 0.15, position: [0.0, 0.037, 0.0], closure: 0.0}
      - {time: 0.3, position: [0.0, 0.043, 0.0], closure: 0.0}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.03}]
      hardness: 2.0e3
)";
  SceneSession s(read_scene_description(write_scene(scene)), quiet());
  int terms = 0;
  for (const Model::BoundTerm& t : s.simulator().model().terms())
    if (t.term->name() == "contact:probe" || t.term->name().rfind("anchor:", 0) == 0) ++terms;
  EXPECT_EQ(terms, 1) << "one term for the tool's shape and anchors";
  EXPECT_EQ(s.compiled_tool(0).anchor_terms, s.compiled_tool(0).contact_terms);
  double anchors = 0, nodes = 0;
  for (int k = 0; k < 30; ++k) {
    const StepReport& rep = s.advance();
    Vec3 force = Vec3::Zero();
    for (const TermQuantityReport& q : rep.quantities) {
      if (q.term != "contact:probe") continue;
      if (q.name == "force") force = Vec3(q.value[0], q.value[1], q.value[2]);
      if (q.name == "anchor_points") anchors = std::max(anchors, double(q.value.size()));
      if (q.name == "patch_nodes") nodes = std::max(nodes, q.value[0]);
    }
    EXPECT_EQ(s.tool_state(0).force, -force) << "step " << k;
  }
  EXPECT_GT(anchors, 0) << "the tool grasped";
  EXPECT_GT(nodes, 0);
  EXPECT_GT(s.tool_state(0).anchors, 0);
  EXPECT_LT(s.tool_state(0).force.y(), -0.01) << "lifted off, the anchored skin pulls the tool down: " << s.tool_state(0).force.transpose();
}

TEST_F(ToolSession, TheResultFileHoldsEveryToolsFramesAndItsGraspEvents) {
  // A gripper closing 2 mm above the top grasps the skin; its frames in the
  // result (pose, closure, force, torque) are what the session reported at
  // each recorded step, and the grasp is among the file's events.
  SceneSession s(read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 0.3, gravity: [0, 0, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: gripper
    keyframes:
      - {time: 0.0, position: [0.0, 0.032, 0.0], closure: 1.0}
      - {time: 0.2, position: [0.0, 0.032, 0.0], closure: 0.0}
      - {time: 0.3, position: [0.0, 0.036, 0.0], closure: 0.0}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.01}]
      hardness: 2000
)")),
                 quiet());
  SimulationResult r = s.result_header();
  ASSERT_EQ(r.tools.size(), 1u);
  EXPECT_EQ(r.tools[0].name, "gripper");
  std::vector<SceneToolState> recorded;
  while (s.steps_done() < s.total_steps()) {
    s.advance();
    if (s.steps_done() % 15 == 0) {
      s.record_frame(r, 0.0);
      recorded.push_back(s.tool_state(0));
    }
  }
  ASSERT_FALSE(s.tool_events().empty());
  const std::string path = (dir_ / "result.h5").string();
  write_simulation_result(r, path);
  const SimulationResult b = read_simulation_result(path);
  ASSERT_EQ(b.tools.size(), 1u);
  ASSERT_EQ(b.tools[0].frames.size(), recorded.size());
  bool pulled = false;
  for (size_t f = 0; f < recorded.size(); ++f) {
    const ToolFrame& g = b.tools[0].frames[f];
    EXPECT_LT((g.pose.matrix() - recorded[f].pose.matrix()).norm(), 1e-14) << f;
    EXPECT_EQ(g.closure, recorded[f].device.closure) << f;
    EXPECT_EQ(g.force, recorded[f].force) << f;
    EXPECT_EQ(g.torque, recorded[f].torque) << f;
    pulled = pulled || g.force.norm() > 0;
  }
  EXPECT_TRUE(pulled) << "the grasped skin pulls on the tool";
  ASSERT_EQ(b.tool_events.size(), s.tool_events().size());
  EXPECT_EQ(b.tool_events[0].tool, "gripper");
  EXPECT_EQ(b.tool_events[0].body, "base");
  EXPECT_EQ(b.tool_events[0].kind, "grasp");
  EXPECT_EQ(b.tool_events[0].time, s.tool_events()[0].time);
  EXPECT_GT(b.tool_events[0].points, 0);
}
