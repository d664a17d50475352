// Contact terms: SDF contact of skin samples against static and
// dynamic rigid objects, bone-capsule contact between bodies. Gradients
// against finite differences through the embedded-sample chain rule (bones
// and z), Gauss–Newton Hessians against k Σ j jᵀ with j = ∂d/∂δ by finite
// differences, the broad phase against brute force, momentum balance of the
// forces, and the equilibrium / momentum figures on a small body.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "sflsh/core/rotation.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/sim/energies/capsule_contact.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/sim/momentum.hpp"
#include "sflsh/sim/rigid_body_terms.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"
#include "sim/incline_fixture.hpp"
#include "sim/two_body_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;
using namespace sflsh::test::two_body;

namespace {


TEST(SdfContact, GradientAndHessianAgainstAStaticSphereMatchFiniteDifferences) {
  const Avatar a = box();
  auto sphere = std::make_shared<geometry::SphereSdf>(0.05);
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.01, 0.12 + 0.05 - 0.015, 0.005);  // 1.5 cm into the top
  const double k = 3.0e4;
  SdfContactOptions o;
  o.stiffness = k;
  const SdfContactTerm term("ball", PosedPoints::at_surface(a), sphere, Isometry::Identity(), false, o);
  for (bool dynamic : {true, false}) {
    std::mt19937 rng(dynamic ? 3 : 4);
    std::vector<Bound> bodies{{&a, body_layout(a, dynamic), {}, {}, {}}};
    bodies[0].q = near_rest(a, rng);
    bodies[0].q_prev = bodies[0].q_prev2 = bodies[0].q;
    StepContext ctx = bind_bodies(bodies, &frames);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx));
    const Derivatives d = analytic(term, ctx, bodies);
    ASSERT_GT(d.E, 0);
    // The value by hand: ½ k (r − |x − c|)² over the skin points inside the ball.
    double by_hand = 0;
    for (int p = 0; p < term.samples().size(); ++p) {
      const double depth = 0.05 - (term.samples().world_point(p, bodies[0].q) - frames["ball"].pose.translation()).norm();
      if (depth > 0) by_hand += 0.5 * k * depth * depth;
    }
    EXPECT_NEAR(d.E, by_hand, 1e-12 * by_hand);
    EXPECT_LT(rel(d.grad, fd_gradient(term, ctx, bodies, 1e-7)), 1e-6) << "bones dynamic " << dynamic;
    // Gauss–Newton: k Σ j jᵀ over the penetrating samples, j by finite differences of φ.
    const int n = total_size(bodies);
    MatX H = MatX::Zero(n, n);
    const PosedPoints& P = term.samples();
    for (int p = 0; p < P.size(); ++p) {
      const Vec3 c = frames["ball"].pose.translation();
      auto phi = [&](const VecX& delta) {
        return (P.world_point(p, retract(bodies[0].q, delta, bodies[0].layout)) - c).norm() - 0.05;
      };
      if (phi(VecX::Zero(n)) >= 0) continue;
      VecX j(n);
      for (int i = 0; i < n; ++i) {
        VecX e = VecX::Zero(n);
        e[i] = 1e-7;
        j[i] = (phi(e) - phi(-e)) / 2e-7;
      }
      H += k * j * j.transpose();
    }
    EXPECT_LT((d.hess - H).norm() / H.norm(), 1e-6) << "bones dynamic " << dynamic;
  }
}

TEST(SdfContact, ADynamicObjectGetsTheOppositeForceAndTheChainRuleThroughItsPose) {
  const Avatar a = box();
  auto cube = std::make_shared<geometry::BoxSdf>(Vec3(0.03, 0.02, 0.05));
  const double k = 2.0e4;
  SdfContactOptions o;
  o.stiffness = k;
  // The box's shape frame sits off its body frame: exercises shape_in_frame.
  Isometry shape_in_frame = Isometry::Identity();
  shape_in_frame.translation() = Vec3(0.004, -0.002, 0.001);
  shape_in_frame.linear() = Eigen::AngleAxisd(0.2, Vec3(0, 0, 1)).toRotationMatrix();
  const SdfContactTerm term("lid", PosedPoints::at_surface(a), cube, shape_in_frame, true, o);
  std::mt19937 rng(7);
  std::vector<Bound> bodies{{&a, body_layout(a, true), {}, {}, {}}, {nullptr, rigid_layout(0), {}, {}, {}}};
  bodies[1].layout.base = bodies[0].layout.size();
  bodies[0].q = near_rest(a, rng);
  Isometry G = Isometry::Identity();
  G.linear() = Eigen::AngleAxisd(0.15, Vec3(1, 0, 0.3).normalized()).toRotationMatrix();
  G.translation() = Vec3(0.01, 0.12 + 0.02 - 0.01, 0.0);
  bodies[1].q.bones = {G};
  bodies[1].q.z = VecX(0);
  for (Bound& b : bodies) b.q_prev = b.q_prev2 = b.q;
  StepContext ctx = bind_bodies(bodies, nullptr);
  const auto cache = begin_term_step(term, ctx);
  ASSERT_TRUE(term.active(ctx));
  const Derivatives d = analytic(term, ctx, bodies);
  ASSERT_GT(d.E, 0);
  EXPECT_LT(rel(d.grad, fd_gradient(term, ctx, bodies, 1e-7)), 1e-6);
  // Momentum: a common translation of both bodies changes nothing, so the
  // translational gradients sum to zero (equal and opposite forces).
  Vec3 sum = d.grad.segment<3>(bodies[1].layout.bone_offset(0) + 3);
  for (int j = 0; j < 24; ++j) sum += d.grad.segment<3>(bodies[0].layout.bone_offset(j) + 3);
  EXPECT_LT(sum.norm(), 1e-9 * d.grad.norm());
  // The Hessian is PSD and symmetric.
  EXPECT_LT((d.hess - d.hess.transpose()).norm(), 1e-12 * d.hess.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(d.hess).eigenvalues().minCoeff(), -1e-9 * d.hess.norm());
  // The reported force is what the box exerts on the body: −(translational gradient of the body).
  const auto rep = term.report(ctx, bodies[0].q);
  ASSERT_EQ(rep[0].name, "force");
  Vec3 body_force = Vec3::Zero();
  for (int j = 0; j < 24; ++j) body_force -= d.grad.segment<3>(bodies[0].layout.bone_offset(j) + 3);
  EXPECT_LT((rep[0].value - body_force).norm(), 1e-9 * body_force.norm());
  EXPECT_LT(rep[0].value[1], 0) << "the lid, above the body, pushes it down";
}

