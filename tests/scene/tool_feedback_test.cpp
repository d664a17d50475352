// What a tool feels in a scene with several tools and an object: the force on
// each tool is minus the sum of the forces of exactly the terms acting on it
// (its shape's and jaws' contact and its anchors; found here from the terms'
// names, independently of the compiled scene's term handles), a coupled
// tool's device feels its coupling, and each tool's anchors hold the skin
// under that tool (its own pose reaches its own anchor term). Some tools'
// names start like another tool's terms' names ("left/jaw0" like the jaws of
// "left", "grip_a@b" like the anchors of "grip_a"): matching term names by
// prefix would give one tool another's forces.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"

using namespace sflsh;

namespace {

using ToolFeedback = test::BoxAvatarScene;

/// On the 6 cm box (top at y = 0.03, skin vertices every 1 cm): two probes
/// pressing 2 mm in, two grippers grasping the skin under them and lifting
/// it, a coupled probe whose device is 1 mm in, and a static ball 2 mm in
/// (felt by no tool), each over a skin vertex.
const char* kScene = R"(
solver: {dt: 1/250, seconds: 0.3, gravity: [0, 0, 0]}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - {name: ball, shape: {type: sphere, radius: 0.005}, position: [0.02, 0.033, 0.02]}
tools:
  - name: left
    shape: {type: sphere, radius: 0.005}
    keyframes: [{time: 0, position: [-0.02, 0.033, -0.02]}]
  - name: left/jaw0
    shape: {type: sphere, radius: 0.005}
    keyframes: [{time: 0, position: [0.02, 0.033, -0.02]}]
  - name: pusher
    shape: {type: sphere, radius: 0.005}
    keyframes: [{time: 0, position: [-0.02, 0.034, 0.02]}]
    coupling: {stiffness: 2000, mass: 0.05, max_force: 1000, haptic_gain: 1}
  - name: grip_a
    keyframes:
      - {time: 0.0, position: [-0.02, 0.032, 0.0], closure: 1.0}
      - {time: 0.2, position: [-0.02, 0.032, 0.0], closure: 0.0}
      - {time: 0.3, position: [-0.02, 0.036, 0.0], closure: 0.0}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.01}]
      hardness: 2000
  - name: grip_a@b
    keyframes:
      - {time: 0.0, position: [0.02, 0.032, 0.0], closure: 1.0}
      - {time: 0.2, position: [0.02, 0.032, 0.0], closure: 0.0}
      - {time: 0.3, position: [0.02, 0.036, 0.0], closure: 0.0}
    grasp:
      sensors: [{origin: [0, 0, 0], direction: [0, -1, 0], range: 0.01}]
      hardness: 2000
)";

Vec3 vec3(const std::vector<double>& v) { return Vec3(v.at(0), v.at(1), v.at(2)); }

/// The names of the terms acting on tool `d` (its shape's and jaws' contact
/// with every body, its anchors on every body), spelled out from the scene.
std::set<std::string> terms_on(const ToolDescription& d, const SceneDescription& sc) {
  std::set<std::string> names;
  if (d.has_shape) names.insert("contact:" + d.name);
  for (size_t j = 0; j < d.jaws.size(); ++j) names.insert("contact:" + d.name + "/jaw" + std::to_string(j));
  if (!d.sensors.empty())
    for (const BodyDescription& b : sc.bodies) names.insert("anchor:" + d.name + "@" + b.name);
  return names;
}

}  // namespace

TEST_F(ToolFeedback, EachToolFeelsExactlyTheTermsActingOnIt) {
  const SceneDescription sc = read_scene_description(write_scene(kScene));
  SceneSessionOptions o;
  o.progress = false;
  SceneSession s(sc, o);
  ASSERT_EQ(s.num_tools(), 5);
  std::map<std::string, bool> felt;
  bool ball_pushed = false;
  while (s.steps_done() < s.total_steps()) {
    const StepReport& rep = s.advance();
    for (int i = 0; i < s.num_tools(); ++i) {
      const ToolDescription& d = sc.tools[size_t(i)];
      const std::set<std::string> mine = terms_on(d, sc);
      Vec3 force = Vec3::Zero(), coupling = Vec3::Zero();
      int anchors = 0;
      for (const TermQuantityReport& q : rep.quantities) {
        if (mine.count(q.term) && q.name == "force") force -= vec3(q.value);
        if (mine.count(q.term) && q.name == "anchor_points") anchors += int(q.value.size());
        if (q.term == "coupling:" + d.name && q.name == "force") coupling = vec3(q.value);
      }
      const SceneToolState& ts = s.tool_state(i);
      EXPECT_LT((ts.force - force).norm(), 1e-12 * (1 + force.norm())) << d.name << " at step " << s.steps_done();
      EXPECT_EQ(ts.anchors, anchors) << d.name;
      if (d.coupled) {
        EXPECT_LT((ts.feedback_force + coupling).norm(), 1e-12 * (1 + coupling.norm())) << d.name;
      }
      felt[d.name] = felt[d.name] || force.norm() > 1e-3;
    }
    for (const TermQuantityReport& q : rep.quantities)
      ball_pushed = ball_pushed || (q.term == "contact:ball" && q.name == "force" && vec3(q.value).norm() > 1e-3);
  }
  // Every tool and the ball touched the flesh: each sum above left out real forces.
  for (const ToolDescription& d : sc.tools) EXPECT_TRUE(felt[d.name]) << d.name << " felt nothing";
  EXPECT_TRUE(ball_pushed);
}

TEST_F(ToolFeedback, EachGrippersAnchorsHoldTheSkinUnderThatGripper) {
  const SceneDescription sc = read_scene_description(write_scene(kScene));
  SceneSessionOptions o;
  o.progress = false;
  SceneSession s(sc, o);
  while (s.steps_done() < s.total_steps()) s.advance();
  const Points skin = s.simulator().posed_surface(0);
  for (const std::string tool : {"grip_a", "grip_a@b"}) {
    const int i = s.tool_index(tool);
    const Vec3 at = s.tool_state(i).pose.translation();
    ASSERT_GT(s.tool_state(i).anchors, 0) << tool;
    const TermQuantityReport* points = nullptr;
    const TermQuantityReport* forces = nullptr;
    for (const TermQuantityReport& q : s.last_report().quantities) {
      if (q.term != "anchor:" + tool + "@base") continue;
      if (q.name == "anchor_points") points = &q;
      if (q.name == "anchor_forces") forces = &q;
    }
    ASSERT_TRUE(points && forces) << tool;
    for (size_t k = 0; k < points->value.size(); ++k) {
      // The anchored skin is under this gripper (1 cm cells), 4 cm from the other one...
      const Vec3 x = skin.row(Eigen::Index(points->value[k])).transpose();
      EXPECT_LT(std::hypot(x.x() - at.x(), x.z() - at.z()), 0.015) << tool << " holds " << x.transpose();
      // ... and pulled up by this gripper's lift.
      EXPECT_GT(forces->value.at(3 * k + 1), 0.0) << tool;
    }
  }
}
