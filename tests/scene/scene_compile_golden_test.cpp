// Golden results of compiling the example scenes (apps/scenes/*.yaml and
// apps/scenes/figures/*.yaml) into a session: the Model's term list (names,
// order, bound bodies), its DoF layout, and the State after the first step and
// after a few more, pinned bit for bit (a hash of every double of the state and
// of the tools' states). A refactor of how a scene is built or stepped must
// reproduce them exactly.
//
// Each scene is run on the small box avatar of box_avatar_fixture.hpp instead
// of the built-in body (`avatar: default`), its body moved where the scene's
// objects and tools meet the belly so that contact and grasping happen within
// the steps taken; live streams stay closed.
//
// To re-record after an intended change of the physics (never for a refactor):
//   SFLSH_PRINT_GOLDEN=1 build/test_scene --gtest_filter='SceneCompileGolden.*'
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using test::BitHash;

/// A configuration: its bones (count, then each transform) and z.
void add(BitHash& h, const Configuration& q) {
  h.add(int(q.bones.size()));
  for (const Isometry& G : q.bones) h.add(G);
  h.add(q.z);
}

/// The model's terms in order: "name@body,body" separated by "; ".
std::string term_list(const Model& m) {
  std::string s;
  for (const Model::BoundTerm& t : m.terms()) {
    s += (s.empty() ? "" : "; ") + t.term->name() + "@";
    for (size_t i = 0; i < t.bodies.size(); ++i) s += (i ? "," : "") + std::to_string(t.bodies[i]);
  }
  return s;
}

/// The DoF layout: per body "name:dynamic/bones/reduced@base", then the total.
std::string dof_layout(const Model& m) {
  std::ostringstream s;
  for (const Model::Body& b : m.bodies())
    s << b.name << ":" << b.layout.bones_dynamic << "/" << b.layout.num_bones << "/" << b.layout.num_reduced << "@"
      << b.layout.base << " ";
  s << "dofs " << m.num_dofs() << " blocks " << m.blocks().size() << " groups " << m.groups().size();
  return s.str();
}

std::string state_hash(const SceneSession& s) {
  BitHash h;
  const State& st = s.simulator().scene_state();
  h.add(st.time);
  for (const BodyState& b : st.bodies) {
    add(h, b.q);
    add(h, b.q_prev);
  }
  return h.hex();
}

std::string tools_hash(const SceneSession& s) {
  BitHash h;
  for (int i = 0; i < s.num_tools(); ++i) {
    const SceneToolState& t = s.tool_state(i);
    h.add(t.pose);
    h.add(t.force);
    h.add(t.torque);
    h.add(t.feedback_force);
    h.add(t.feedback_torque);
    h.add(t.anchors);
    h.add(t.max_stretch);
    h.add(t.device.position);
    h.add(t.device.closure);
  }
  for (const Isometry& T : s.object_poses()) h.add(T);
  for (const SceneToolEvent& e : s.tool_events()) {
    h.add(e.time);
    h.add(e.points);
  }
  return h.hex();
}

struct Golden {
  std::string terms, layout, first_step, last_step, tools;
  int events = 0;
};

struct ExampleScene {
  const char* file;  ///< under apps/scenes, or (starting with '\n') the scene's text

  /// Moves the box avatar where the scene's objects and tools act.
  std::function<void(SceneDescription&)> place;
  long steps;
  Golden golden;
  /// Called after the first step (e.g. to change the stiffness scale).
  std::function<void(SceneSession&)> after_first_step = nullptr;
};

/// The box's front face (z = +0.03 m in its frame) at z = 0.11 m with the
/// height y = 1.05 m inside it: where the example scenes' belly is.
void at_belly(SceneDescription& s) { s.bodies[0].offset = Vec3(0, 1.035, 0.08); }