TEST(SdfContact, FrictionDerivativesMatchFiniteDifferencesWhileStickingAndSliding) {
  // A dynamic lid pressed into the top; the body at t − h was displaced
  // tangentially by `slip` from q (slip < ε: static spring; slip > ε: sliding).
  const Avatar a = box();
  auto cube = std::make_shared<geometry::BoxSdf>(Vec3(0.05, 0.02, 0.05));
  for (double slip : {2e-6, 1e-3}) {
    SdfContactOptions o;
    o.stiffness = 2.0e4;
    o.friction = 0.6;
    const SdfContactTerm with("lid", PosedPoints::at_surface(a), cube, Isometry::Identity(), true, o);
    o.friction = 0;
    const SdfContactTerm without("lid", PosedPoints::at_surface(a), cube, Isometry::Identity(), true, o);
    std::mt19937 rng(9);
    std::vector<Bound> bodies{{&a, body_layout(a, true), {}, {}, {}}, {nullptr, rigid_layout(0), {}, {}, {}}};
    bodies[1].layout.base = bodies[0].layout.size();
    bodies[0].q = near_rest(a, rng);
    bodies[0].q_prev = bodies[0].q;
    for (Isometry& G : bodies[0].q_prev.bones) G.translation() += Vec3(slip, 0, -0.5 * slip);
    bodies[0].q_prev2 = bodies[0].q_prev;
    Isometry G = Isometry::Identity();
    G.translation() = Vec3(0.003, 0.12 + 0.02 - 0.004, 0.001);
    bodies[1].q.bones = {G};
    bodies[1].q.z = VecX(0);
    bodies[1].q_prev = bodies[1].q_prev2 = bodies[1].q;
    StepContext ctx = bind_bodies(bodies, nullptr);
    auto cache = begin_term_step(with, ctx);
    const Derivatives dw = analytic(with, ctx, bodies);
    StepContext ctx0 = bind_bodies(bodies, nullptr);
    auto cache0 = begin_term_step(without, ctx0);
    const Derivatives d0 = analytic(without, ctx0, bodies);
    ASSERT_GT(dw.E, d0.E) << "no friction energy at slip " << slip;
    const double fd_eps = slip < 1e-5 ? 1e-8 : 1e-7;
    EXPECT_LT(rel(dw.grad, fd_gradient(with, ctx, bodies, fd_eps)), 1e-5) << "slip " << slip;
    // The friction Hessian is exact (not Gauss–Newton): against differences of the friction gradient.
    const MatX Hf = dw.hess - d0.hess;
    const int n = total_size(bodies);
    MatX fd(n, n);
    for (int i = 0; i < n; ++i) {
      VecX e = VecX::Zero(n);
      e[i] = 1e-9;
      auto grad_at = [&](const VecX& delta) {
        std::vector<Configuration> q;
        for (const Bound& b : bodies) q.push_back(retract(b.q, delta, b.layout));
        StepContext c1 = ctx, c0 = ctx0;
        for (size_t k = 0; k < bodies.size(); ++k) c1.bound[k].q = c0.bound[k].q = &q[k];
        VecX g1 = VecX::Zero(n), g0 = VecX::Zero(n);
        with.evaluate(c1, q[0], &g1, nullptr);
        without.evaluate(c0, q[0], &g0, nullptr);
        return VecX(g1 - g0);
      };
      fd.col(i) = (grad_at(e) - grad_at(-e)) / 2e-9;
    }
    // Compare on the translational columns (the rotational ones add the exponential map's curvature).
    std::vector<int> trans;
    for (int j = 0; j < 24; ++j)
      for (int c = 3; c < 6; ++c) trans.push_back(bodies[0].layout.bone_offset(j) + c);
    for (int c = 3; c < 6; ++c) trans.push_back(bodies[1].layout.bone_offset(0) + c);
    double err = 0, scale = 0;
    for (int r : trans)
      for (int c : trans) {
        err = std::max(err, std::abs(Hf(r, c) - fd(r, c)));
        scale = std::max(scale, std::abs(Hf(r, c)));
      }
    EXPECT_LT(err, 1e-4 * scale) << "slip " << slip;
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(Hf).eigenvalues().minCoeff(), -1e-9 * Hf.norm());
    // Momentum: the friction forces on body and lid are equal and opposite.
    const VecX gf = dw.grad - d0.grad;
    Vec3 sum = gf.segment<3>(bodies[1].layout.bone_offset(0) + 3);
    for (int j = 0; j < 24; ++j) sum += gf.segment<3>(bodies[0].layout.bone_offset(j) + 3);
    EXPECT_LT(sum.norm(), 1e-9 * gf.norm());
    if (slip > 1e-4) {
      // Sliding (slip ≫ ε): each skin point in the lid at t (λ_p = k·depth,
      // normal n_p there) pulls the lid by μ λ_p along its tangential slip ŝ_p:
      // ∂E/∂v_lid = −Σ μ λ_p ŝ_p.
      Vec3 expected = Vec3::Zero();
      for (int p = 0; p < with.samples().size(); ++p) {
        const Vec3 x_t = with.samples().world_point(p, bodies[0].q_prev);
        const geometry::SdfSample sd = cube->evaluate(G.inverse() * x_t);
        if (sd.distance >= 0) continue;
        const Vec3 n = G.linear() * sd.gradient;
        const Vec3 s = (Mat3::Identity() - n * n.transpose()) * (with.samples().world_point(p, bodies[0].q) - x_t);
        expected -= 0.6 * 2.0e4 * -sd.distance * s.normalized();
      }
      ASSERT_GT(expected.norm(), 0);
      EXPECT_LT((gf.segment<3>(bodies[1].layout.bone_offset(0) + 3) - expected).norm(), 1e-6 * expected.norm());
    }
  }
}

