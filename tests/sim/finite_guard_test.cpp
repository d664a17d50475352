// The run-time numerical guard (sim/finite_guard.hpp): it finds the first
// non-finite value and names the term, the body and the part of the state.
#include <gtest/gtest.h>

#include <limits>

#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sim/synthetic_avatar.hpp"

using namespace sflsh;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Fixture {
  std::shared_ptr<const Avatar> avatar = std::make_shared<Avatar>(test::make_synthetic_avatar());
  SimulatorOptions options;
  Simulator sim{avatar_model(avatar, options, nullptr, "bob")};
  StepReport rep;
  Fixture() {
    sim.reset(std::vector<Isometry>(24, Isometry::Identity()));
    rep = sim.step(std::vector<Isometry>(24, Isometry::Identity()));
  }
};

}  // namespace

TEST(FiniteGuard, AFiniteStepPasses) {
  Fixture f;
  ASSERT_FALSE(f.rep.energies.empty());
  EXPECT_TRUE(find_non_finite(f.sim.model(), f.sim.scene_state(), f.rep).finite());
  EXPECT_NO_THROW(require_finite_step(f.sim.model(), f.sim.scene_state(), f.rep, 1, "run"));
}

TEST(FiniteGuard, NamesTheReducedDofAndTheBody) {
  Fixture f;
  State s = f.sim.scene_state();
  s.bodies[0].q.z[4] = kNaN;
  const NonFiniteReport r = find_non_finite(f.sim.model(), s, f.rep);
  EXPECT_EQ(r.body, "bob");
  EXPECT_EQ(r.what, "reduced DoF z[4] = nan");
  EXPECT_TRUE(r.term.empty());
}

TEST(FiniteGuard, NamesTheBoneBeforeTheSoftDofs) {
  Fixture f;
  State s = f.sim.scene_state();
  s.bodies[0].q.z[0] = kNaN;
  s.bodies[0].q.bones[3].translation().y() = std::numeric_limits<double>::infinity();
  const NonFiniteReport r = find_non_finite(f.sim.model(), s, f.rep);
  EXPECT_EQ(r.body, "bob");
  EXPECT_EQ(r.what, "bone 3 (spine1) transform");
}

TEST(FiniteGuard, NamesTheFirstNonFiniteTermWithItsBodyAndTheStepInTheError) {
  Fixture f;
  StepReport rep = f.rep;
  ASSERT_GE(rep.energies.size(), 2u);
  const std::string second = rep.energies[1].name;
  rep.energies[1].value = kNaN;
  rep.energy_after = kNaN;
  const NonFiniteReport r = find_non_finite(f.sim.model(), f.sim.scene_state(), rep);
  EXPECT_EQ(r.term, second);
  EXPECT_EQ(r.body, "bob");
  EXPECT_FALSE(r.finite());
  try {
    require_finite_step(f.sim.model(), f.sim.scene_state(), rep, 17, "builtin:jump");
    ADD_FAILURE() << "no error";
  } catch (const NonFiniteError& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.step(), 17);
    for (const std::string& frag : std::vector<std::string>{"builtin:jump", "step 17", "term '" + second + "'", "body 'bob'"})
      EXPECT_NE(m.find(frag), std::string::npos) << frag << " not in: " << m;
  }
}

TEST(FiniteGuard, TermsNotEvaluatedAreNotReported) {
  // NewtonOptions::report_final off: every term and the total are NaN by design.
  Fixture f;
  StepReport rep = f.rep;
  for (auto& e : rep.energies) e.value = kNaN;
  rep.energy_after = kNaN;
  EXPECT_TRUE(find_non_finite(f.sim.model(), f.sim.scene_state(), rep).finite());
}
