// A coupled tool (a haptic device's tool: a rigid body pulled to the device by
// a virtual coupling) with contact.patch presses through the patch, as a
// kinematic tool does: at rest, the force on a coupled probe equals the force
// on a kinematic probe held where the coupled one came to rest, equals the
// coupling's pull (stiffness × the device's offset from the tool); and the
// coupled tool's jaws move on it through their moving shape frames.
#include <gtest/gtest.h>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_compiler.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"

namespace sflsh {
namespace {

class CoupledToolPatch : public test::BoxAvatarScene {
 protected:
  /// Runs `scene` to its end; returns the first tool's state.
  SceneToolState run(const std::string& scene) {
    SceneSessionOptions o;
    o.progress = false;
    o.open_streams = false;
    SceneSession s(read_scene_description(write_scene(scene)), o);
    while (s.steps_done() < s.total_steps()) s.advance();
    return s.tool_state(0);
  }
};

// The box's top is at y = 0.03; a 5 mm probe whose device is 2 mm into it,
// gravity off, 0.6 s at 1/200 s: the critically damped coupling (2000 N/m,
// 50 g) settles within ~0.1 s.
const char* kHeader = R"(solver: {dt: 1/200, seconds: 0.6, gravity: [0, 0, 0]}
contact: {patch: {radius: 0.015}}
bodies:
  - {name: base, avatar: box.h5, motion: none, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
)";

TEST_F(CoupledToolPatch, ACoupledProbePressesThroughThePatchWithTheKinematicProbesForce) {
  const std::string coupled = std::string(kHeader) +
                              "    keyframes: [{time: 0, position: [0.002, 0.033, 0.001]}]\n"
                              "    coupling: {stiffness: 2000, mass: 0.05, max_force: 100}\n";
  {
    const CompiledScene c = compile_scene(read_scene_description(write_scene(coupled)));
    EXPECT_EQ(c.model->find_term<SdfContactTerm>(0), nullptr) << "the coupled probe kept the per-sample penalty";
    ASSERT_NE(c.model->find_term<ContactPatchTerm>(0), nullptr);
  }
  const SceneToolState held = run(coupled);
  const Vec3 rest = held.pose.translation();
  // The coupling pulls the tool towards the device: its pull is what the flesh pushes back.
  const Vec3 pull = 2000.0 * (Vec3(0.002, 0.033, 0.001) - rest);
  ASSERT_GT(held.force.y(), 0.05) << "the probe does not touch";
  EXPECT_LT((held.force + pull).norm(), 0.01 * held.force.norm())
      << "force " << held.force.transpose() << ", coupling " << pull.transpose();
  // A kinematic probe held where the coupled one rests feels the same force.
  char at[160];
  std::snprintf(at, sizeof at, "    keyframes: [{time: 0, position: [%.17g, %.17g, %.17g]}]\n", rest.x(), rest.y(),
                rest.z());
  const SceneToolState kinematic = run(std::string(kHeader) + at);
  EXPECT_LT((kinematic.force - held.force).norm(), 0.02 * held.force.norm())
      << "kinematic " << kinematic.force.transpose() << ", coupled " << held.force.transpose();
}

TEST_F(CoupledToolPatch, ACoupledGrippersJawsPressThroughTheirOwnPatchesWhereTheyMove) {
  // Two 5 mm jaws 6 mm either side of a coupled gripper's origin, hinged 2 cm
  // above it about z; the device sits with the jaws 2 mm into the top. Closed
  // (closure 0) they press the skin; open (0.8 rad: ±0.4 each) they swing up
  // by 3.9 mm, out of reach, and feel nothing. (A jaw placed by the tool's
  // pose alone, its moving frame ignored, would press at the tool's origin
  // open or closed.)
  auto scene = [](double closure) {
    char text[1200];
    std::snprintf(text, sizeof text, R"(solver: {dt: 1/200, seconds: 0.4, gravity: [0, 0, 0]}
contact: {patch: {radius: 0.015}}
bodies:
  - {name: base, avatar: box.h5, motion: none, bones: kinematic}
tools:
  - name: gripper
    gripper:
      hinge: {origin: [0, 0.02, 0], axis: [0, 0, 1]}
      jaws:
        - {shape: {type: sphere, radius: 0.005}, offset: [-0.006, 0, 0], side: -1}
        - {shape: {type: sphere, radius: 0.005}, offset: [0.006, 0, 0], side: 1}
    keyframes: [{time: 0, position: [0.0, 0.033, 0.0], closure: %g}]
    coupling: {stiffness: 2000, mass: 0.05, max_force: 100}
)",
                  closure);
    return std::string(text);
  };
  const CompiledScene c = compile_scene(read_scene_description(write_scene(scene(0.0))));
  EXPECT_EQ(c.model->find_term<SdfContactTerm>(0), nullptr) << "the coupled jaws kept the per-sample penalty";
  const SceneToolState closed = run(scene(0.0)), open = run(scene(0.8));
  EXPECT_GT(closed.force.y(), 0.05) << closed.force.transpose();
  EXPECT_LT(open.force.norm(), 1e-9) << open.force.transpose();
}

}  // namespace
}  // namespace sflsh