TEST(SdfContact, BroadPhaseKeepsEveryPenetratingSampleAndNothingFar) {
  const Avatar a = box();
  auto plane = std::make_shared<geometry::PlaneSdf>(Vec3::UnitY(), 0.0);
  std::map<std::string, WorldFrame> frames;
  frames["floor"].pose.translation() = Vec3(0, 0.015, 0);  // the bottom 1.5 cm are under the floor
  SdfContactOptions o;
  o.cluster_size = 0.03;
  const SdfContactTerm term("floor", PosedPoints::at_surface(a), plane, Isometry::Identity(), false, o);
  std::mt19937 rng(11);
  std::vector<Bound> bodies{{&a, body_layout(a, false), {}, {}, {}}};
  bodies[0].q = near_rest(a, rng);
  bodies[0].q_prev = bodies[0].q_prev2 = bodies[0].q;
  StepContext ctx = bind_bodies(bodies, &frames);
  auto cache = begin_term_step(term, ctx);
  const std::vector<int>& cand = term.candidates(ctx);
  int penetrating = 0, far = 0;
  for (int p = 0; p < term.samples().size(); ++p) {
    const double y = term.samples().world_point(p, bodies[0].q).y() - 0.015;
    const bool is_candidate = std::find(cand.begin(), cand.end(), p) != cand.end();
    if (y < 0) {
      ++penetrating;
      EXPECT_TRUE(is_candidate) << "sample " << p << " is under the floor but not a candidate";
    }
    if (y > 0.03) {
      ++far;
      EXPECT_FALSE(is_candidate) << "sample " << p << " is " << y << " m above the floor";
    }
  }
  EXPECT_GT(penetrating, 0);
  EXPECT_GT(far, 0);
  // Far away: no candidates, the term is inactive.
  frames["floor"].pose.translation() = Vec3(0, -1.0, 0);
  cache = begin_term_step(term, ctx);
  EXPECT_FALSE(term.active(ctx));
  // A missing frame is named.
  ctx.frames.clear();
  EXPECT_THROW(begin_term_step(term, ctx), Error);
}

/// The avatar at rest: identity bones, z = 0.
Configuration rest(const Avatar& a) {
  Configuration q;
  q.bones.assign(24, Isometry::Identity());
  q.z = VecX::Zero(a.num_reduced());
  return q;
}

/// The lowest world y of the term's samples at q.
double lowest_sample_y(const SdfContactTerm& term, const Configuration& q) {
  double bottom = 1e9;
  for (int p = 0; p < term.samples().size(); ++p) bottom = std::min(bottom, term.samples().world_point(p, q).y());
  return bottom;
}

