// SceneSession::reset() and set_stiffness_scale() (the viewer's
// reset button and stiffness slider) on the small box avatar: a reset
// followed by N steps is bit-identical to a fresh session's N steps; the
// scaled model's elastic energy, gradient and Hessian equal those of an
// ElasticTerm built from the avatar with every Young's modulus and Fung c
// multiplied by the scale; the static sag under gravity shrinks as 1/scale.
#include <gtest/gtest.h>

#include <cmath>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/energies/elastic.hpp"

using namespace sflsh;

namespace {

using SessionReset = test::BoxAvatarScene;

SceneSessionOptions quiet() {
  SceneSessionOptions o;
  o.progress = false;
  return o;
}

/// A coupled probe pressed 1 cm into the box's top by 0.2 s, under gravity,
/// with stiffness-proportional damping (so the scale reaches the damping too).
const char* kPressScene = R"(
solver: {dt: 1/250, seconds: 1, damping: 0.01}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    keyframes:
      - {time: 0.0, position: [0.0, 0.040, 0.0]}
      - {time: 0.2, position: [0.0, 0.020, 0.0]}
    coupling: {stiffness: 2000, mass: 0.05}
)";

/// Everything a step leaves behind that the next depends on, compared bit for bit.
void expect_same_state(const SceneSession& a, const SceneSession& b) {
  ASSERT_EQ(a.steps_done(), b.steps_done());
  EXPECT_EQ(a.time(), b.time());
  const State& sa = a.simulator().scene_state();
  const State& sb = b.simulator().scene_state();
  ASSERT_EQ(sa.bodies.size(), sb.bodies.size());
  for (size_t i = 0; i < sa.bodies.size(); ++i) {
    EXPECT_EQ(sa.bodies[i].q.z, sb.bodies[i].q.z) << "body " << i;
    EXPECT_EQ(sa.bodies[i].q_prev.z, sb.bodies[i].q_prev.z) << "body " << i;
    for (size_t j = 0; j < sa.bodies[i].q.bones.size(); ++j) {
      EXPECT_EQ(sa.bodies[i].q.bones[j].matrix(), sb.bodies[i].q.bones[j].matrix()) << "body " << i << " bone " << j;
      EXPECT_EQ(sa.bodies[i].q_prev.bones[j].matrix(), sb.bodies[i].q_prev.bones[j].matrix());
    }
  }
  EXPECT_EQ(a.body_surface(0), b.body_surface(0));
  EXPECT_EQ(a.tool_state(0).force, b.tool_state(0).force);
  EXPECT_EQ(a.tool_state(0).pose.matrix(), b.tool_state(0).pose.matrix());
  EXPECT_EQ(a.tool_state(0).device.position, b.tool_state(0).device.position);
  EXPECT_EQ(a.tool_state(0).live, b.tool_state(0).live);
}

/// The session's elastic term of body 0 (wrapped when scaled).
const EnergyTerm& elastic_term(const SceneSession& s) {
  for (const Model::BoundTerm& t : s.simulator().model().terms())
    if (t.bodies[0] == s.body_model_index(0) && t.term->name() == "elastic") return *t.term;
  ADD_FAILURE() << "no elastic term";
  throw std::runtime_error("no elastic term");
}

StepContext soft_context(const Avatar& a) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = a.num_reduced();
  return ctx;
}

/// Runs `steps` steps and returns the largest soft displacement |u| (m).
double sag_after(SceneSession& s, int steps) {
  for (int i = 0; i < steps; ++i) s.advance();
  return s.body_displacement(0).rowwise().norm().maxCoeff();
}

}  // namespace

TEST_F(SessionReset, ResetThenStepsEqualsAFreshSessionBitForBit) {
  const SceneDescription sc = read_scene_description(write_scene(kPressScene));
  SceneSession used(sc, quiet());
  for (int i = 0; i < 40; ++i) used.advance();
  // A pushed pose makes the tool live; the reset drops it (keyframes again).
  teleop::PoseSample p;
  p.position = Vec3(0.004, 0.025, 0.0);
  used.set_device_pose(0, p);
  for (int i = 0; i < 30; ++i) used.advance();
  ASSERT_TRUE(used.tool_state(0).live);
  ASSERT_GT(used.tool_state(0).force.norm(), 0.1) << "the probe should press the flesh before the reset";
  used.reset();
  EXPECT_EQ(used.steps_done(), 0);
  EXPECT_EQ(used.time(), 0.0);
  EXPECT_FALSE(used.tool_state(0).live);

  SceneSession fresh(sc, quiet());
  expect_same_state(used, fresh);
  for (int i = 0; i < 90; ++i) {
    used.advance();
    fresh.advance();
  }
  expect_same_state(used, fresh);
  EXPECT_GT(fresh.tool_state(0).force.norm(), 0.1);  // the compared steps include contact
}

