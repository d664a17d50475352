// What contact.bodies compiles to: the skin-against-skin term with the
// scene's pressure stiffness and spacing and the bone capsules shrunk to the
// scene's core radius, or (model: capsules) the capsules alone at full radius.
#include <gtest/gtest.h>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/scene/scene_compiler.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/sim/energies/capsule_contact.hpp"
#include "sflsh/sim/energies/skin_contact.hpp"

namespace sflsh {
namespace {

class BodyContactCompile : public test::BoxAvatarScene {
 protected:
  CompiledScene compile(const std::string& contact) {
    return compile_scene(read_scene_description(write_scene(
        "solver: {seconds: 0.1}\ncontact: " + contact +
        "\nbodies:\n"
        "  - {name: a, avatar: box.h5, motion: none, bones: dynamic}\n"
        "  - {name: b, avatar: box.h5, motion: none, bones: dynamic, placement: {offset: [0.2, 0, 0]}}\n")));
  }
};

TEST_F(BodyContactCompile, SkinTermAndCoresTakeTheScenesValues) {
  const CompiledScene c = compile("{bodies: {pressure_stiffness: 3.0e8, spacing: 0.006, core_radius: 0.7}}");
  const auto* skin = c.model->find_term<SkinContactTerm>(0);
  ASSERT_NE(skin, nullptr);
  EXPECT_EQ(skin->options().pressure_stiffness, 3.0e8);
  EXPECT_EQ(skin->options().spacing, 0.006);
  const auto* caps = c.model->find_term<CapsuleContactTerm>(0);
  ASSERT_NE(caps, nullptr);
  EXPECT_EQ(caps->options().radius_scale, 0.7);
  EXPECT_EQ(caps->options().stiffness, ContactDescription().body_body_stiffness);
}

TEST_F(BodyContactCompile, CapsulesModelHasNoSkinTermAndFullRadius) {
  const CompiledScene c = compile("{bodies: {model: capsules, core_radius: 0.7}}");
  EXPECT_EQ(c.model->find_term<SkinContactTerm>(0), nullptr);
  const auto* caps = c.model->find_term<CapsuleContactTerm>(0);
  ASSERT_NE(caps, nullptr);
  EXPECT_EQ(caps->options().radius_scale, 1.0);
}

}  // namespace
}  // namespace sflsh