TEST(SdfContact, BroadPhaseLooksAheadByTheSkinsAndTheObjectsMotion) {
  // The reach of the broad phase (sdf_contact.hpp, SdfContactOptions::margin):
  // margin + twice a sample's displacement over the last step + the object's
  // motion over the step, h (|v| + |ω| extent) (extent 1 m for a plane). A
  // floor 4 cm below the box's lowest sample at t, margin 1 cm:
  const Avatar a = box();
  auto plane = std::make_shared<geometry::PlaneSdf>(Vec3::UnitY(), 0.0);
  SdfContactOptions o;
  o.cluster_size = 0.03;
  const SdfContactTerm term("floor", PosedPoints::at_surface(a), plane, Isometry::Identity(), false, o);
  const Configuration q = rest(a);
  const double bottom = lowest_sample_y(term, q);
  std::map<std::string, WorldFrame> frames;
  frames["floor"].pose.translation() = Vec3(0, bottom - 0.04, 0);
  auto lowest_is_candidate = [&](std::vector<Bound>& bodies) {
    StepContext ctx = bind_bodies(bodies, &frames);
    const auto cache = begin_term_step(term, ctx);
    const std::vector<int>& cand = term.candidates(ctx);
    int lowest = 0;
    for (int p = 0; p < term.samples().size(); ++p)
      if (term.samples().world_point(p, q).y() < term.samples().world_point(lowest, q).y()) lowest = p;
    return std::find(cand.begin(), cand.end(), lowest) != cand.end();
  };
  // At rest and a still floor: 4 cm is beyond the 1 cm margin.
  std::vector<Bound> rest{{&a, body_layout(a, false), q, q, q}};
  EXPECT_FALSE(lowest_is_candidate(rest));
  // The box fell 2 cm over the last step: 1 cm + 2 × 2 cm reaches the floor.
  Configuration up = q;
  for (Isometry& G : up.bones) G.translation().y() += 0.02;
  std::vector<Bound> falling{{&a, body_layout(a, false), q, q, up}};
  EXPECT_TRUE(lowest_is_candidate(falling));
  // The floor turns at 3 rad/s: h · 3 rad/s · 1 m = 5 cm of reach.
  frames["floor"].angular_velocity = Vec3(3.0, 0, 0);
  EXPECT_TRUE(lowest_is_candidate(rest));
  frames["floor"].angular_velocity = Vec3(1.0, 0, 0);  // 1.7 cm: 2.7 cm in all, short of 4 cm
  EXPECT_FALSE(lowest_is_candidate(rest));
}

TEST(SdfContact, SampleSpacingKeepsOneVertexPerCell) {
  const Avatar a = box();
  const PosedPoints all = skin_contact_samples(a, 0.0);
  EXPECT_EQ(all.size(), a.surface_rest.rows());
  // The box surface has vertices every 4 cm; 8 cm cells keep one per cell: at most 2·2·2 per cell group.
  const PosedPoints sparse = skin_contact_samples(a, 0.08);
  EXPECT_LT(sparse.size(), all.size());
  std::set<std::tuple<long, long, long>> cells;
  for (int p = 0; p < sparse.size(); ++p) {
    const Vec3 x = sparse.unposed().row(p).transpose() / 0.08;
    EXPECT_TRUE(cells.insert({long(std::floor(x.x())), long(std::floor(x.y())), long(std::floor(x.z()))}).second);
  }
  // Each kept sample is, of the cell's vertices, the one nearest the cell's centre.
  for (int p = 0; p < sparse.size(); ++p) {
    const Vec3 x = sparse.unposed().row(p).transpose();
    const Vec3 cell = (x / 0.08).array().floor();
    const Vec3 centre = (cell.array() + 0.5).matrix() * 0.08;
    for (int v = 0; v < all.size(); ++v) {
      const Vec3 y = all.unposed().row(v).transpose();
      if (Vec3((y / 0.08).array().floor()) != cell) continue;
      EXPECT_LE((x - centre).norm(), (y - centre).norm() + 1e-15) << "sample " << p << " vs vertex " << v;
    }
  }
}

TEST(SdfContact, AMovingShapeFrameMovesTheShapeAndANonFiniteOneIsRefusedNamingIt) {
  // A dynamic lid whose shape the inputs move 2 cm up on its body (a jaw
  // opening): pressed 4 mm into the box's top by its body pose, the moved
  // shape no longer touches. Both contact models read the frame the same way.
  const Avatar a = box();
  auto cube = std::make_shared<geometry::BoxSdf>(Vec3(0.05, 0.02, 0.05));
  std::vector<Bound> bodies{{&a, body_layout(a, false), {}, {}, {}}, {nullptr, rigid_layout(0), {}, {}, {}}};
  bodies[1].layout.base = bodies[0].layout.size();
  bodies[0].q.bones = identity_bones();
  bodies[0].q.z = VecX::Zero(a.num_reduced());
  bodies[0].q_prev = bodies[0].q_prev2 = bodies[0].q;
  Isometry G = Isometry::Identity();
  G.translation() = Vec3(0.0, 0.12 + 0.02 - 0.004, 0.0);
  bodies[1].q.bones = {G};
  bodies[1].q.z = VecX(0);
  bodies[1].q_prev = bodies[1].q_prev2 = bodies[1].q;
  const SdfContactTerm sdf("lid", PosedPoints::at_surface(a), cube, Isometry::Identity(), true);
  ContactPatchOptions po;
  po.patch = false;
  const ContactPatchTerm patch("lid", a, cube, Isometry::Identity(), true, po);
  for (const EnergyTerm* term : {static_cast<const EnergyTerm*>(&sdf), static_cast<const EnergyTerm*>(&patch)}) {
    ASSERT_EQ(term->input_frames(), std::vector<std::string>{"lid/shape"});
    std::map<std::string, WorldFrame> frames;
    {
      StepContext ctx = bind_bodies(bodies, nullptr);  // no frame: the shape where the body puts it
      auto cache = begin_term_step(*term, ctx);
      EXPECT_GT(term->evaluate(ctx, bodies[0].q, nullptr, nullptr), 0) << term->name();
    }
    frames["lid/shape"].pose = G * Isometry(Eigen::Translation3d(0, 0.02, 0));
    {
      StepContext ctx = bind_bodies(bodies, &frames);
      auto cache = begin_term_step(*term, ctx);
      EXPECT_EQ(term->evaluate(ctx, bodies[0].q, nullptr, nullptr), 0) << term->name();
    }
    frames["lid/shape"].pose.translation().x() = NAN;
    StepContext ctx = bind_bodies(bodies, &frames);
    test::expect_error([&] { begin_term_step(*term, ctx); }, {"contact:lid", "'lid/shape'", "not finite"});
  }
}

