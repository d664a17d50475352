// The integrator: rest, free fall, prescribed bones, settling under gravity
// against a static solve, released oscillation with/without damping,
// converged Newton = minimizer, and the step time at K = 64.
#include <iostream>
#include <numeric>

#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/scaled_term.hpp"
#include "sflsh/sim/energies/gravity.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/simulator.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

std::shared_ptr<const Avatar> avatar(int handles = 8, bool all_tets = true) {
  test::SyntheticAvatarOptions o;
  o.handles = handles;
  o.handle_radius = 0.07;
  o.all_tets = all_tets;
  return std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
}

/// Mass-weighted mean world position over the inertia cubature.
Vec3 centre_of_mass(const Avatar& a, const Configuration& q) {
  const InertiaTerm inertia(a);
  const Points x = inertia.points().world(q);
  return (inertia.masses().transpose() * x).transpose() / inertia.masses().sum();
}

/// Static equilibrium of elasticity + gravity (kinematic bones = identity), by
/// Newton with line search to convergence.
VecX static_solution(const Avatar& a, const Vec3& gravity) {
  ElasticTerm elastic(a);
  GravityTerm grav(a);
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.gravity = gravity;
  Configuration q;
  q.bones = identity_bones();
  q.z = VecX::Zero(a.num_reduced());
  NewtonOptions o;
  o.iterations = 100;
  o.line_search = true;
  o.gradient_tolerance = 1e-13;
  const StepReport rep = newton_minimize({&elastic, &grav}, ctx, q, o);
  // Converged to round-off: the line search stops when E can no longer decrease.
  EXPECT_LT(rep.grad_norm_after, 1e-7 * rep.grad_norm_before) << rep.summary();
  return q.z;
}

