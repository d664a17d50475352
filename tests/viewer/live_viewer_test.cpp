// LiveViewer's controls over the WebSocket protocol, on a SceneSession of the
// small box avatar: the stiffness slider's message reaches the session's
// stiffness scale, reset sends it back to step 0 (unless the run writes files
// along its time line), pause holds the state, a step while paused is
// exactly one solver step, and every tool's force and every contact reach the page.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <nlohmann/json.hpp>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/live_run.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/viewer/live_viewer.hpp"
#include "sflsh/viewer/web_assets.hpp"
#include "viewer_test_support.hpp"

namespace sflsh::viewer {
namespace {

using LiveControls = sflsh::test::BoxAvatarScene;

const char* kProbeScene = R"(
solver: {dt: 1/250, seconds: 10}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    keyframes: [{time: 0.0, position: [0.0, 0.045, 0.0]}]
)";

SceneSessionOptions quiet_session() {
  SceneSessionOptions o;
  o.progress = false;
  return o;
}

ViewerServerOptions quiet_server() {
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  return o;
}

/// Calls before_frame until `done()` or 30 s pass (controls arrive on the server's thread; a guard against a hang).
template <class Done>
bool frames_until(LiveRunHooks& hooks, SceneSession& s, Done done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < end) {
    hooks.before_frame(s);
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return false;
}

/// The info JSON of the next frame message the client reads.
nlohmann::json next_info(test::Client& c, const ViewerScene& scene, QuantizedSkin* state) {
  bool text = true;
  std::string m;
  while (text) m = c.read(&text);
  return nlohmann::json::parse(decode_frame(m, scene, state).info);
}

}  // namespace

TEST_F(LiveControls, StiffnessAndResetReachTheSession) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  SceneSession s(read_scene_description(write_scene(kProbeScene)), quiet_session());
  LiveViewer v(s, quiet_server(), "box");
  LiveRunHooks hooks;
  v.install(hooks);
  test::Client c(v.server().port());
  bool text = false;
  EXPECT_EQ(nlohmann::json::parse(c.read(&text))["can_reset"], true);
  for (int i = 0; i < 20; ++i) s.advance();
  // The frame's skin is the session's (its cached pose offsets included), twice: computed, then reused.
  for (int k = 0; k < 2; ++k) {
    const ViewerFrame f = v.frame(LiveRunStatus{});
    EXPECT_EQ(Points(f.positions), s.body_surface(0));
    EXPECT_EQ(VecX(f.displacement), VecX(s.body_displacement(0).rowwise().norm()));
    s.advance();
  }
  c.send(R"({"type":"stiffness","seq":1,"scale":2.5})");
  ASSERT_TRUE(frames_until(hooks, s, [&] { return s.stiffness_scale(0) == 2.5; }));
  c.send(R"({"type":"stiffness","seq":2,"scale":25})");  // out of range: rejected by the parser
  c.send(R"({"type":"reset","seq":3})");
  ASSERT_TRUE(frames_until(hooks, s, [&] { return s.steps_done() == 0; }));
  EXPECT_EQ(s.time(), 0.0);
  EXPECT_EQ(s.stiffness_scale(0), 2.5);  // kept by the reset
  // The page sees both in the next frame's info.
  v.server().publish(v.frame(LiveRunStatus{}));
  QuantizedSkin state;
  const nlohmann::json info = next_info(c, v.server().scene(), &state);
  EXPECT_EQ(info["stiffness"], 2.5);
  EXPECT_EQ(info["resets"], 1);
  EXPECT_EQ(info["t"], 0.0);
  EXPECT_EQ(v.server().counters().controls_rejected, 1);
}