TEST(SdfContact, FrictionIsCarriedByAKinematicObjectsRotation) {
  // A floor turning at 2 rad/s about a vertical axis 1 m from the box (the
  // floor frame's origin at x = −1 m): the point a sample touched at t is
  // carried h ω × r ≈ 3.3 cm along −z (≫ the static slip h · 1 mm/s), so every
  // touching sample slides and friction drags the body along −z with μ λ each
  // (λ = k · 1 mm of penetration at t).
  const Avatar a = box();
  auto plane = std::make_shared<geometry::PlaneSdf>(Vec3::UnitY(), 0.0);
  SdfContactOptions o;
  o.friction = 0.5;
  const SdfContactTerm term("floor", PosedPoints::at_surface(a), plane, Isometry::Identity(), false, o);
  const Configuration q = rest(a);
  const double bottom = lowest_sample_y(term, q);
  std::map<std::string, WorldFrame> frames;
  frames["floor"].pose.translation() = Vec3(-1.0, bottom + 0.001, 0);
  frames["floor"].angular_velocity = Vec3(0, 2.0, 0);
  std::vector<Bound> bodies{{&a, body_layout(a, false), q, q, q}};
  StepContext ctx = bind_bodies(bodies, &frames);
  const auto cache = begin_term_step(term, ctx);
  int touching = 0;
  for (int p = 0; p < term.samples().size(); ++p) touching += term.samples().world_point(p, q).y() < bottom + 1e-9;
  ASSERT_GT(touching, 0);
  const auto rep = term.report(ctx, q);
  ASSERT_EQ(rep[1].name, "friction_force");
  const Vec3 f(rep[1].value);
  const double expected = o.friction * o.stiffness * 0.001 * touching;
  EXPECT_NEAR(-f.z(), expected, 2e-3 * expected) << f.transpose();
  EXPECT_LT(std::abs(f.x()) + std::abs(f.y()), 1e-3 * expected) << f.transpose();
}

TEST(SdfContact, TruncatedSampleRowsKeepTheStrongestHandlesAndTheRowSum) {
  const Avatar a = box(6);
  const PosedPoints all = PosedPoints::at_surface(a);
  double dropped = -1;
  const PosedPoints two = all.with_truncated_rows(2, &dropped);
  std::mt19937 rng(13);
  const Configuration q = near_rest(a, rng);
  double worst = 0;
  for (int p = 0; p < all.size(); ++p) {
    const PosedPoints::Rows r = all.rows(p), t = two.rows(p);
    ASSERT_LE(t.num_handles, 2);
    ASSERT_EQ(t.num_handles, std::min(2, r.num_handles));
    // By hand: the two largest weights of the full row, scaled to its sum.
    std::vector<std::pair<double, int>> w;
    double total = 0;
    for (int e = 0; e < r.num_handles; ++e) {
      w.emplace_back(r.handle_weights[e], r.handles[e]);
      total += r.handle_weights[e];
    }
    std::sort(w.rbegin(), w.rend());
    double kept = 0, sum = 0;
    for (int e = 0; e < t.num_handles; ++e) kept += w[e].first;
    worst = std::max(worst, total - kept);
    for (int e = 0; e < t.num_handles; ++e) {
      sum += t.handle_weights[e];
      // It is one of the strongest (ties may go either way), scaled by total / kept.
      const auto it = std::find_if(w.begin(), w.end(), [&](const auto& x) { return x.second == t.handles[e]; });
      ASSERT_NE(it, w.end());
      EXPECT_GE(it->first, w[t.num_handles - 1].first - 1e-15) << "point " << p << " kept a weaker handle";
      EXPECT_NEAR(t.handle_weights[e], it->first * total / kept, 1e-15);
    }
    EXPECT_NEAR(sum, total, 1e-14);
    // Bones untouched: with z = 0 the points coincide.
    Configuration q0 = q;
    q0.z.setZero();
    EXPECT_LT((two.world_point(p, q0) - all.world_point(p, q0)).norm(), 1e-15);
  }
  EXPECT_NEAR(dropped, worst, 1e-15);
  EXPECT_GT(dropped, 0);
  // Keeping every handle changes nothing.
  const PosedPoints same = all.with_truncated_rows(1000);
  for (int p = 0; p < all.size(); ++p) EXPECT_LT((same.world_point(p, q) - all.world_point(p, q)).norm(), 1e-15);
}

