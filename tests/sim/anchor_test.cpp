// Anchor term: energy against its closed form, gradient against
// central differences, Gauss–Newton Hessian against (k + c/h) Σ DᵀD with
// D = ∂(x_p − a_p)/∂δ by finite differences of world points (independent of
// the term's Jacobian code), for a kinematic tool frame and a dynamic tool
// body, with the flesh's bones dynamic and kinematic; forces on flesh and
// tool equal and opposite.
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <random>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"

using namespace sflsh;

namespace {

constexpr double kStep = 1.0 / 120.0;

Avatar flesh_box() {
  test::SyntheticAvatarOptions o;
  o.handles = 6;
  o.handle_radius = 0.1;
  o.all_tets = false;
  o.samples = 8;
  Avatar a = test::make_synthetic_avatar(o);
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  return a;
}

Isometry random_pose(std::mt19937& rng, double angle, double shift) {
  std::normal_distribution<double> n;
  Isometry G = Isometry::Identity();
  G.linear() = Eigen::AngleAxisd(angle * n(rng), Vec3(n(rng), n(rng), n(rng)).normalized()).toRotationMatrix();
  G.translation() = shift * Vec3(n(rng), n(rng), n(rng));
  return G;
}

Configuration perturbed(const Avatar& a, std::mt19937& rng, double scale) {
  Configuration q;
  for (int j = 0; j < 24; ++j) q.bones.push_back(random_pose(rng, 0.05 * scale, 0.004 * scale));
  std::uniform_real_distribution<double> u(-0.005 * scale, 0.005 * scale);
  q.z = VecX::NullaryExpr(a.num_reduced(), [&](Eigen::Index) { return u(rng); });
  return q;
}

/// The flesh (body 0) and, optionally, a dynamic tool (body 1): q, q_t, q_{t−h} and layouts.
struct Rig {
  const Avatar* avatar = nullptr;
  std::vector<DofLayout> layouts;
  std::vector<Configuration> q, q_prev, q_prev2;
  std::vector<AnchorPoint> anchors;  ///< the anchor term's set for the step

