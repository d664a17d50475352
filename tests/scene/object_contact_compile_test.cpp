// What body–object contact compiles to: with contact.patch the face-sampled
// patch term with the scene's friction, radius, node cap, pressure stiffness
// and spacing; without, the per-skin-sample penalty with the scene's friction.
#include <gtest/gtest.h>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_compiler.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"

namespace sflsh {
namespace {

class ObjectContactCompile : public test::BoxAvatarScene {
 protected:
  CompiledScene compile(const std::string& contact) {
    return compile_scene(read_scene_description(write_scene(
        "solver: {seconds: 0.1}\ncontact: " + contact +
        "\nbodies:\n"
        "  - {name: a, avatar: box.h5, motion: none, bones: dynamic}\n"
        "objects:\n"
        "  - {name: ball, shape: {type: sphere, radius: 0.05}, kind: dynamic, mass: 1.0, position: [0, 0.3, 0]}\n")));
  }
};

TEST_F(ObjectContactCompile, ThePatchTermTakesTheScenesFrictionAndPatchSettings) {
  const CompiledScene c =
      compile("{friction: 0.3, patch: {radius: 0.03, max_nodes: 77, pressure_stiffness: 5.0e7, spacing: 0.003}}");
  EXPECT_EQ(c.model->find_term<SdfContactTerm>(0), nullptr);
  const auto* patch = c.model->find_term<ContactPatchTerm>(0);
  ASSERT_NE(patch, nullptr);
  EXPECT_EQ(patch->options().friction, 0.3);
  EXPECT_EQ(patch->options().patch_radius, 0.03);
  EXPECT_EQ(patch->options().max_patch_nodes, 77);
  EXPECT_EQ(patch->options().pressure_stiffness, 5.0e7);
  EXPECT_EQ(patch->options().spacing, 0.003);
}

TEST_F(ObjectContactCompile, WithoutThePatchThePerSamplePenaltyTakesTheScenesFriction) {
  const CompiledScene c = compile("{friction: 0.3, stiffness: {body_object: 3.0e5}}");
  EXPECT_EQ(c.model->find_term<ContactPatchTerm>(0), nullptr);
  const auto* sdf = c.model->find_term<SdfContactTerm>(0);
  ASSERT_NE(sdf, nullptr);
  EXPECT_EQ(sdf->options().friction, 0.3);
  EXPECT_EQ(sdf->options().stiffness, 3.0e5);
}

}  // namespace
}  // namespace sflsh
