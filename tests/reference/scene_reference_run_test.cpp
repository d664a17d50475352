// `simulate scene.yaml --solver full`: the full-FEM reference driven by the
// scene session's inputs, on the small box avatar (6 cm, top at y = 0.03 m).
#include "sflsh/reference/scene_reference_run.hpp"

#include <gtest/gtest.h>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using SceneReference = test::BoxAvatarScene;

/// A 1 cm ball lowered from 1.5 cm above the top to 5 mm into it by 0.2 s, then held;
/// `as` is "objects" (a kinematic object), "tools" (a kinematic tool) or
/// "coupled" (a tool pulled along that path by a virtual coupling).
std::string ball_scene(const std::string& as) {
  const std::string ball = as == "objects" ? R"(objects:
  - name: ball
    shape: {type: sphere, radius: 0.01}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.2, position: [0.0, 0.035, 0.0]}
)"
                                           : R"(tools:
  - name: ball
    shape: {type: sphere, radius: 0.01}
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.2, position: [0.0, 0.035, 0.0]}
)" + std::string(as == "coupled" ? "    coupling: {stiffness: 2000, mass: 0.05}\n" : "");
  return R"(solver: {dt: 1/100, seconds: 0.3, gravity: [0, 0, 0]}
contact: {friction: 0}
output: {fps: 20}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
)" + ball;
}

SceneReferenceOptions quiet() {
  SceneReferenceOptions o;
  o.progress = false;
  return o;
}

/// The lowest skin point's depth below the top (m) in the last frame, within 5 mm of the axis.
double dent(const SimulationResult& r) {
  double lowest = 0.03;
  const Points& x = r.frame_positions.back();
  for (int v = 0; v < x.rows(); ++v)
    if (std::hypot(x(v, 0), x(v, 2)) < 0.005 && x(v, 1) > 0.02) lowest = std::min(lowest, x(v, 1));
  return 0.03 - lowest;
}

}  // namespace

TEST_F(SceneReference, TheFullFemDentsUnderAKinematicBallAndPushesItUp) {
  const SceneDescription sc = read_scene_description(write_scene(ball_scene("objects")));
  SceneContactStats st;
  const SimulationResult full = run_scene_reference(sc, quiet(), &st);
  ASSERT_EQ(full.num_frames, 7);  // t = 0, 0.05, ..., 0.3
  ASSERT_EQ(st.pairs.size(), 1u);
  EXPECT_EQ(st.pairs[0].term, "contact:ball");
  EXPECT_EQ(st.pairs[0].body, "base");
  // The ball is 5 mm into the undeformed top: the flesh gives way under it
  // (a dent of millimetres), so the penalty's own penetration is smaller than
  // 5 mm, and the obstacle presses the body down (the force on the body).
  const double d = dent(full);
  EXPECT_GT(d, 2e-3) << "dent " << d;
  EXPECT_LT(d, 5.5e-3) << "dent " << d;
  EXPECT_LT(st.pairs[0].max_penetration, 5e-3 - 0.5 * d);
  EXPECT_LT(st.pairs[0].last_force.y(), -0.05) << st.pairs[0].last_force.transpose();
  // Mostly vertical (the 1 cm cells' facets under the ball are not symmetric about its axis).
  EXPECT_LT(std::hypot(st.pairs[0].last_force.x(), st.pairs[0].last_force.z()), 0.2 * -st.pairs[0].last_force.y());
  // The ball's frames follow its keyframes (held at y = 0.035 after 0.2 s).
  ASSERT_EQ(full.objects.size(), 1u);
  EXPECT_NEAR(full.objects[0].poses.back().translation().y(), 0.035, 1e-12);
  // The result's contact is the reference's (its last frame is the last step), drawn at the ball.
  ASSERT_EQ(full.contacts.size(), 1u);
  EXPECT_EQ(full.contacts[0].term, "contact:ball");
  ASSERT_EQ(full.contacts[0].frames.size(), 7u);
  EXPECT_EQ(full.contacts[0].frames.back().force, st.pairs[0].last_force);
  EXPECT_GT(full.contacts[0].frames.back().max_penetration, 0.0);
  EXPECT_LE(full.contacts[0].frames.back().max_penetration, st.pairs[0].max_penetration);
  EXPECT_NEAR(full.contacts[0].frames.back().point.y(), 0.035, 1e-12);
}

TEST_F(SceneReference, ABallAsAToolGivesTheSameReferenceAsTheSameBallAsAnObject) {
  // Three paths to the same obstacle pose (object keyframes, tool track, a
  // coupled tool's device track): any mix-up of poses or fields in one shows.
  SceneContactStats a, b, c;
  const SimulationResult ra = run_scene_reference(read_scene_description(write_scene(ball_scene("objects"))), quiet(), &a);
  const SimulationResult rb = run_scene_reference(read_scene_description(write_scene(ball_scene("tools"))), quiet(), &b);
  {
    // The coupled tool moves along its device's path (the coupling runs as kinematic), with a warning.
    ::testing::internal::CaptureStderr();
    const SimulationResult rc =
        run_scene_reference(read_scene_description(write_scene(ball_scene("coupled"))), quiet(), &c);
    const std::string warning = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(warning.find("tools 'ball'"), std::string::npos) << warning;
    EXPECT_NE(warning.find("device's path"), std::string::npos) << warning;
    EXPECT_EQ(rc.frame_positions.back(), rb.frame_positions.back());
    EXPECT_EQ(c.pairs.at(0).last_force, b.pairs.at(0).last_force);
  }
  ASSERT_EQ(ra.num_frames, rb.num_frames);
  EXPECT_EQ(ra.frame_positions.back(), rb.frame_positions.back());
  EXPECT_EQ(a.pairs.at(0).last_force, b.pairs.at(0).last_force);
  // The tool's frames carry the reference's reaction on it: the opposite of its contact force on the body.
  ASSERT_EQ(rb.tools.size(), 1u);
  EXPECT_EQ(rb.tools[0].frames.back().force, Vec3(-b.pairs.at(0).last_force));
  EXPECT_GT(b.pairs.at(0).last_force.norm(), 0.05);
  EXPECT_GT(a.pairs.at(0).max_force, 0.05);
}