TEST(CapsuleContact, GradientHessianAndMomentumBetweenTwoBodies) {
  const Avatar a = box(), b = box();
  const double k = 1.0e4;
  const CapsuleContactTerm term(a, &b, {k, 2});
  ASSERT_EQ(term.pairs().size(), 1u);
  std::mt19937 rng(5);
  std::vector<Bound> bodies{{&a, body_layout(a, true), {}, {}, {}}, {&b, body_layout(b, true), {}, {}, {}}};
  for (Bound& bd : bodies) bd.layout.num_reduced = 0;  // Bones blocks only
  bodies[1].layout.base = bodies[0].layout.size();
  Isometry shift = Isometry::Identity();
  shift.translation() = Vec3(0.05, 0.01, 0.002);  // axes 5 cm apart, radii 3 + 3 cm: 1 cm overlap
  bodies[0].q = near_rest(a, rng);
  bodies[1].q = near_rest(b, rng, shift);
  for (Bound& bd : bodies) bd.q_prev = bd.q_prev2 = bd.q;
  StepContext ctx = bind_bodies(bodies, nullptr);
  const auto cache = begin_term_step(term, ctx);
  ASSERT_TRUE(term.active(ctx));
  const Derivatives d = analytic(term, ctx, bodies);
  ASSERT_GT(d.E, 0);
  EXPECT_LT(rel(d.grad, fd_gradient(term, ctx, bodies, 1e-7)), 1e-6);
  // Independent overlap: |Δ axis points| − 0.06 from brute-force sampling of the two segments.
  const Vec3 a0 = bodies[0].q.bones[3] * a.capsules[0].p0, a1 = bodies[0].q.bones[3] * a.capsules[0].p1;
  const Vec3 b0 = bodies[1].q.bones[3] * b.capsules[0].p0, b1 = bodies[1].q.bones[3] * b.capsules[0].p1;
  double dmin = 1e9;
  for (int i = 0; i <= 400; ++i)
    for (int j = 0; j <= 400; ++j)
      dmin = std::min(dmin, ((a0 + (a1 - a0) * i / 400.0) - (b0 + (b1 - b0) * j / 400.0)).norm());
  EXPECT_NEAR(d.E, 0.5 * k * (dmin - 0.06) * (dmin - 0.06), 1e-3 * d.E);
  // GN Hessian = k j jᵀ with j = ∂d/∂δ = grad / (k d).
  const double gap = dmin - 0.06;
  const VecX j = d.grad / (k * gap);
  EXPECT_LT((d.hess - k * j * j.transpose()).norm(), 1e-3 * d.hess.norm());
  // Equal and opposite: translational and rotational gradients sum to zero.
  const auto [force, torque] = summed_bone_gradient(d.grad, bodies);
  EXPECT_LT(force.norm(), 1e-12 * d.grad.norm());
  EXPECT_LT(torque.norm(), 1e-12 * d.grad.norm());
}

/// Boxes a and b at rest, b shifted by `shift` along x, bound with their bone blocks only.
std::vector<Bound> boxes_apart(const Avatar& a, const Avatar& b, double shift) {
  Configuration qa, qb;
  qa.bones.assign(24, Isometry::Identity());
  qb.bones.assign(24, Isometry(Eigen::Translation3d(shift, 0, 0)));
  qa.z = qb.z = VecX::Zero(0);
  std::vector<Bound> bodies{{&a, body_layout(a, true), qa, qa, qa}, {&b, body_layout(b, true), qb, qb, qb}};
  for (Bound& bd : bodies) bd.layout.num_reduced = 0;
  bodies[1].layout.base = bodies[0].layout.size();
  return bodies;
}

TEST(CapsuleContact, NoEnergyAtAGapAndHalfKDepthSquaredInOverlap) {
  // Two rest-pose boxes side by side: parallel capsule axes (radius 3 cm,
  // same y range), so by hand the signed distance is |shift| − 6 cm.
  const Avatar a = box(), b = box();
  const double k = 1.0e4;
  const CapsuleContactTerm term(a, &b, {k, 2});
  for (double shift : {0.061, 0.0601, 0.055}) {
    std::vector<Bound> bodies = boxes_apart(a, b, shift);
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    const Derivatives d = analytic(term, ctx, bodies);
    const double depth = std::min(0.0, shift - 0.06);
    EXPECT_NEAR(d.E, 0.5 * k * depth * depth, 1e-12) << "shift " << shift;
    if (depth == 0.0) EXPECT_EQ(d.grad.norm(), 0.0) << "shift " << shift;
  }
}