TEST_F(SessionReset, ResetKeepsTheStiffnessScaleAndMatchesAFreshScaledSession) {
  const SceneDescription sc = read_scene_description(write_scene(kPressScene));
  SceneSession used(sc, quiet());
  for (int i = 0; i < 20; ++i) used.advance();
  used.set_stiffness_scale(3.0);
  for (int i = 0; i < 20; ++i) used.advance();
  used.reset();
  EXPECT_EQ(used.stiffness_scale(0), 3.0);
  SceneSession fresh(sc, quiet());
  fresh.set_stiffness_scale(3.0, 0);
  for (int i = 0; i < 80; ++i) {
    used.advance();
    fresh.advance();
  }
  expect_same_state(used, fresh);
  // And the scale changed the run: an unscaled session differs.
  SceneSession unscaled(sc, quiet());
  for (int i = 0; i < 80; ++i) unscaled.advance();
  EXPECT_NE(unscaled.simulator().state(0).z, fresh.simulator().state(0).z);
}

TEST_F(SessionReset, StiffnessScaleEqualsScalingTheMaterialsYoungsModuliAndFungC) {
  const SceneDescription sc = read_scene_description(write_scene(kPressScene));
  SceneSession s(sc, quiet());
  const Avatar& a = s.avatar(0);
  const StepContext ctx = soft_context(a);
  Configuration q;
  q.bones = std::vector<Isometry>(24, Isometry::Identity());
  // A fixed displaced state: small (the quadratic regime) and large (Fung
  // saturation and the barrier matter).
  for (double amplitude : {1e-4, 4e-3}) {
    q.z = amplitude * VecX::LinSpaced(a.num_reduced(), -1.0, 1.3).array().sin().matrix();
    for (double scale : {0.25, 3.0}) {
      s.set_stiffness_scale(scale);
      Avatar scaled = a;
      for (RegionMaterial& m : scaled.materials) {
        m.young_along *= scale;
        m.young_through *= scale;
        m.young_around *= scale;
        m.fung_c *= scale;
      }
      const ElasticTerm expected_term(scaled), unscaled_term(a);
      const int n = a.num_reduced();
      VecX g = VecX::Zero(n), ge = VecX::Zero(n);
      MatX H = MatX::Zero(n, n), He = MatX::Zero(n, n);
      const double e = elastic_term(s).evaluate(ctx, q, &g, &H);
      const double expected = expected_term.evaluate(ctx, q, &ge, &He);
      const double e1 = unscaled_term.evaluate(ctx, q, nullptr, nullptr);
      ASSERT_GT(e1, 0.0);
      EXPECT_NEAR(e, expected, 1e-12 * expected) << "amplitude " << amplitude << " scale " << scale;
      EXPECT_NEAR(e / e1, scale, 1e-12 * scale);
      EXPECT_LT((g - ge).norm(), 1e-12 * ge.norm());
      EXPECT_LT((H - He).norm(), 1e-12 * He.norm());
    }
  }
  // Scale 1 is the avatar's own term again, and bad scales or bodies are refused.
  s.set_stiffness_scale(1.0);
  EXPECT_NE(dynamic_cast<const ElasticTerm*>(&elastic_term(s)), nullptr);
  EXPECT_THROW(s.set_stiffness_scale(0.0), Error);
  EXPECT_THROW(s.set_stiffness_scale(std::nan("")), Error);
  EXPECT_THROW(s.set_stiffness_scale(2.0, 1), Error);
}

TEST_F(SessionReset, StaticSagUnderGravityShrinksAsOneOverTheScale) {
  // No tool: the box sags under its own weight. In the small-strain regime
  // the static sag solves K u = f, so scaling K by s divides it by s.
  const SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/250, seconds: 2, damping: 0.01}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
)"));
  SceneSession soft(sc, quiet()), stiff(sc, quiet());
  stiff.set_stiffness_scale(4.0);
  const double u1 = sag_after(soft, 250), u4 = sag_after(stiff, 250);
  // Settled: another 50 steps change the sag by < 0.5%.
  EXPECT_NEAR(sag_after(soft, 50), u1, 5e-3 * u1);
  EXPECT_NEAR(sag_after(stiff, 50), u4, 5e-3 * u4);
  std::printf("box sag under gravity: %.4f mm at scale 1, %.4f mm at scale 4 (ratio %.4f)\n", u1 * 1e3, u4 * 1e3,
              u4 / u1);
  ASSERT_GT(u1, 1e-6);
  EXPECT_NEAR(u4 / u1, 0.25, 0.01);
}

TEST_F(SessionReset, ChangingTheScaleInContactKeepsThePatchsDisplacement) {
  // The contact patch's displacement δu (and its velocity history) is state
  // the terms carry from step to step. Setting the scale rebuilds the model:
  // a session set to its own scale (1) in the middle of a press must go on
  // exactly as one left alone, not lose the dent (a pop, then a new patch).
  std::string text = kPressScene;
  text.replace(text.find("bodies:"), 0, "contact: {patch: true, friction: 0}\n");
  text.erase(text.find("    coupling:"));  // kinematic: it stays pressed in
  const SceneDescription sc = read_scene_description(write_scene(text.c_str()));
  SceneSession rescaled(sc, quiet()), alone(sc, quiet());
  double pressed = 0;
  for (int i = 0; i < 60; ++i) {
    rescaled.advance();
    alone.advance();
    pressed = std::max(pressed, alone.tool_state(0).force.norm());
  }
  ASSERT_GT(pressed, 0.1) << "the probe should press the flesh by now";
  rescaled.set_stiffness_scale(1.0);
  for (int i = 0; i < 5; ++i) {
    rescaled.advance();
    alone.advance();
  }
  expect_same_state(rescaled, alone);
}