class SceneCompileGolden : public test::BoxAvatarScene {
 protected:
  void check(const ExampleScene& ex) {
    const bool inline_text = ex.file[0] == '\n';
    SceneDescription sc = read_scene_description(inline_text ? write_scene(ex.file)
                                                             : test::source_dir() + "/apps/scenes/" + ex.file);
    for (BodyDescription& b : sc.bodies) {
      b.avatar = (dir_ / "box.h5").string();
      b.default_avatar = false;
    }
    if (ex.place) ex.place(sc);
    const std::string label = inline_text ? ::testing::UnitTest::GetInstance()->current_test_info()->name() : ex.file;
    SceneSessionOptions o;
    o.progress = false;
    o.open_streams = false;
    SceneSession s(sc, o);
    Golden got;
    got.terms = term_list(s.simulator().model());
    got.layout = dof_layout(s.simulator().model());
    s.advance();
    got.first_step = state_hash(s);
    if (ex.after_first_step) ex.after_first_step(s);
    while (s.steps_done() < ex.steps) s.advance();
    got.last_step = state_hash(s);
    got.tools = tools_hash(s);
    got.events = int(s.tool_events().size());
    if (std::getenv("SFLSH_PRINT_GOLDEN")) {
      std::printf("%s:\n  {\"%s\",\n   \"%s\",\n   \"%s\", \"%s\", \"%s\", %d}\n", label.c_str(), got.terms.c_str(),
                  got.layout.c_str(), got.first_step.c_str(), got.last_step.c_str(), got.tools.c_str(), got.events);
      return;
    }
    EXPECT_EQ(got.terms, ex.golden.terms) << label;
    EXPECT_EQ(got.layout, ex.golden.layout) << label;
    EXPECT_EQ(got.first_step, ex.golden.first_step) << label << ": the state after one step";
    EXPECT_EQ(got.last_step, ex.golden.last_step) << label << ": the state after " << ex.steps << " steps";
    EXPECT_EQ(got.tools, ex.golden.tools) << label << ": the tools' states";
    EXPECT_EQ(got.events, ex.golden.events) << label << ": grasp and release events";
  }
};

}  // namespace

TEST_F(SceneCompileGolden, BallAtBelly) {
  check({"ball_at_belly.yaml", at_belly, 20,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; bone_gravity@1; contact:ball@0,1",
          "alice:0/24/18@0 ball:1/1/0@18 dofs 24 blocks 2 groups 1",
          "68ed6ec61abdbba7", "ea08165d5345babe", "56766bd87a663ba2", 0}});
}

// Re-pinned when the scene came to hold the rest pose and use the contact patch.
TEST_F(SceneCompileGolden, BoxPress) {
  check({"box_press.yaml", at_belly, 90,
         {"inertia@0; elastic@0; gravity@0; contact:press@0",
          "alice:0/24/18@0 dofs 18 blocks 1 groups 1",
          "792ef903953b7ef5", "791e438f130e95e2", "602916d977821fb4", 0}});
}

TEST_F(SceneCompileGolden, FallOnFloor) {
  check({"fall_on_floor.yaml", nullptr, 25,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@0; bone_gravity@0; joint_constraint@0; joint_limit@0; tracking@0; contact:floor@0; self_contact@0",
          "alice:1/24/18@0 dofs 162 blocks 25 groups 1",
          "d15e96574e431472", "0dc3b3af81ecd280", "176d968e934f1089", 0}});
}

TEST_F(SceneCompileGolden, PinchBelly) {
  check({"pinch_belly.yaml", at_belly, 40,
         {"inertia@0; elastic@0; gravity@0; anchor:gripper@alice@0",
          "alice:0/24/18@0 dofs 18 blocks 1 groups 1",
          "792ef903953b7ef5", "542c6c2162f1e9f4", "1d79ae60ea801307", 1}});
}

TEST_F(SceneCompileGolden, TeleopPinch) {
  check({"teleop_pinch.yaml", at_belly, 5,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; coupling:gripper@1; anchor:gripper@alice@0,1",
          "alice:0/24/18@0 gripper:1/1/0@18 dofs 24 blocks 2 groups 1",
          "475744638fd3888d", "29678b6fc97123f1", "fabcba68b78a16da", 0}});
}

// Two bodies meet skin against skin (skin_contact@0,1) with the bone
// capsules as cores (body_contact@0,1): the states re-pinned when that became
// the default body-body contact (an intended change of the physics), and
// when a closest point on an edge of the box bodies came to take its side from
// every face there (skin_contact.cpp, closest_skin_point), not one face's.
TEST_F(SceneCompileGolden, TwoWalkers) {
  auto closer = [](SceneDescription& s) {
    s.bodies[0].offset.z() = -0.04;
    s.bodies[1].offset.z() = 0.04;
  };
  check({"two_walkers.yaml", closer, 6,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@0; bone_gravity@0; joint_constraint@0; joint_limit@0; tracking@0; inertia@1; elastic@1; gravity@1; bone_inertia@1; bone_gravity@1; joint_constraint@1; joint_limit@1; tracking@1; skin_contact@0,1; body_contact@0,1",
          "alice:1/24/18@0 bob:1/24/18@162 dofs 324 blocks 50 groups 1",
          "55315353cb598496", "65475380961d7298", "14650fb0739d0383", 0}});
}

