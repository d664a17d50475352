// Skin-against-skin contact between two bodies: the energy and force of two
// flat faces pressed together against κ × depth × area by hand, derivatives
// against central differences through both bodies' bones and soft DoFs,
// the Gauss–Newton Hessian's form, equal and opposite forces (linear and
// angular momentum), the broad phase (far apart: nothing; a fast approach:
// caught), and bad options.
#include <gtest/gtest.h>

#include <random>

#include "sflsh/sim/energies/skin_contact.hpp"
#include "sflsh/sim/momentum.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/two_body_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;
using namespace sflsh::test::two_body;

namespace {

// The box avatar: x, z ∈ [−0.04, 0.04], y ∈ [0, 0.12]; its +x face has area 0.08 × 0.12.
constexpr double kFaceArea = 0.08 * 0.12;

Configuration translated(const Avatar& a, const Vec3& t) {
  Configuration q;
  q.bones.assign(24, Isometry(Eigen::Translation3d(t)));
  q.z = VecX::Zero(a.num_reduced());
  return q;
}

std::vector<Bound> two_boxes(const Avatar& a, const Avatar& b, const Configuration& qa, const Configuration& qb,
                             const Configuration& qb_prev) {
  std::vector<Bound> bodies{{&a, body_layout(a, true), qa, qa, qa}, {&b, body_layout(b, true), qb, qb_prev, qb_prev}};
  bodies[1].layout.base = bodies[0].layout.size();
  return bodies;
}

TEST(SkinContact, TwoFlatFacesPressedTogetherGiveKappaDepthAreaByHand) {
  // Box b side by side with box a along +x, 1 mm of overlap: every sample of
  // a's +x face is 1 mm inside b behind b's −x face, and every sample of b's
  // −x face 1 mm inside a (the samples nearest an edge sit 2.2 mm from it: no
  // side face is nearer). Each side counts κ/2, so E = ½ κ A d² and the force
  // on a is κ A d along −x.
  const Avatar a = box(), b = box();
  const double kappa = 1.0e8, d = 0.001;
  SkinContactOptions o;
  o.pressure_stiffness = kappa;
  const SkinContactTerm term(a, b, o);
  for (double depth : {d, -0.003}) {  // overlapping; 3 mm apart (within the margin: pairs, no energy)
    const Configuration qa = translated(a, Vec3::Zero()), qb = translated(b, Vec3(0.08 - depth, 0, 0));
    std::vector<Bound> bodies = two_boxes(a, b, qa, qb, qb);
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx)) << "depth " << depth;
    const Derivatives got = analytic(term, ctx, bodies);
    const auto rep = term.report(ctx, qa);
    if (depth < 0) {
      EXPECT_EQ(got.E, 0.0);
      EXPECT_EQ(got.grad.norm(), 0.0);
      EXPECT_EQ(rep[1].value[0], 0);  // active samples
      continue;
    }
    EXPECT_NEAR(got.E, 0.5 * kappa * kFaceArea * d * d, 1e-9 * got.E);
    ASSERT_EQ(rep[0].name, "force");
    EXPECT_LT((Vec3(rep[0].value) - Vec3(-kappa * kFaceArea * d, 0, 0)).norm(), 1e-6 * kappa * kFaceArea * d)
        << Vec3(rep[0].value).transpose();
    EXPECT_NEAR(rep[2].value[0], d, 1e-12);              // max penetration (behind b's −x face, its nearest)
    EXPECT_NEAR(rep[3].value[0], kFaceArea, 1e-12);      // contact area (each side's, averaged)
    ASSERT_EQ(rep[4].name, "max_plane_gap");
    EXPECT_NEAR(rep[4].value[0], d, 1e-12);
  }
}

