// Friction of the patch's face-sampled contact (sim/energies/contact_patch.hpp,
// "Friction"): sliding and sticking forces by hand (μ × the pressure's force,
// the mollifier's share below the static slip), the condensed energy's
// gradient against finite differences with a kinematic and a dynamic object,
// the reaction on a dynamic object, and a slab that friction holds on an
// incline below its friction angle only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sim/energies/contact_patch_cache.hpp"
#include "contact_patch_bordered.hpp"
#include "sim/incline_fixture.hpp"
#include "sim/two_body_fixture.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using test::two_body::box;
using test::two_body::kH;

StepContext context(const Avatar& a, const std::map<std::string, WorldFrame>* frames, bool bones_dynamic) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.layout.bones_dynamic = bones_dynamic;
  ctx.h = kH;
  ctx.gravity = Vec3::Zero();
  ctx.q_prev.bones = identity_bones();
  ctx.q_prev.z = VecX::Zero(a.num_reduced());
  ctx.q_prev2 = ctx.q_prev;
  if (frames)
    for (const auto& [name, f] : *frames) ctx.frames.push_back(&f);
  return ctx;
}

Vec3 quantity3(const std::vector<TermQuantity>& r, const std::string& name) {
  for (const TermQuantity& q : r)
    if (q.name == name) return q.value.head<3>();
  ADD_FAILURE() << "no quantity " << name;
  return Vec3::Constant(NAN);
}

TEST(ContactPatchFriction, SlidingFrictionIsMuTimesThePressuresForceAndStickingItsMollifiedShare) {
  // The box's skin reduced to its top face (y = 3 cm, 6 cm × 6 cm), a
  // half-space 0.7 mm into it that moves along +x at speed v: every sample
  // is 0.7 mm deep (normal force κ δ A in all) and, with the body at rest,
  // slips by h v against the floor over the step. Sliding (h v ≫ ε = 1e-3 h)
  // the floor drags the body by μ κ δ A along +x; at h v = ε/2 the mollifier
  // gives f1(ε/2) = 2·½ − ¼ = ¾ of it.
  Avatar a = box(0, 6, 0.01);
  std::vector<int> top;
  for (int f = 0; f < a.surface_faces.rows(); ++f) {
    bool on_top = true;
    for (int i = 0; i < 3; ++i) on_top = on_top && a.surface_rest(a.surface_faces(f, i), 1) > 0.03 - 1e-9;
    if (on_top) top.push_back(f);
  }
  a.surface_faces = Triangles(a.surface_faces(top, Eigen::all));
  ASSERT_EQ(int(top.size()), 2 * 6 * 6);
  const double kappa = 3.0e7, depth = 0.0007, area = 0.06 * 0.06, mu = 0.4;
  const double normal = kappa * depth * area;
  for (const auto& [speed, share] : {std::pair{0.3, 1.0}, std::pair{0.5e-3, 0.75}}) {
    std::map<std::string, WorldFrame> frames;
    WorldFrame& floor = frames["floor"];
    floor.pose.linear() = Eigen::AngleAxisd(M_PI, Vec3::UnitX()).toRotationMatrix();  // normal −y
    floor.pose.translation() = Vec3(0, 0.03 - depth, 0);
    floor.linear_velocity = Vec3(speed, 0, 0);
    ContactPatchOptions o;
    o.pressure_stiffness = kappa;
    o.spacing = 0.004;
    o.patch = false;
    o.friction = mu;
    const ContactPatchTerm term("floor", a, std::make_shared<geometry::PlaneSdf>(Vec3(0, 1, 0), 0.0),
                                Isometry::Identity(), false, o);
    StepContext ctx = context(a, &frames, false);
    const auto cache = begin_term_step(term, ctx);
    const auto r = term.report(ctx, ctx.q_prev);
    const Vec3 friction = quantity3(r, "friction_force"), force = quantity3(r, "force");
    EXPECT_NEAR(friction.x(), share * mu * normal, 1e-9 * normal) << speed;
    EXPECT_NEAR(friction.y(), 0.0, 1e-12) << speed;
    EXPECT_NEAR(friction.z(), 0.0, 1e-12) << speed;
    EXPECT_NEAR(force.y(), -normal, 1e-9 * normal) << speed;
    EXPECT_NEAR(force.x(), friction.x(), 1e-12) << "the force holds its friction part";
    // The energy adds μ κ a δ f0(h v) per sample: f0 = z beyond ε.
    if (share == 1.0) {
      o.friction = 0;
      const ContactPatchTerm frictionless("floor", a, std::make_shared<geometry::PlaneSdf>(Vec3(0, 1, 0), 0.0),
                                          Isometry::Identity(), false, o);
      StepContext ctx0 = context(a, &frames, false);
      const auto cache0 = begin_term_step(frictionless, ctx0);
      EXPECT_NEAR(term.evaluate(ctx, ctx.q_prev, nullptr, nullptr) -
                      frictionless.evaluate(ctx0, ctx0.q_prev, nullptr, nullptr),
                  mu * normal * kH * speed, 1e-9 * mu * normal * kH * speed);
    }
  }
}