  int size() const { return layouts.back().end(); }
  StepContext context() const {
    StepContext ctx;
    ctx.avatar = avatar;
    ctx.layout = layouts[0];
    ctx.h = kStep;
    ctx.q_prev = q_prev[0];
    ctx.q_prev2 = q_prev2[0];
    ctx.anchors = &anchors;
    for (size_t i = 0; i < layouts.size(); ++i)
      ctx.bound.push_back({int(i), int(i), i == 0 ? avatar : nullptr, layouts[i], &q[i], &q_prev[i], &q_prev2[i]});
    return ctx;
  }
  /// The rig's q retracted by the step δ (all bodies).
  std::vector<Configuration> moved(const VecX& delta) const {
    std::vector<Configuration> out;
    for (size_t i = 0; i < q.size(); ++i) out.push_back(retract(q[i], delta, layouts[i]));
    return out;
  }
};

Rig make_rig(const Avatar& a, bool bones_dynamic, bool dynamic_tool, std::mt19937& rng) {
  Rig r;
  r.avatar = &a;
  DofLayout L;
  L.bones_dynamic = bones_dynamic;
  L.num_reduced = a.num_reduced();
  L.bone_pivots = a.joints_rest;
  r.layouts.push_back(L);
  r.q_prev.push_back(perturbed(a, rng, 1.0));
  r.q_prev2.push_back(r.q_prev[0]);
  r.q.push_back(perturbed(a, rng, 1.0));
  if (dynamic_tool) {
    DofLayout T;
    T.num_bones = 1;
    T.num_reduced = 0;
    T.bone_pivots = Points::Zero(1, 3);
    T.base = L.size();
    r.layouts.push_back(T);
    Configuration g;
    g.bones = {random_pose(rng, 0.3, 0.02)};
    g.bones[0].translation() += Vec3(0.0, 0.15, 0.0);
    g.z = VecX(0);
    r.q_prev.push_back(g);
    r.q_prev2.push_back(g);
    g.bones[0] = random_pose(rng, 0.02, 0.003) * g.bones[0];
    r.q.push_back(g);
  }
  return r;
}

/// Anchors on a few skin vertices at their position at time t plus a few mm, in the tool frame `T`.
std::vector<Anchor> make_anchors(const PosedPoints& P, const Configuration& q_t, const Isometry& T, std::mt19937& rng) {
  std::normal_distribution<double> n;
  std::vector<Anchor> out;
  for (int p : {0, 7, 19, P.size() - 1}) {
    const Vec3 x = P.world_point(p, q_t) + 0.004 * Vec3(n(rng), n(rng), n(rng));
    out.push_back({p, T.inverse() * x});
  }
  return out;
}

struct Check {
  double E = 0, E_closed_form = 0, grad_err = 0, hess_err = 0;
  VecX grad;
  std::vector<TermQuantity> report;
};

/// Evaluates the term on the rig against closed forms and finite differences.
/// `tool_at(δ)`: the tool points a_p (world) at the retracted iterate, `tool_t`: at time t.
Check check_term(const AnchorTerm& term, Rig& rig, const std::vector<Anchor>& anchors,
                 const std::function<Vec3(const std::vector<Configuration>&, int)>& tool_at,
                 const std::vector<Vec3>& tool_t, double k, double c) {
  StepContext ctx = rig.context();
  const auto cache = begin_term_step(term, ctx);
  EXPECT_TRUE(term.active(ctx));
  const PosedPoints& P = term.points();
  const int n = rig.size();
  Check out;
  out.grad = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  out.E = term.evaluate(ctx, rig.q[0], &out.grad, &H);
  // Energy and the stretch vectors r_p(δ) = x_p − a_p, straight from world points.
  auto energy = [&](const VecX& delta) {
    const std::vector<Configuration> q = rig.moved(delta);
    StepContext c2 = ctx;
    for (size_t i = 0; i < q.size(); ++i) c2.bound[i].q = &q[i];
    return term.evaluate(c2, q[0], nullptr, nullptr);
  };
  auto stretch = [&](const VecX& delta, int i) {
    const std::vector<Configuration> q = rig.moved(delta);
    return Vec3(P.world_point(anchors[i].point, q[0]) - tool_at(q, i));
  };
  for (size_t i = 0; i < anchors.size(); ++i) {
    const Vec3 r = stretch(VecX::Zero(n), int(i));
    const Vec3 d = r - (P.world_point(anchors[i].point, rig.q_prev[0]) - tool_t[i]);
    out.E_closed_form += 0.5 * k * r.squaredNorm() + 0.5 * (c / kStep) * d.squaredNorm();
  }
  VecX g(n);
  MatX H_gn = MatX::Zero(n, n);
  std::vector<MatX> D(anchors.size(), MatX(3, n));
  const double eps = 1e-7;
  for (int j = 0; j < n; ++j) {
    VecX e = VecX::Zero(n);
    e[j] = eps;
    g[j] = (energy(e) - energy(-e)) / (2 * eps);
    for (size_t i = 0; i < anchors.size(); ++i) D[i].col(j) = (stretch(e, int(i)) - stretch(-e, int(i))) / (2 * eps);
  }
  for (const MatX& Di : D) H_gn += (k + c / kStep) * Di.transpose() * Di;
  out.grad_err = (out.grad - g).norm() / g.norm();
  out.hess_err = (H - H_gn).norm() / H_gn.norm();
  out.report = term.report(ctx, rig.q[0]);
  return out;
}

VecX quantity(const std::vector<TermQuantity>& r, const std::string& name) {
  for (const TermQuantity& q : r)
    if (q.name == name) return q.value;
  ADD_FAILURE() << "no quantity " << name;
  return Vec3::Zero();
}

TEST(AnchorTerm, KinematicToolMatchesClosedFormAndFiniteDifferences) {
  const Avatar a = flesh_box();
  const double k = 2.0e3, c = 3.0;
  const AnchorTerm term("jaw", PosedPoints::at_surface(a), false, {k, c});
  for (bool bones_dynamic : {true, false}) {
    std::mt19937 rng(bones_dynamic ? 11 : 12);
    Rig rig = make_rig(a, bones_dynamic, false, rng);
    WorldFrame jaw;
    jaw.pose = random_pose(rng, 0.5, 0.05);
    jaw.angular_velocity = Vec3(0.4, -1.0, 0.3);
    jaw.linear_velocity = Vec3(0.05, 0.2, -0.1);
    const std::vector<Anchor> anchors = make_anchors(term.points(), rig.q_prev[0], jaw.pose, rng);
    anchor_points(jaw, anchors, false, rig.anchors);
    // Tool points by hand: a = T o; at t, carried back by the frame's twist.
    std::vector<Vec3> a_next, a_t;
    for (const Anchor& an : anchors) {
      const Vec3 p = jaw.pose * an.offset;
      a_next.push_back(p);
      a_t.push_back(p - kStep * (jaw.linear_velocity + jaw.angular_velocity.cross(p - jaw.pose.translation())));
    }
    const Check ch = check_term(term, rig, anchors, [&](const std::vector<Configuration>&, int i) { return a_next[i]; },
                                a_t, k, c);
    ASSERT_GT(ch.E, 0);
    EXPECT_NEAR(ch.E, ch.E_closed_form, 1e-12 * ch.E_closed_form);
    EXPECT_LT(ch.grad_err, 1e-6) << "bones dynamic " << bones_dynamic;
    EXPECT_LT(ch.hess_err, 1e-6) << "bones dynamic " << bones_dynamic;
  }
}

TEST(AnchorTerm, DynamicToolGetsTheOppositeForceAndMatchesFiniteDifferences) {
  const Avatar a = flesh_box();
  const double k = 5.0e3, c = 2.0;
  const AnchorTerm term("gripper", PosedPoints::at_surface(a), true, {k, c});
  for (bool bones_dynamic : {true, false}) {
    std::mt19937 rng(bones_dynamic ? 21 : 22);
    Rig rig = make_rig(a, bones_dynamic, true, rng);
    const Isometry G_t = rig.q_prev[1].bones[0];
    const std::vector<Anchor> anchors = make_anchors(term.points(), rig.q_prev[0], G_t, rng);
    WorldFrame body_t;
    body_t.pose = G_t;
    anchor_points(body_t, anchors, true, rig.anchors);
    std::vector<Vec3> a_t;
    for (const Anchor& an : anchors) a_t.push_back(G_t * an.offset);
    const Check ch = check_term(
        term, rig, anchors,
        [&](const std::vector<Configuration>& q, int i) { return Vec3(q[1].bones[0] * anchors[i].offset); }, a_t, k,
        c);
    ASSERT_GT(ch.E, 0);
    EXPECT_NEAR(ch.E, ch.E_closed_form, 1e-12 * ch.E_closed_form);
    EXPECT_LT(ch.grad_err, 1e-6) << "bones dynamic " << bones_dynamic;
    EXPECT_LT(ch.hess_err, 1e-6) << "bones dynamic " << bones_dynamic;
    // The force on the tool is −∂E/∂v_tool; on the flesh, the reported force.
    const Vec3 on_flesh = quantity(ch.report, "force");
    const Vec3 on_tool = -ch.grad.segment<3>(rig.layouts[1].base + 3);
    EXPECT_GT(on_flesh.norm(), 1.0);
    EXPECT_LT((on_flesh + on_tool).norm(), 1e-9 * on_flesh.norm()) << on_flesh.transpose() << " | " << on_tool.transpose();
    if (bones_dynamic) {
      // Momentum: the translation gradients of all bones and the tool sum to zero.
      Vec3 total = -on_tool;
      for (int j = 0; j < 24; ++j) total += ch.grad.segment<3>(rig.layouts[0].bone_offset(j) + 3);
      EXPECT_LT(total.norm(), 1e-9 * on_flesh.norm());
    }
  }
}

TEST(AnchorTerm, ReportsPerAnchorForcesAndIsInactiveWithoutAnchors) {
  const Avatar a = flesh_box();
  const double k = 1.0e3;
  const AnchorTerm term("jaw", PosedPoints::at_surface(a), false, {k, 0.0});
  std::mt19937 rng(5);
  Rig rig = make_rig(a, true, false, rng);
  rig.q[0] = rig.q_prev[0];
  StepContext ctx = rig.context();
  auto cache = begin_term_step(term, ctx);
  EXPECT_FALSE(term.active(ctx));
  // One anchor pulled 2 mm along +y from vertex 3: force k·2 mm along +y.
  WorldFrame jaw;
  jaw.pose.translation() = Vec3(0.01, 0.02, 0.03);
  const Vec3 x3 = term.points().world_point(3, rig.q[0]);
  anchor_points(jaw, {{3, jaw.pose.inverse() * (x3 + Vec3(0, 0.002, 0))}}, false, rig.anchors);
  ctx = rig.context();
  cache = begin_term_step(term, ctx);
  ASSERT_TRUE(term.active(ctx));
  const std::vector<TermQuantity> rep = term.report(ctx, rig.q[0]);
  EXPECT_LT((quantity(rep, "force") - Vec3(0, k * 0.002, 0)).norm(), 1e-9);
  EXPECT_LT((quantity(rep, "anchor_forces") - Vec3(0, k * 0.002, 0)).norm(), 1e-9);
  EXPECT_NEAR(quantity(rep, "max_stretch")[0], 0.002, 1e-12);
  // Re-arming replaces the previous anchors; a bad point index is one clear error.
  anchor_points(jaw, {}, false, rig.anchors);
  EXPECT_TRUE(rig.anchors.empty());
  ctx = rig.context();
  cache = begin_term_step(term, ctx);
  EXPECT_FALSE(term.active(ctx));
  rig.anchors = {AnchorPoint{100000, Vec3::Zero(), Vec3::Zero()}};
  ctx = rig.context();
  EXPECT_THROW(begin_term_step(term, ctx), Error);
  rig.anchors = {AnchorPoint{-1, Vec3::Zero(), Vec3::Zero()}};
  ctx = rig.context();
  EXPECT_THROW(begin_term_step(term, ctx), Error);
  EXPECT_THROW(AnchorTerm("jaw", PosedPoints::at_surface(a), false, {0.0, 1.0}), Error);
}

}  // namespace