TEST(SkinContact, ASampleThatSlidesOffTheOtherSkinWithinTheStepIsNotCountedAsPenetrating) {
  // The pairs are made with b beside a, 1 mm of overlap. Over the step b
  // moves 2 mm further in along −x and 13 cm up along +y: the lagged planes
  // (b's −x face, moving with b) put a's +x face 3 mm behind them, but b is
  // now above a (1 cm apart) and no sample is inside it, so the penetration is 0 while the
  // plane gap is 3 mm. Moving only 2 mm in, without the slide, both are 3 mm.
  const Avatar a = box(), b = box();
  const SkinContactTerm term(a, b, {});
  const Configuration qa = translated(a, Vec3::Zero());
  for (double up : {0.13, 0.0}) {
    std::vector<Bound> bodies = two_boxes(a, b, qa, translated(b, Vec3(0.079, 0, 0)), translated(b, Vec3(0.079, 0, 0)));
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx));
    bodies[1].q = translated(b, Vec3(0.077, up, 0));
    const auto rep = term.report(ctx, qa);
    ASSERT_EQ(rep[2].name, "max_penetration");
    ASSERT_EQ(rep[4].name, "max_plane_gap");
    EXPECT_NEAR(rep[4].value[0], 0.003, 1e-12) << "up " << up;
    EXPECT_NEAR(rep[2].value[0], up > 0 ? 0.0 : 0.003, 1e-12) << "up " << up;
  }
}

TEST(SkinContact, DerivativesMatchFiniteDifferencesAndTheForcesBalance) {
  // Two deformed boxes overlapping by a few millimetres at random bone poses and z.
  const Avatar a = box(), b = box();
  const SkinContactTerm term(a, b, {});
  std::mt19937 rng(3);
  Isometry shift = Isometry::Identity();
  shift.translation() = Vec3(0.076, 0.004, -0.002);
  const Configuration qa = near_rest(a, rng), qb = near_rest(b, rng, shift);
  std::vector<Bound> bodies = two_boxes(a, b, qa, qb, qb);
  StepContext ctx = bind_bodies(bodies, nullptr);
  const auto cache = begin_term_step(term, ctx);
  ASSERT_TRUE(term.active(ctx));
  const Derivatives got = analytic(term, ctx, bodies);
  ASSERT_GT(got.E, 0);
  // The pairs are fixed for the step and each gap is linear in the points: the
  // energy is piecewise quadratic in the points, so the differences are exact
  // up to the bones' rotation and round-off.
  EXPECT_LT(rel(got.grad, fd_gradient(term, ctx, bodies, 1e-7)), 1e-6);
  // Gauss–Newton: the Hessian is symmetric and PSD.
  EXPECT_LT((got.hess - got.hess.transpose()).norm(), 1e-12 * got.hess.norm());
  const Eigen::SelfAdjointEigenSolver<MatX> eig(got.hess);
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff());
  // Against second differences of the energy along random directions: equal
  // where no pair's gap changes sign and the points move linearly (z only).
  VecX u = VecX::Zero(got.grad.size());
  std::normal_distribution<double> n01;
  for (const Bound& bd : bodies)
    for (int i = bd.layout.z_offset(); i < bd.layout.end(); ++i) u[i] = n01(rng);
  u *= 1e-5 / u.norm();
  const double second = energy_at(term, ctx, bodies, u) - 2 * got.E + energy_at(term, ctx, bodies, -u);
  EXPECT_NEAR(second, u.dot(got.hess * u), 1e-3 * std::abs(u.dot(got.hess * u)));
  // Equal and opposite: a uniform translation v of both bodies' bones moves
  // every skin point by v, a rotation ω about the origin by ω × x, and neither
  // changes the energy: the summed bone gradients vanish.
  const auto [force, torque] = summed_bone_gradient(got.grad, bodies);
  EXPECT_LT(force.norm(), 1e-9 * got.grad.norm());
  EXPECT_LT(torque.norm(), 1e-9 * got.grad.norm());
}

TEST(SkinContact, FarApartNothingAndAFastApproachIsCaught) {
  const Avatar a = box(), b = box();
  const SkinContactTerm term(a, b, {});
  const Configuration qa = translated(a, Vec3::Zero());
  {  // 20 cm apart, at rest: inactive.
    std::vector<Bound> bodies = two_boxes(a, b, qa, translated(b, Vec3(0.28, 0, 0)), translated(b, Vec3(0.28, 0, 0)));
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    EXPECT_FALSE(term.active(ctx));
  }
  {  // At t 3 cm apart, having moved 4 cm in the last step: within its reach
     // (1 cm + 1.5 × 4 cm), so the pairs exist and an overlap at the end of the step counts.
    std::vector<Bound> bodies =
        two_boxes(a, b, qa, translated(b, Vec3(0.078, 0, 0)), translated(b, Vec3(0.11, 0, 0)));
    bodies[1].q_prev2 = translated(b, Vec3(0.15, 0, 0));
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx));
    EXPECT_NEAR(analytic(term, ctx, bodies).E, 0.5 * kDefaultPressureStiffness * kFaceArea * 0.002 * 0.002, 1e-6);
  }
}

