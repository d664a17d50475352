// Forward sensitivities of the simulated skin (fit/trajectory_sensitivity.hpp)
// against central finite differences of whole simulations, for every kind of
// parameter, on a tiny synthetic body.
#include <gtest/gtest.h>

#include "fit_fixture.hpp"
#include "sflsh/fit/trajectory_sensitivity.hpp"
#include "sflsh/sim/simulator.hpp"

namespace sflsh {
namespace {

TEST(TrajectorySensitivity, ForwardRunIsTheSimulatorsToTheBit) {
  const Avatar a = test::fit_avatar();
  const BoneSequence seq = test::fit_bones(a, 20);
  const FitParameters params(a, "young,fung_c", "all");
  const SurfaceRun run = simulate_surface(a, params, VecX::Zero(params.size()), 0.0, seq, {20}, {}, false);
  // The same run through Simulator directly.
  SimulatorOptions so;
  so.h = seq.h;
  so.bones_dynamic = false;
  so.newton.nonlinearity_tolerance = 0.0;  // one Newton step per time step, as the fit differentiates
  Simulator sim(avatar_model(std::make_shared<Avatar>(a), so));
  Configuration q0{seq.bones[0], VecX::Zero(a.num_reduced())}, qm{seq.bones_before, VecX::Zero(a.num_reduced())};
  sim.reset(q0, qm);
  for (int s = 1; s <= 20; ++s) sim.step(seq.bones[s]);
  EXPECT_EQ((run.surface[0] - sim.posed_surface()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT((sim.posed_surface() - a.surface_rest).cwiseAbs().maxCoeff(), 1e-3);  // it moved
}

struct Case {
  const char* kinds;
  double damping;
};

class SensitivityVsFiniteDifference : public ::testing::TestWithParam<Case> {};

TEST_P(SensitivityVsFiniteDifference, EveryParameter) {
  const Avatar a = test::fit_avatar();
  const BoneSequence seq = test::fit_bones(a, 24);
  const FitParameters params(a, GetParam().kinds, "all");
  VecX p = params.initial(a, GetParam().damping);
  // Away from the defaults, regions different.
  for (int i = 0; i < params.size(); ++i)
    if (params.entries()[i].kind != FitParameter::Kind::Poisson && params.entries()[i].kind != FitParameter::Kind::Damping)
      p[i] += 0.2 * (i % 2 ? 1 : -1);
  const std::vector<int> steps = {6, 12, 24};
  const SurfaceRun run = simulate_surface(a, params, p, 0.0, seq, steps, {}, true);
  EXPECT_EQ(run.shortened_steps, 0);
  for (int i = 0; i < params.size(); ++i) {
    const double eps = params.entries()[i].kind == FitParameter::Kind::Damping ? 1e-5 : 1e-5;
    VecX pp = p, pm = p;
    pp[i] += eps;
    pm[i] -= eps;
    const SurfaceRun rp = simulate_surface(a, params, pp, 0.0, seq, steps, {}, false);
    const SurfaceRun rm = simulate_surface(a, params, pm, 0.0, seq, steps, {}, false);
    for (size_t f = 0; f < steps.size(); ++f) {
      const Points d = (rp.surface[f] - rm.surface[f]) / (2 * eps);
      const VecX fd = Eigen::Map<const MatXr>(MatXr(d).data(), d.size(), 1);
      const VecX an = run.jacobian[f].col(i);
      const double scale = fd.norm();
      ASSERT_GT(scale, 1e-7) << params.entries()[i].label(a.materials) << " does not move the skin";
      EXPECT_LT((an - fd).norm(), 2e-5 * scale)
          << params.entries()[i].label(a.materials) << " at step " << steps[f] << ": |fd| = " << scale
          << " m per unit, |analytic - fd| = " << (an - fd).norm();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, SensitivityVsFiniteDifference,
                         ::testing::Values(Case{"young,fung_c", 0.0}, Case{"poisson", 0.0},
                                           Case{"young,damping", 0.01}));

}  // namespace
}  // namespace sflsh