// A kinematic tool with a grasp sensor above the top closes at 0.05 s, lifts
// 3 mm by 0.15 s, holds, and opens at 0.25 s. The reference grasps its own
// skin by the reduced run's rule: the same events at the same times (the
// same points: the sensor hits the same face), the anchored skin rises with
// the tool, the body pulls the tool down while it holds (the same direction
// and scale as the reduced run's force on the box's 6-handle basis), and
// nothing after the release.
TEST_F(SceneReference, AToolGraspsTheReferencesSkinLiftsItAndLetsGo) {
  const SceneDescription sc = read_scene_description(write_scene(test::kBoxPinchScene));
  std::vector<Vec3> force_full;
  SceneReferenceOptions o = quiet();
  o.on_step = [&](const SceneReferenceStep& s) {
    ASSERT_EQ(s.tool_forces->size(), 1u);
    force_full.push_back(s.tool_forces->at(0));
  };
  const SimulationResult full = run_scene_reference(sc, o);
  std::vector<Vec3> force_reduced;
  SceneSessionOptions so;
  so.progress = false;
  SceneSession reduced(sc, so);
  while (reduced.steps_done() < reduced.total_steps()) {
    reduced.advance();
    force_reduced.push_back(reduced.tool_state(0).force);
  }
  ASSERT_EQ(force_full.size(), 30u);
  ASSERT_EQ(force_reduced.size(), 30u);
  const std::vector<ToolEvent>& ev = reduced.tool_events();
  ASSERT_EQ(full.tool_events.size(), 2u);
  ASSERT_EQ(ev.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(full.tool_events[i].kind, i == 0 ? "grasp" : "release");
    EXPECT_EQ(full.tool_events[i].kind, ev[i].kind);
    EXPECT_NEAR(full.tool_events[i].time, ev[i].time, 1e-12);
    EXPECT_EQ(full.tool_events[i].points, ev[i].points);
    EXPECT_GT(full.tool_events[i].points, 0);
  }
  // Held and lifted (t = 0.2 s, step 20): the body pulls the tool down, as in the reduced run.
  const Vec3 f = force_full[19], fr = force_reduced[19];
  EXPECT_LT(f.y(), -0.2) << f.transpose();
  EXPECT_LT(std::hypot(f.x(), f.z()), 0.2 * -f.y()) << f.transpose();
  EXPECT_GT(f.y() / fr.y(), 0.3) << f.transpose() << " vs reduced " << fr.transpose();
  EXPECT_LT(f.y() / fr.y(), 1.5) << f.transpose() << " vs reduced " << fr.transpose();
  // The result's tool frames carry the reference's force; after the release, none.
  ASSERT_EQ(full.tools.size(), 1u);
  EXPECT_EQ(full.tools[0].frames[4].force, force_full[19]);  // frame 4: t = 0.2 s
  EXPECT_EQ(force_full.back(), Vec3::Zero());
  // The skin under the tool rose with it (the top is at y = 0.03).
  double highest = 0;
  for (int v = 0; v < full.frame_positions[4].rows(); ++v) highest = std::max(highest, full.frame_positions[4](v, 1));
  EXPECT_GT(highest, 0.0315);
}

TEST_F(SceneReference, ScenesItCannotRunAreRefusedNamingTheItem) {
  const std::string head = "solver: {dt: 1/100, seconds: 0.1}\nbodies:\n  - {name: base, avatar: box.h5}\n";
  auto refused = [&](const std::string& text, std::initializer_list<std::string> fragments) {
    const SceneDescription sc = read_scene_description(write_scene(text));
    test::expect_error([&] { run_scene_reference(sc, quiet()); }, fragments);
  };
  refused(head + "  - {name: other, avatar: box.h5, placement: {offset: [0.2, 0, 0]}}\n", {"scene.yaml", "one body", "has 2"});
  refused(head + "objects:\n  - {name: rock, shape: {type: sphere, radius: 0.01}, kind: dynamic, density: 1000, "
                 "position: [0, 0.1, 0]}\n",
          {"scene.yaml", "objects 'rock'", "dynamic"});
  refused(head + "tools:\n  - name: probe\n    shape: {type: sphere, radius: 0.005}\n"
                 "    pose_stream: {port: 7001}\n    coupling: {stiffness: 2000}\n",
          {"scene.yaml", "tools 'probe'", "live stream"});
  refused(head + "tools:\n  - name: pincer\n    keyframes: [{time: 0, position: [0, 0.1, 0]}]\n    gripper:\n"
                 "      hinge: {origin: [0, 0.03, 0], axis: [1, 0, 0]}\n      jaws:\n"
                 "        - {shape: {type: capsule, radius: 0.003, length: 0.02}, offset: [0, 0.01, 0.004], side: 1}\n",
          {"scene.yaml", "tools 'pincer'", "jaws"});
}