TEST(CapsuleContact, CoresScaleEveryRadius) {
  // radius_scale 0.5: the 3 cm capsules become 1.5 cm cores, so two parallel
  // axes 5 cm apart (overlapping at full radius) do not touch, and 2.5 cm
  // apart overlap by 3 − 2.5 = 0.5 cm: E = ½ k (5 mm)².
  const Avatar a = box(), b = box();
  const double k = 1.0e4;
  const CapsuleContactTerm term(a, &b, {k, 2, 0.5});
  for (const auto& [shift, depth] : {std::pair{0.05, 0.0}, std::pair{0.025, 0.005}}) {
    std::vector<Bound> bodies = boxes_apart(a, b, shift);
    StepContext ctx = bind_bodies(bodies, nullptr);
    const auto cache = begin_term_step(term, ctx);
    EXPECT_NEAR(analytic(term, ctx, bodies).E, 0.5 * k * depth * depth, 1e-12) << "shift " << shift;
  }
  test::expect_error([&] { CapsuleContactTerm(a, &b, {k, 2, 0.0}); }, {"capsule contact", "radius scale"});
  test::expect_error([&] { CapsuleContactTerm(a, &b, {k, 2, 1.5}); }, {"capsule contact", "radius scale"});
}

TEST(CapsuleContact, AFastApproachIsCaughtByTheBroadPhaseAndTheForcePushesTheBodiesApart) {
  // Parallel capsules (radius 3 cm, 6 cm long: bounding spheres of 6 cm) with
  // body b at +x. At t − h the axes were 20 cm apart, at t 15 cm (b moved 5 cm
  // in a step), and the step ends at 5.5 cm: 5 mm of overlap. The broad phase
  // looks 2 cm + twice the last step's motion ahead (12 cm): the pair is near
  // at t although its bounding spheres are 3 cm apart, so the overlap counts:
  // E = ½ k (5 mm)², and the force on a is k · 5 mm along −x (away from b).
  const Avatar a = box(), b = box();
  const double k = 1.0e4;
  const CapsuleContactTerm term(a, &b, {k, 2});
  auto at = [](double x) {
    Configuration q;
    q.bones.assign(24, Isometry(Eigen::Translation3d(x, 0, 0)));
    q.z = VecX::Zero(0);
    return q;
  };
  const Configuration qa = at(0.0);
  std::vector<Bound> bodies{{&a, body_layout(a, true), qa, qa, qa},
                            {&b, body_layout(b, true), at(0.055), at(0.15), at(0.20)}};
  for (Bound& bd : bodies) bd.layout.num_reduced = 0;
  bodies[1].layout.base = bodies[0].layout.size();
  StepContext ctx = bind_bodies(bodies, nullptr);
  const auto cache = begin_term_step(term, ctx);
  ASSERT_TRUE(term.active(ctx));
  const Derivatives d = analytic(term, ctx, bodies);
  EXPECT_NEAR(d.E, 0.5 * k * 0.005 * 0.005, 1e-12);
  const auto rep = term.report(ctx, bodies[0].q);
  ASSERT_EQ(rep[0].name, "force");
  EXPECT_LT((Vec3(rep[0].value) - Vec3(-k * 0.005, 0, 0)).norm(), 1e-9) << Vec3(rep[0].value).transpose();
}

TEST(CapsuleContact, SelfContactSkipsAdjacentBonesAndPairsTouchingAtRest) {
  Avatar a = box();
  const Points J = a.joints_rest;
  auto cap = [&](int bone, int child) {
    return BoneCapsule{bone, Vec3(J.row(bone).transpose()), Vec3(J.row(child).transpose()), 0.02};
  };
  // Left hip→knee (1→4), left knee→ankle (4→7), right hip→knee (2→5), left elbow→wrist (18→20).
  a.capsules = {cap(1, 4), cap(4, 7), cap(2, 5), cap(18, 20)};
  const CapsuleContactTerm term(a, nullptr);
  // 1–4: parent and child; 1–2: siblings under the pelvis (2 edges); both skipped.
  // 4–2 (3 edges), and the elbow against each leg capsule, are kept.
  const std::vector<std::pair<int, int>> expected{{1, 2}, {0, 3}, {1, 3}, {2, 3}};
  std::vector<std::pair<int, int>> got = term.pairs();
  std::sort(got.begin(), got.end());
  std::vector<std::pair<int, int>> want = expected;
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want);
}

/// A model: the box avatar (bones kinematic or dynamic) plus a dynamic ball
/// (radius r, mass m) in contact through the skin.
struct BallScene {
  std::shared_ptr<const Model> model;
  int avatar = 0, ball = 1;
};
BallScene ball_scene(const Avatar& a, bool bones_dynamic, double r, double m, const Vec3& gravity, int iterations) {
  ModelOptions mo;
  mo.h = kH;
  mo.gravity = gravity;
  mo.newton.iterations = iterations;
  mo.newton.gradient_tolerance = 1e-10;
  mo.newton.line_search = iterations > 1;
  ModelBuilder mb(mo);
  BallScene s;
  auto avatar = std::make_shared<const Avatar>(a);
  s.avatar = mb.add_body({"box", avatar, bones_dynamic});
  s.ball = mb.add_body({"ball", nullptr, true});
  add_soft_tissue_terms(mb, s.avatar, {true, 0.0});
  if (bones_dynamic) {
    SkeletonTermsOptions sk;
    sk.body_mass = 2.0;
    sk.tracking = false;  // external: would take momentum
    sk.joint_limits = false;
    add_skeleton_terms(mb, s.avatar, sk);
  }
  add_rigid_body_terms(mb, s.ball, m, Mat3::Identity() * 0.4 * m * r * r);
  SdfContactOptions co;
  co.stiffness = 2.0e4;
  mb.add_term(std::make_shared<const SdfContactTerm>("ball", PosedPoints::at_surface(a),
                                                     std::make_shared<geometry::SphereSdf>(r), Isometry::Identity(), true,
                                                     co),
              {s.avatar, s.ball});
  s.model = mb.build();
  return s;
}