TEST(Simulator, BodyAtRestStaysAtRest) {
  for (bool dynamic : {false, true}) {
    SimulatorOptions o;
    o.gravity = Vec3::Zero();
    o.bones_dynamic = dynamic;
    Simulator sim(avatar_model(avatar(), o));
    for (int i = 0; i < 30; ++i) {
      const StepReport rep = sim.step(identity_bones());
      EXPECT_EQ(rep.outcome, StepOutcome::Accepted);
    }
    EXPECT_LT(sim.state().z.norm(), 1e-14);
    for (const Isometry& G : sim.state().bones) EXPECT_LT((G.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(sim.time(), 30 * o.h, 1e-12);
  }
}

TEST(Simulator, FreeFallOfTheWholeBodyMatchesGravity) {
  // Bones dynamic, soft-tissue terms only: every point accelerates at g, the body
  // does not deform. Backward Euler from rest: x_n = x_0 + h² g n(n+1)/2.
  SimulatorOptions o;
  o.bones_dynamic = true;
  const auto a = avatar();
  Simulator sim(avatar_model(a, o));
  const Vec3 c0 = centre_of_mass(*a, sim.state());
  const int n = 20;
  Vec3 c_prev = c0, c_prev2 = c0;
  for (int i = 1; i <= n; ++i) {
    const StepReport rep = sim.step(identity_bones());
    ASSERT_NE(rep.outcome, StepOutcome::Rejected);
    const Vec3 c = centre_of_mass(*a, sim.state());
    if (i >= 2) {
      EXPECT_LT(((c - 2 * c_prev + c_prev2) / (o.h * o.h) - o.gravity).norm(), 1e-6) << "step " << i;
    }
    c_prev2 = c_prev;
    c_prev = c;
  }
  EXPECT_LT((c_prev - c0 - o.h * o.h * o.gravity * n * (n + 1) / 2.0).norm(), 1e-9);
  EXPECT_LT(sim.state().z.norm(), 1e-9);
  EXPECT_LT(sim.model().find_term<ElasticTerm>(0)->min_det(sim.state().z) - 1.0, 1e-9);
}

TEST(Simulator, PrescribedBonesTrackTheMotionExactly) {
  const auto a = avatar();
  Simulator sim(avatar_model(a, SimulatorOptions{}));  // kinematic by default
  const double h = sim.h();
  double max_u = 0;
  for (int i = 1; i <= 40; ++i) {
    const auto target = test::synthetic_motion(*a, i * h);
    const StepReport rep = sim.step(target);
    EXPECT_NE(rep.outcome, StepOutcome::Rejected);
    for (int j = 0; j < 24; ++j) EXPECT_EQ((sim.state().bones[j].matrix() - target[j].matrix()).norm(), 0.0);
    const Points J = sim.joints();
    EXPECT_LT((J.row(3).transpose() - target[3] * Vec3(a->joints_rest.row(3).transpose())).norm(), 1e-14);
    max_u = std::max(max_u, sim.soft_displacement().rowwise().norm().maxCoeff());
  }
  // The motion shakes the soft tissue (it is not just skinning).
  EXPECT_GT(max_u, 1e-4);
  EXPECT_GT(sim.model().find_term<ElasticTerm>(0)->min_det(sim.state().z), 0.0);
}

TEST(Simulator, SoftTissueSettlesAtTheStaticEquilibrium) {
  const auto a = avatar();
  SimulatorOptions o;
  o.gravity = Vec3(-9.81, -9.81, 0);  // sideways and down: bending and compression
  Simulator sim(avatar_model(a, o));
  for (int i = 0; i < 400; ++i) sim.step(identity_bones());
  const VecX z_static = static_solution(*a, o.gravity);
  ASSERT_GT(z_static.norm(), 1e-4);
  EXPECT_LT((sim.state().z - z_static).norm(), 1e-5 * z_static.norm());
}

/// Elastic + kinetic energy of the reduced state (kinetic from (x_t − x_{t−1})/h).
double mechanical_energy(const Simulator& sim, const InertiaTerm& inertia, const ElasticTerm& elastic) {
  StepContext ctx;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = sim.avatar().num_reduced();
  const Points v = (inertia.points().world(sim.state()) - inertia.points().world(sim.previous_state())) / sim.h();
  double kinetic = 0;
  for (int s = 0; s < v.rows(); ++s) kinetic += 0.5 * inertia.masses()[s] * v.row(s).squaredNorm();
  return kinetic + elastic.evaluate(ctx, sim.state(), nullptr, nullptr);
}

TEST(Simulator, ReleasedDeformationOscillatesWithoutDampingAndDecaysWithIt) {
  const auto a = avatar();
  const VecX z0 = static_solution(*a, Vec3(-30, 0, 0));  // a sideways bend, then released
  const InertiaTerm inertia(*a);
  const ElasticTerm elastic(*a);
  struct Run {
    int crossings = 0;
    double energy_ratio = 0;
  };
  auto run = [&](double beta) {
    SimulatorOptions o;
    o.h = 2.5e-4;
    o.gravity = Vec3::Zero();
    o.damping = beta;
    Simulator sim(avatar_model(a, o));
    Configuration q0;
    q0.bones = identity_bones();
    q0.z = z0;
    sim.reset(q0, q0);
    const double E0 = mechanical_energy(sim, inertia, elastic);
    Run r;
    double previous = z0.dot(z0);
    for (int i = 0; i < 800; ++i) {  // 0.2 s
      sim.step(identity_bones());
      const double s = sim.state().z.dot(z0);
      if ((s < 0) != (previous < 0)) ++r.crossings;
      previous = s;
    }
    r.energy_ratio = mechanical_energy(sim, inertia, elastic) / E0;
    return r;
  };
  const Run free = run(0.0), damped = run(0.01);
  std::cout << "[ released ] undamped: " << free.crossings << " zero crossings, energy ratio " << free.energy_ratio
            << "; damped (beta 0.01 s): " << damped.crossings << " crossings, ratio " << damped.energy_ratio << "\n";
  // The bend's fundamental mode is ≈ 12 Hz (ω ≈ 75 rad/s): ≥ 2 periods in 0.2 s.
  EXPECT_GE(free.crossings, 4);
  // Backward Euler loses energy by 1/(1 + ω²h²) per step: (1 + (75·2.5e-4)²)^-800 ≈ 0.75
  // for that mode, less for higher ones.
  EXPECT_GT(free.energy_ratio, 0.5);
  EXPECT_LT(free.energy_ratio, 1.0 + 1e-6);  // and never gains energy
  EXPECT_LT(damped.energy_ratio, 0.3 * free.energy_ratio);
}

TEST(Simulator, ConvergedNewtonReachesTheMinimizer) {
  const auto a = avatar();
  SimulatorOptions o;
  o.newton.iterations = 30;
  o.newton.line_search = true;
  o.newton.gradient_tolerance = 1e-12;
  Simulator sim(avatar_model(a, o));
  SimulatorOptions one = o;
  one.newton = NewtonOptions();
  one.newton.nonlinearity_tolerance = 0.0;  // exactly one Newton step (the check is tested below)
  Simulator sim1(avatar_model(a, one));
  for (int i = 1; i <= 10; ++i) {
    const auto target = test::synthetic_motion(*a, i * o.h, 0.03, 0.5);
    const StepReport rep = sim.step(target);
    // Round-off level: the line search stops when E (~0.5 J, resolved to ~1e-16 J)
    // no longer decreases, at |g| ~ 1e-8 here; reassociating the Hessian's sums
    // (the exact speed-ups) moves the last iterate by round-off and |g|
    // from just below to just above 1e-8, hence the margin. Mean dilatation
    // (the default) couples each cell's tets in K, whose larger
    // entries raise that floor to ~1e-7; not converging would leave |g| near
    // its start (~0.8).
    EXPECT_LT(rep.grad_norm_after, 3e-7 * std::max(1.0, rep.grad_norm_before)) << rep.summary();
    const StepReport rep1 = sim1.step(target);
    EXPECT_LT(rep1.energy_after, rep1.energy_before) << rep1.summary();  // one step decreases E
    EXPECT_EQ(rep1.iterations, 1);
  }
  // One Newton step per time step stays close to the converged trajectory.
  EXPECT_LT((sim1.state().z - sim.state().z).norm(), 0.2 * sim.state().z.norm());
}

/// E(z) = Σ_i ½ a z_i² + ¼ b z_i⁴ − f z_i on the soft DoFs alone.
struct QuarticTerm : EnergyTerm {
  double a = 1, b = 0, f = 1;
  bool checked = true;  ///< in_nonlinearity_check (false: as a contact term)
  std::string name() const override { return "quartic"; }
  bool in_nonlinearity_check() const override { return checked; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override {
    const int z0 = ctx.layout.z_offset();
    double E = 0;
    for (int i = 0; i < q.z.size(); ++i) {
      const double z = q.z[i];
      E += 0.5 * a * z * z + 0.25 * b * z * z * z * z - f * z;
      if (grad) (*grad)[z0 + i] += a * z + b * z * z * z - f;
      if (hess) (*hess)(z0 + i, z0 + i) += a + 3 * b * z * z;
    }
    return E;
  }
};

/// A system of three soft DoFs and no bones (the quartic tests below).
StepContext three_soft_dofs() {
  StepContext ctx;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_bones = 0;
  ctx.layout.num_reduced = 3;
  return ctx;
}

/// NewtonOptions::nonlinearity_tolerance. From z = 0 the Newton step is f/a; the energy falls by
/// ½ f²/a − ¼ b f⁴/a⁴ against the model's ½ f²/a, so ρ = 1 − ½ b f²/a³ (by hand): 0.9 for
/// a = f = 1, b = 0.2. Then the second iteration goes from 1 to 1 − (1 + 0.2 − 1)/(1 + 0.6) =
/// 0.875. A quadratic (b = 0) has ρ = 1 and takes no second iteration.
TEST(Newton, AFullStepFarFromItsQuadraticModelGetsOneMoreIteration) {
  const StepContext ctx = three_soft_dofs();
  QuarticTerm term;
  term.b = 0.2;
  NewtonOptions o;
  o.max_z_step = 0;  // the steps here are 1 "m": no cap
  o.nonlinearity_tolerance = 0.05;
  Configuration q;
  q.z = VecX::Zero(3);
  StepReport rep = newton_minimize({&term}, ctx, q, o);
  EXPECT_EQ(rep.iterations, 2) << rep.summary();
  EXPECT_EQ(rep.iterations_for_nonlinearity, 1);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(q.z[i], 0.875, 1e-15);
  // Within the tolerance (|ρ − 1| = 0.1 < 0.2), off (0) and a quadratic: one iteration, z = f/a.
  for (const auto& [tol, b] : {std::pair{0.2, 0.2}, std::pair{0.0, 0.2}, std::pair{1e-9, 0.0}}) {
    term.b = b;
    o.nonlinearity_tolerance = tol;
    q.z = VecX::Zero(3);
    rep = newton_minimize({&term}, ctx, q, o);
    EXPECT_EQ(rep.iterations, 1) << "tolerance " << tol << ", b " << b;
    EXPECT_EQ(rep.iterations_for_nonlinearity, 0);
    EXPECT_NEAR(q.z[0], 1.0, 1e-15);
  }
  o.nonlinearity_tolerance = -1;
  EXPECT_THROW(newton_minimize({&term}, ctx, q, o), Error);
}

/// Contact terms are left out of the check: a quadratic Q = ½z² − z and a
/// quartic U = ½z² + z⁴. From z = 0 the step is δ = 1/2 (g = −1, H = 2) and
/// the model predicts a decrease of ¼ per DoF. Q falls by 3/8, exactly its own
/// model's −g_Qδ − ½H_Qδ² = ½ − ⅛; U rises by ⅛ + 1/16 against a model of ⅛:
/// ρ = 0.75 (by hand). Counted, U adds an iteration; as a contact term, none
/// (z = 1/2 exactly). The other way round (Q quartic, U = ½z² left out) Q
/// departs from its model by 1/16 = ¼ of the predicted decrease: added.
TEST(Newton, TermsLeftOutOfTheNonlinearityCheckDoNotAddIterations) {
  const StepContext ctx = three_soft_dofs();
  NewtonOptions o;
  o.max_z_step = 0;
  o.nonlinearity_tolerance = 0.05;
  for (const bool left_out : {false, true}) {
    QuarticTerm quadratic, quartic;
    quartic.f = 0;
    quartic.b = 4;
    quartic.checked = !left_out;
    const auto scaled = std::make_shared<const QuarticTerm>(quartic);
    ScaledTerm unit(scaled, 1.0);  // the wrapper forwards in_nonlinearity_check
    EXPECT_EQ(unit.in_nonlinearity_check(), !left_out);
    Configuration q;
    q.z = VecX::Zero(3);
    const StepReport rep = newton_minimize({&quadratic, &unit}, ctx, q, o);
    EXPECT_EQ(rep.iterations_for_nonlinearity, left_out ? 0 : 1) << "left out " << left_out;
    if (left_out) {
      EXPECT_NEAR(q.z[1], 0.5, 1e-15);
    }
  }
  QuarticTerm nonlinear, left_out;
  nonlinear.b = 4;
  left_out.f = 0;
  left_out.checked = false;
  Configuration q;
  q.z = VecX::Zero(3);
  EXPECT_EQ(newton_minimize({&nonlinear, &left_out}, ctx, q, o).iterations_for_nonlinearity, 1);
}

/// Unset, the tolerance is kAutoNonlinearityTolerance (0.05) when the step's DoFs are all soft
/// tissue, and off when the system has others (here a dynamic bone, on which the quartic does
/// not act: its zero Hessian rows are set to 1, so it does not move). Same quartic as above, ρ = 0.9.
TEST(Newton, TheNonlinearityCheckIsOnByDefaultOnlyWhenEveryDofIsSoftTissue) {
  QuarticTerm term;
  term.b = 0.2;
  NewtonOptions o;
  o.max_z_step = 0;
  ASSERT_FALSE(o.nonlinearity_tolerance.has_value());
  EXPECT_EQ(kAutoNonlinearityTolerance, 0.05);
  for (const bool bones_dynamic : {false, true}) {
    StepContext ctx;
    ctx.layout.bones_dynamic = bones_dynamic;
    ctx.layout.num_bones = 1;
    ctx.layout.num_reduced = 3;
    Configuration q;
    q.bones = {Isometry::Identity()};
    q.z = VecX::Zero(3);
    const StepReport rep = newton_minimize({&term}, ctx, q, o);
    EXPECT_EQ(rep.iterations_for_nonlinearity, bones_dynamic ? 0 : 1) << "bones dynamic " << bones_dynamic;
    EXPECT_NEAR(q.z[0], bones_dynamic ? 1.0 : 0.875, 1e-15);
    EXPECT_TRUE(q.bones[0].isApprox(Isometry::Identity(), 0.0));
    // Set explicitly, it applies with the bone too.
    NewtonOptions explicit_tol = o;
    explicit_tol.nonlinearity_tolerance = 0.05;
    q.bones = {Isometry::Identity()};
    q.z = VecX::Zero(3);
    EXPECT_EQ(newton_minimize({&term}, ctx, q, explicit_tol).iterations_for_nonlinearity, 1);
  }
}

}  // namespace
}  // namespace sflsh