/// A 1.2 cm ball's patch on the box's top with friction μ, minimized to round-off.
ContactPatchOptions ball_options(double mu) {
  ContactPatchOptions o;
  o.pressure_stiffness = 2.0e7;
  o.spacing = 0.003;
  o.patch_radius = 0.015;
  o.inner_tolerance = 1e-13;
  o.friction = mu;
  return o;
}

TEST(ContactPatchFriction, CondensedEnergyGradientMatchesFiniteDifferencesWhileSlidingAndSticking) {
  // A 1.2 cm ball 1.5 mm into the box's top with its patch, moving along the
  // skin (sliding, slip ≫ ε) or barely (sticking, slip < ε); the body's
  // subspace displaced so that every piece is non-trivial.
  const Avatar a = box(6, 6, 0.01);
  for (double speed : {0.05, 0.2e-3}) {
    std::map<std::string, WorldFrame> frames;
    frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - 0.0015, -0.003);
    frames["ball"].linear_velocity = Vec3(speed, 0, -0.5 * speed);
    const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false,
                                ball_options(0.6));
    for (bool dynamic : {false, true}) {
      SCOPED_TRACE(std::string(dynamic ? "bones dynamic" : "bones kinematic") + ", speed " + std::to_string(speed));
      StepContext ctx = context(a, &frames, dynamic);
      Configuration q = ctx.q_prev;
      for (int i = 0; i < q.z.size(); ++i) q.z[i] = 5e-4 * std::sin(1.7 * i + 0.3);
      ctx.q_prev2.z = -0.5 * q.z;
      const auto cache = begin_term_step(term, ctx);
      ASSERT_FALSE(term.patch_nodes(ctx).empty());
      const auto& c = contact_patch_detail::patch_cache(ctx, term.name());
      ASSERT_GT(*std::max_element(c.friction_bound.begin(), c.friction_bound.end()), 0) << "no sample with friction";
      const int n = ctx.layout.size();
      VecX g = VecX::Zero(n);
      ASSERT_GT(term.evaluate(ctx, q, &g, nullptr), 0);
      const VecX fd = test::fd_gradient(term, ctx, q, 1e-7);
      EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "|g| " << g.norm() << ", |fd| " << fd.norm();
      VecX g_alone = VecX::Zero(n), g_with_hessian = VecX::Zero(n);
      MatX H = MatX::Zero(n, n);
      term.evaluate(ctx, q, &g_alone, nullptr);
      term.evaluate(ctx, q, &g_with_hessian, &H);
      const VecX bordered =
          test::bordered_rhs_difference(contact_patch_detail::patch_cache(ctx, term.name()), ctx.layout.z_offset(), n);
      EXPECT_LT((g_with_hessian - g_alone - bordered).norm(), 1e-12 * g_alone.norm());
    }
  }
}