TEST(ContactScene, ABallRestingOnAKinematicBodyIsHeldByItsWeight) {
  // Skin vertices 1 cm apart on a 6 cm box top: the ball rests on several.
  const Avatar a = box(6, 6, 0.01);
  const double r = 0.05, m = 0.2;
  const BallScene sc = ball_scene(a, false, r, m, Vec3(0, -9.81, 0), 3);
  Simulator sim(sc.model);
  State s = sim.scene_state();
  s.bodies[sc.ball].q.bones[0].translation() = Vec3(0.005, 0.03 + r + 0.002, -0.003);  // 2 mm above the top
  s.bodies[sc.ball].q_prev = s.bodies[sc.ball].q;
  sim.set_state(s);
  StepInputs in;
  in.bodies.resize(2);
  in.bodies[sc.avatar].bones = identity_bones();
  StepReport rep;
  for (int i = 0; i < 180; ++i) rep = sim.step(in);
  Vec3 force = Vec3::Zero();
  for (const TermQuantityReport& q : rep.quantities)
    if (q.term == "contact:ball" && q.name == "force") force = Vec3(q.value[0], q.value[1], q.value[2]);
  // The force on the body is the ball's weight (pointing down) within 2 %.
  EXPECT_NEAR(force.y(), -m * 9.81, 0.02 * m * 9.81);
  EXPECT_LT(std::hypot(force.x(), force.z()), 0.02 * m * 9.81);
  const Vec3 v = (sim.state(sc.ball).bones[0].translation() - sim.previous_state(sc.ball).bones[0].translation()) / kH;
  EXPECT_LT(v.norm(), 1e-3) << "the ball has not come to rest";
}

/// The slab on an incline (incline_fixture.hpp) held by the per-sample penalty with friction μ.
Vec3 slab_on_incline(double tilt, double mu) {
  return test::slab_on_incline(tilt, [mu](const Avatar& a, const Vec3& half) {
    SdfContactOptions co;
    co.stiffness = 2.0e5;
    co.friction = mu;
    return std::make_shared<const SdfContactTerm>("slab", PosedPoints::at_surface(a),
                                                  std::make_shared<geometry::BoxSdf>(half), Isometry::Identity(), true,
                                                  co);
  });
}

TEST(ContactScene, FrictionHoldsASlabOnAnInclineAboveTheFrictionAngleOnly) {
  // 15° incline: tan = 0.27. μ = 0.5 holds it; μ = 0.1 lets it slide, about
  // ½ g (sin θ − μ cos θ) t² = 0.79 m in 1 s if nothing stopped it (the
  // slab's side meets the top's last samples after 3 cm).
  const double tilt = 15 * M_PI / 180;
  const Vec3 stuck = slab_on_incline(tilt, 0.5), slid = slab_on_incline(tilt, 0.1);
  EXPECT_LT(std::abs(stuck.x()), 2e-3) << "held by friction: " << stuck.transpose();
  EXPECT_GT(slid.x(), 0.02) << "should slide: " << slid.transpose();
}

TEST(ContactScene, ABallThrownAtAFreeBodyConservesLinearMomentum) {
  const Avatar a = box();
  const double r = 0.03, m = 0.3;
  const BallScene sc = ball_scene(a, true, r, m, Vec3::Zero(), 30);
  Simulator sim(sc.model);
  State s = sim.scene_state();
  Isometry& G = s.bodies[sc.ball].q.bones[0];
  G.translation() = Vec3(0.0, 0.06, 0.04 + r + 0.01);  // 1 cm in front of the box, thrown at it
  s.bodies[sc.ball].q_prev = s.bodies[sc.ball].q;
  s.bodies[sc.ball].q_prev.bones[0].translation() -= Vec3(0, 0, -2.0) * kH;  // 2 m/s towards −z
  sim.set_state(s);
  StepInputs in;
  in.bodies.resize(2);
  in.bodies[sc.avatar].bones = identity_bones();
  const Vec3 p0 = linear_momentum(*sc.model, sim.scene_state());
  ASSERT_NEAR(p0.z(), -2.0 * m, 1e-9);
  bool touched = false;
  for (int i = 0; i < 30; ++i) {
    const StepReport rep = sim.step(in);
    for (const TermQuantityReport& q : rep.quantities)
      if (q.name == "active_samples" && q.value[0] > 0) touched = true;
  }
  EXPECT_TRUE(touched);
  const Vec3 p1 = linear_momentum(*sc.model, sim.scene_state());
  EXPECT_LT((p1 - p0).norm(), 1e-6 * p0.norm()) << "p0 " << p0.transpose() << ", p1 " << p1.transpose();
  // The ball slowed down: momentum went to the body.
  const Vec3 vb = (sim.state(sc.ball).bones[0].translation() - sim.previous_state(sc.ball).bones[0].translation()) / kH;
  EXPECT_GT(vb.z(), -1.9);
}

}  // namespace