TEST_F(SceneCompileGolden, MomentumBump) {
  auto closer = [](SceneDescription& s) {
    s.bodies[0].offset.z() = -0.04;
    s.bodies[1].offset.z() = 0.04;
  };
  check({"figures/momentum_bump.yaml", closer, 6,
         {"inertia@0; elastic@0; bone_inertia@0; bone_gravity@0; joint_constraint@0; joint_limit@0; tracking@0; inertia@1; elastic@1; bone_inertia@1; bone_gravity@1; joint_constraint@1; joint_limit@1; tracking@1; skin_contact@0,1; body_contact@0,1",
          "alice:1/24/18@0 bob:1/24/18@162 dofs 324 blocks 50 groups 1",
          "bb69675050e51204", "09e9f7343cfd680f", "14650fb0739d0383", 0}});
}

TEST_F(SceneCompileGolden, WalkerMeetsStander) {
  auto closer = [](SceneDescription& s) {
    s.bodies[0].offset.z() = -0.04;
    s.bodies[1].offset.z() = 0.04;
  };
  check({"figures/walker_meets_stander.yaml", closer, 6,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@0; bone_gravity@0; joint_constraint@0; joint_limit@0; tracking@0; inertia@1; elastic@1; gravity@1; bone_inertia@1; bone_gravity@1; joint_constraint@1; joint_limit@1; tracking@1; skin_contact@0,1; body_contact@0,1",
          "alice:1/24/18@0 bob:1/24/18@162 dofs 324 blocks 50 groups 1",
          "05c633c21398ea9f", "8b6d5cb8f0561b49", "14650fb0739d0383", 0}});
}

TEST_F(SceneCompileGolden, WalkerMeetsStanderWithCapsules) {
  auto closer = [](SceneDescription& s) {
    s.bodies[0].offset.z() = -0.04;
    s.bodies[1].offset.z() = 0.04;
  };
  check({"figures/walker_meets_stander_capsules.yaml", closer, 6,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@0; bone_gravity@0; joint_constraint@0; joint_limit@0; tracking@0; inertia@1; elastic@1; gravity@1; bone_inertia@1; bone_gravity@1; joint_constraint@1; joint_limit@1; tracking@1; body_contact@0,1",
          "alice:1/24/18@0 bob:1/24/18@162 dofs 324 blocks 50 groups 1",
          "05c633c21398ea9f", "aada448650dd38d2", "14650fb0739d0383", 0}});
}

TEST_F(SceneCompileGolden, PinchCoupled) {
  check({"figures/pinch_coupled.yaml", at_belly, 130,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; coupling:gripper@1; anchor:gripper@alice@0,1",
          "alice:0/24/18@0 gripper:1/1/0@18 dofs 24 blocks 2 groups 1",
          "aea730fe525068cc", "517abb0990f4b0df", "51800f1c0f956660", 1}});
}

TEST_F(SceneCompileGolden, PinchFromFile) {
  check({"figures/pinch_from_file.yaml", at_belly, 40,
         {"inertia@0; elastic@0; gravity@0; anchor:gripper@alice@0",
          "alice:0/24/18@0 dofs 18 blocks 1 groups 1",
          "792ef903953b7ef5", "542c6c2162f1e9f4", "1d79ae60ea801307", 1}});
}

TEST_F(SceneCompileGolden, SlabOnBelly) {
  check({"figures/slab_on_belly.yaml", [](SceneDescription& s) { s.bodies[0].offset = Vec3(0, 1.085, 0.08); }, 10,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; bone_gravity@1; contact:slab@0,1",
          "alice:0/24/18@0 slab:1/1/0@18 dofs 24 blocks 2 groups 1",
          "9795bcc04e365eb1", "4186a2a4550db76a", "7dca32eb0aabe095", 0}});
}

// The probe touches the box's front face at 0.1 s (step 6) and is 2 mm in at step 12.
TEST_F(SceneCompileGolden, ProbeBelly) {
  check({"figures/probe_belly.yaml", at_belly, 12,
         {"inertia@0; elastic@0; contact:probe@0", "alice:0/24/18@0 dofs 18 blocks 1 groups 1",
          "d48f112e19027b1d", "5734bb020626946e", "f5dc3864a7d12373", 0}});
}

// The box's back face touches the front face at 0.08 s (step 5) and is 6 mm in at step 20:
// a contact over the whole face, whose patch grows with it.
TEST_F(SceneCompileGolden, BoxPressBelly) {
  check({"figures/box_press_belly.yaml", at_belly, 20,
         {"inertia@0; elastic@0; contact:press@0", "alice:0/24/18@0 dofs 18 blocks 1 groups 1",
          "d48f112e19027b1d", "7b9a31c9560e13f2", "44b1bbdc96ed0aae", 0}});
}