TEST(AnchorTerm, MaxStretchIsTheLargestAnchorsNotTheLastOnes) {
  // Two anchors: vertex 3 pulled 3 mm along +y, vertex 5 pulled 1 mm along +x
  // (vertex 5's frame comes last): max_stretch 3 mm, the total force the sum.
  const Avatar a = flesh_box();
  const double k = 1.0e3;
  const AnchorTerm term("jaw", PosedPoints::at_surface(a), false, {k, 0.0});
  std::mt19937 rng(5);
  Rig rig = make_rig(a, true, false, rng);
  rig.q[0] = rig.q_prev[0];
  WorldFrame jaw;
  jaw.pose.translation() = Vec3(0.01, 0.02, 0.03);
  const Vec3 x3 = term.points().world_point(3, rig.q[0]), x5 = term.points().world_point(5, rig.q[0]);
  anchor_points(jaw,
                {{3, jaw.pose.inverse() * (x3 + Vec3(0, 0.003, 0))}, {5, jaw.pose.inverse() * (x5 + Vec3(0.001, 0, 0))}},
                false, rig.anchors);
  StepContext ctx = rig.context();
  auto cache = begin_term_step(term, ctx);
  const std::vector<TermQuantity> rep = term.report(ctx, rig.q[0]);
  EXPECT_NEAR(quantity(rep, "max_stretch")[0], 0.003, 1e-12);
  EXPECT_LT((quantity(rep, "force") - Vec3(k * 0.001, k * 0.003, 0)).norm(), 1e-9);
}