TEST(ContactPatchFriction, ADynamicObjectGetsTheOppositeFrictionAndItsDerivativesMatchFiniteDifferences) {
  // The ball as a rigid body bound second, moved 0.5 mm along +x over the
  // step: the flesh it touched at t is dragged along (the friction is ahead
  // of the ball's motion on the body, behind it on the ball).
  const Avatar a = box(6, 6, 0.01);
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), true,
                              ball_options(0.5));
  using test::two_body::Bound;
  Configuration ball;
  ball.bones = {Isometry::Identity()};
  ball.bones[0].translation() = Vec3(0.004, 0.03 + 0.012 - 0.0015, -0.003);
  ball.z = VecX();
  Configuration ball_prev = ball;
  ball_prev.bones[0].translation().x() -= 0.0005;
  std::vector<Bound> bodies{{&a, test::two_body::body_layout(a, true), {}, {}, {}},
                            {nullptr, test::two_body::rigid_layout(0), ball, ball_prev, ball_prev}};
  bodies[1].layout.base = bodies[0].layout.size();
  bodies[0].q_prev.bones = identity_bones();
  bodies[0].q_prev.z = VecX::Zero(a.num_reduced());
  bodies[0].q_prev2 = bodies[0].q_prev;
  bodies[0].q = bodies[0].q_prev;
  for (int i = 0; i < a.num_reduced(); ++i) bodies[0].q.z[i] = 4e-4 * std::sin(1.3 * i + 0.2);
  StepContext ctx = test::two_body::bind_bodies(bodies, nullptr);
  const auto cache = begin_term_step(term, ctx);
  ASSERT_FALSE(term.patch_nodes(ctx).empty());
  const Configuration& q = bodies[0].q;
  const int n = test::two_body::total_size(bodies);
  VecX g = VecX::Zero(n);
  ASSERT_GT(term.evaluate(ctx, q, &g, nullptr), 0);
  const VecX fd = test::two_body::fd_gradient(term, ctx, bodies, 1e-7);
  EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "|g| " << g.norm() << ", |fd| " << fd.norm();
  // The ball's generalized force along v is the reaction of the whole force
  // on the body (pressure and friction), and the friction drags the flesh
  // along the ball's motion (+x).
  const auto r = term.report(ctx, q);
  const Vec3 f = quantity3(r, "force"), friction = quantity3(r, "friction_force");
  EXPECT_GT(friction.x(), 0.05 * f.norm()) << friction.transpose();
  EXPECT_LT((g.segment<3>(bodies[1].layout.base + 3) - f).norm(), 1e-6 * f.norm());
}

/// The slab on an incline (incline_fixture.hpp) held through the patch with friction μ.
Vec3 slab_on_incline(double tilt, double mu) {
  return test::slab_on_incline(tilt, [mu](const Avatar& a, const Vec3& half) {
    ContactPatchOptions o;
    o.pressure_stiffness = 1.0e8;
    o.spacing = 0.005;
    o.patch_radius = 0.015;
    o.friction = mu;
    return std::make_shared<const ContactPatchTerm>("slab", a, std::make_shared<geometry::BoxSdf>(half),
                                                    Isometry::Identity(), true, o);
  });
}

TEST(ContactPatchFriction, FrictionHoldsASlabOnAnInclineBelowItsFrictionAngleOnly) {
  // 15° incline: tan = 0.27. μ = 0.5 holds the slab (the flesh under it
  // shears a little); μ = 0.1 lets it slide, ½ g (sin θ − μ cos θ) t² = 0.79 m
  // in 1 s if nothing stopped it.
  const double tilt = 15 * M_PI / 180;
  const Vec3 stuck = slab_on_incline(tilt, 0.5), slid = slab_on_incline(tilt, 0.1);
  EXPECT_LT(std::abs(stuck.x()), 2e-3) << "held by friction: " << stuck.transpose();
  EXPECT_GT(slid.x(), 0.02) << "should slide: " << slid.transpose();
}

}  // namespace
}  // namespace sflsh