TEST_F(LiveControls, EveryToolsForceAndEveryContactReachThePage) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  // Two probes 5 mm into the box's top (y = 0.03), a third one far above it.
  SceneSession s(read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 10}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - {name: left, shape: {type: sphere, radius: 0.005}, keyframes: [{time: 0.0, position: [-0.015, 0.03, 0.0]}]}
  - {name: right, shape: {type: sphere, radius: 0.005}, keyframes: [{time: 0.0, position: [0.015, 0.03, 0.0]}]}
  - {name: away, shape: {type: sphere, radius: 0.005}, keyframes: [{time: 0.0, position: [0.0, 0.5, 0.0]}]}
)")),
                 quiet_session());
  LiveViewer v(s, quiet_server(), "box");
  test::Client c(v.server().port());
  const nlohmann::json scene = nlohmann::json::parse(c.read());
  ASSERT_EQ(scene["contacts"].size(), 3u);
  EXPECT_EQ(scene["contacts"][1]["term"], "contact:right");
  for (int i = 0; i < 10; ++i) s.advance();
  v.server().publish(v.frame(LiveRunStatus{}));
  QuantizedSkin state;
  const nlohmann::json info = next_info(c, v.server().scene(), &state);
  ASSERT_EQ(info["tools"].size(), 3u);
  ASSERT_EQ(info["contacts"].size(), 3u);
  for (int t = 0; t < 3; ++t) {
    const Vec3 tool(info["tools"][t]["force"][0], info["tools"][t]["force"][1], info["tools"][t]["force"][2]);
    const Vec3 contact(info["contacts"][t]["force"][0], info["contacts"][t]["force"][1], info["contacts"][t]["force"][2]);
    EXPECT_EQ(tool, s.tool_state(t).force) << "tool " << t;
    // A tool without anchors feels what its contact exerts on the body, reversed.
    EXPECT_LT((tool + contact).norm(), 1e-9 * (1 + tool.norm())) << "tool " << t;
    if (t < 2) {  // pressed in: in contact, with a force
      EXPECT_GT(info["contacts"][t]["active"].get<int>(), 0) << "tool " << t;
      EXPECT_GT(contact.norm(), 0.0) << "tool " << t;
    }
  }
  EXPECT_EQ(info["contacts"][2]["force"][1], 0.0);  // "away" touches nothing
  EXPECT_GT(double(info["contacts"][1]["point"][0]), 0.005);  // "right" acts right of the centre
}

TEST_F(LiveControls, ResetIsIgnoredWhenTheRunWritesAlongItsTimeLine) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  SceneSession s(read_scene_description(write_scene(kProbeScene)), quiet_session());
  LiveViewer v(s, quiet_server(), "box", /*allow_reset=*/false);
  LiveRunHooks hooks;
  v.install(hooks);
  test::Client c(v.server().port());
  bool text = false;
  EXPECT_EQ(nlohmann::json::parse(c.read(&text))["can_reset"], false);
  for (int i = 0; i < 5; ++i) s.advance();
  c.send(R"({"type":"reset","seq":1})");
  c.send(R"({"type":"stiffness","seq":2,"scale":0.5})");
  ASSERT_TRUE(frames_until(hooks, s, [&] { return s.stiffness_scale(0) == 0.5; }));
  EXPECT_EQ(s.steps_done(), 5);
  EXPECT_NE(v.summary().find("controls 1 applied, 1 ignored"), std::string::npos) << v.summary();
}

TEST_F(LiveControls, PauseHoldsAndStepTakesExactlyOneSolverStep) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  SceneSession s(read_scene_description(write_scene(kProbeScene)), quiet_session());
  LiveViewer v(s, quiet_server(), "box");
  LiveRunHooks hooks;
  long after_step_calls = 0;
  hooks.after_step = [&](const SceneSession&, const StepReport&) { ++after_step_calls; };
  v.install(hooks);
  test::Client c(v.server().port());
  bool text = false;
  c.read(&text);  // the scene
  for (int i = 0; i < 3; ++i) s.advance();
  c.send(R"({"type":"pause","seq":1,"paused":true})");
  // The run's frames on another thread: before_frame holds there while paused;
  // this thread is the page that steps and resumes.
  std::atomic<bool> stop{false};
  std::thread frames([&] {
    while (!stop) {
      hooks.before_frame(s);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  QuantizedSkin state;
  nlohmann::json info;
  do info = next_info(c, v.server().scene(), &state);
  while (info["paused"] != true);
  const double t0 = info["t"];
  EXPECT_NEAR(t0, 3 * s.dt(), 1e-12);
  c.send(R"({"type":"step","seq":2})");
  do info = next_info(c, v.server().scene(), &state);
  while (info["seq"] != 2);
  // One step of dt = 1/250 s (not a real-time frame's catch-up substeps).
  EXPECT_NEAR(double(info["t"]) - t0, 1.0 / 250, 1e-12);
  c.send(R"({"type":"pause","seq":3,"paused":false})");
  stop = true;  // the frame thread leaves its paused loop when the resume arrives
  frames.join();
  EXPECT_EQ(s.steps_done(), 4);
  EXPECT_EQ(after_step_calls, 1);  // the run's after_step hook saw the paused step
}

}  // namespace sflsh::viewer