TEST(SkinContact, TwoFreeBodiesCollideAndKeepTheirMomentum) {
  // Box b drifts at 1 m/s (−x) into box a, 1 cm away; no gravity, no motion,
  // Newton to convergence. Over the impact (the first steps: the boxes end
  // up moving together) skin contact is internal: the total linear momentum
  // stays, b slows down and a starts moving, and b stays on its side.
  ModelOptions mo;
  mo.h = kH;
  mo.gravity = Vec3::Zero();
  mo.newton.iterations = 20;
  mo.newton.gradient_tolerance = 1e-10;
  mo.newton.line_search = true;
  ModelBuilder mb(mo);
  const auto avatar = std::make_shared<const Avatar>(box());
  const int a = mb.add_body({"a", avatar, true}), b = mb.add_body({"b", avatar, true});
  for (int body : {a, b}) {
    add_soft_tissue_terms(mb, body, {true, 0.0});
    SkeletonTermsOptions sk;
    sk.body_mass = 2.0;
    sk.tracking = false;  // external: would take momentum
    sk.joint_limits = false;
    add_skeleton_terms(mb, body, sk);
  }
  mb.add_term(std::make_shared<const SkinContactTerm>(*avatar, *avatar), {a, b});
  Simulator sim(mb.build());
  State s = sim.scene_state();
  for (Isometry& G : s.bodies[b].q.bones) G = Isometry(Eigen::Translation3d(0.09, 0, 0));
  s.bodies[b].q_prev = s.bodies[b].q;
  for (Isometry& G : s.bodies[b].q_prev.bones) G.translation() += Vec3(1.0 * kH, 0, 0);  // moving at −1 m/s
  sim.set_state(s);
  StepInputs in;
  in.bodies.resize(2);
  for (auto& body : in.bodies) body.bones = identity_bones();  // no tracking: the targets are unused
  const Vec3 p0 = linear_momentum(sim.model(), sim.scene_state());
  ASSERT_LT(p0.x(), 0);
  double deepest = 0, closest = 1;
  for (int i = 0; i < 4; ++i) {
    const StepReport rep = sim.step(in);
    for (const TermQuantityReport& q : rep.quantities)
      if (q.term == "skin_contact" && q.name == "max_penetration") deepest = std::max(deepest, q.value[0]);
    closest = std::min(closest, sim.state(b).bones[0].translation().x() - sim.state(a).bones[0].translation().x());
  }
  EXPECT_GT(deepest, 0);  // they touched
  const Vec3 p1 = linear_momentum(sim.model(), sim.scene_state());
  EXPECT_LT((p1 - p0).norm(), 1e-6 * p0.norm()) << "p0 " << p0.transpose() << ", p1 " << p1.transpose();
  const double va = (sim.state(a).bones[0].translation() - sim.previous_state(a).bones[0].translation()).x() / kH;
  const double vb = (sim.state(b).bones[0].translation() - sim.previous_state(b).bones[0].translation()).x() / kH;
  EXPECT_LT(va, -0.3);        // a was pushed along −x
  EXPECT_GT(vb, -0.7);        // b slowed down
  EXPECT_GT(closest, 0.078);  // the boxes are 8 cm wide: b stayed on its side
}

TEST(SkinContact, BadOptionsAreRefusedInOneLine) {
  const Avatar a = box(), b = box();
  auto with = [](double kappa, double spacing, double max_depth) {
    SkinContactOptions o;
    o.pressure_stiffness = kappa;
    o.spacing = spacing;
    o.max_depth = max_depth;
    return o;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  test::expect_error([&] { SkinContactTerm(a, b, with(0, 0.01, 0.05)); }, {"skin contact", "pressure stiffness"});
  test::expect_error([&] { SkinContactTerm(a, b, with(nan, 0.01, 0.05)); }, {"skin contact", "pressure stiffness"});
  test::expect_error([&] { SkinContactTerm(a, b, with(1e8, -0.01, 0.05)); }, {"skin contact", "spacing"});
  test::expect_error([&] { SkinContactTerm(a, b, with(1e8, 0.01, 0)); }, {"skin contact", "max depth"});
}

}  // namespace