TEST_F(SceneCompileGolden, SphereOnBelly) {
  check({"figures/sphere_on_belly.yaml", at_belly, 10,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; bone_gravity@1; contact:ball@0,1",
          "alice:0/24/18@0 ball:1/1/0@18 dofs 24 blocks 2 groups 1",
          "ad8d92391288d1b9", "ac4dbc1327e78a48", "86248d6cd23606eb", 0}});
}

TEST_F(SceneCompileGolden, YankBelly) {
  check({"figures/yank_belly.yaml", at_belly, 130,
         {"inertia@0; elastic@0; gravity@0; bone_inertia@1; coupling:gripper@1; anchor:gripper@alice@0,1",
          "alice:0/24/18@0 gripper:1/1/0@18 dofs 24 blocks 2 groups 1",
          "aea730fe525068cc", "8eeb242d76d659e9", "dec85dfb8506dbee", 1}});
}

// What the example scenes do not use: a tool with a shape, gripper jaws and
// grasp sensors; a kinematic object on keyframes; soft-tissue damping; a
// stiffness scale changed after the first step.
namespace {
const char* kGripperScene = R"(
solver: {dt: 1/250, seconds: 0.3, gravity: [0, 0, 0], damping: 0.01}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - name: press
    shape: {type: box, size: [0.01, 0.01, 0.01]}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [0.02, 0.04, 0.02]}
      - {time: 0.2, position: [0.02, 0.032, 0.02]}
tools:
  - name: gripper
    shape: {type: sphere, radius: 0.003}
    keyframes:
      - {time: 0.0, position: [0.0, 0.038, 0.0], closure: 1.0}
      - {time: 0.2, position: [0.0, 0.038, 0.0], closure: 0.0}
    gripper:
      hinge: {origin: [0, 0, 0], axis: [1, 0, 0]}
      jaws:
        - {shape: {type: capsule, radius: 0.002, length: 0.01}, offset: [0, -0.01, 0.004], side: 1}
        - {shape: {type: capsule, radius: 0.002, length: 0.01}, offset: [0, -0.01, -0.004], side: -1}
    grasp:
      sensors: [{origin: [0, -0.005, 0], direction: [0, -1, 0], range: 0.02}]
      hardness: 2000
)";

// The contact patch with a kinematic tool, a coupled tool (which keeps the
// per-sample penalty) and a static plane.
const char* kPatchScene = R"(
solver: {dt: 1/100, seconds: 0.2, gravity: [0, -9.81, 0]}
contact: {friction: 0, patch: {radius: 0.015}}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - {name: floor, shape: {type: plane, normal: [0, 1, 0]}, kind: static, position: [0, 0.001, 0]}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.01}
    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.2, position: [0.0, 0.036, 0.0]}
  - name: pusher
    shape: {type: sphere, radius: 0.005}
    keyframes:
      - {time: 0.0, position: [0.02, 0.04, 0.0]}
      - {time: 0.2, position: [0.02, 0.025, 0.0]}
    coupling: {stiffness: 2000, mass: 0.05, max_force: 100, haptic_gain: 0.5}
)";
}  // namespace

TEST_F(SceneCompileGolden, GripperWithJawsDampingAndStiffnessScale) {
  check({kGripperScene, nullptr, 60,
         {"inertia@0; elastic@0; damping@0; contact:press@0; contact:gripper@0; contact:gripper/jaw0@0; contact:gripper/jaw1@0; anchor:gripper@base@0",
          "base:0/24/18@0 dofs 18 blocks 1 groups 1",
          "b686aa9f2e3a707e", "6715e1e94e93e12b", "cc2447fd044ef622", 1},
         [](SceneSession& s) { s.set_stiffness_scale(2.0); }});
}

TEST_F(SceneCompileGolden, ContactPatchWithKinematicAndCoupledTools) {
  // A kinematic probe and a coupled pusher on the box, the probe's contact
  // ending within the steps (its patch released). Re-pinned only with a change
  // of the patch's physics (git log of this file says which).
  check({kPatchScene, nullptr, 20,
         {"inertia@0; elastic@0; gravity@0; contact:floor@0; contact:probe@0; bone_inertia@1; coupling:pusher@1; contact:pusher@0,1",
          "base:0/24/18@0 pusher:1/1/0@18 dofs 24 blocks 2 groups 1",
          "a7701bae56eddb01", "3070686220c09c2f", "0a3a4de3ef583044", 0}});
}

TEST_F(SceneCompileGolden, CoversEveryExampleScene) {
  int scenes = 0;
  for (const char* dir : {"apps/scenes", "apps/scenes/figures"})
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(test::source_dir()) / dir))
      scenes += e.path().extension() == ".yaml";
  EXPECT_EQ(scenes, 16) << "a new example scene: add it to SceneCompileGolden";
}
