// A grasping tool's anchors held by the contact patch (contact_patch.hpp,
// PatchAnchors): the patch's limit (covering the whole body, a coarse
// subspace plus the patch pinches as the nodal full space with AnchorTerm),
// the force without a patch by hand (hardness and damping apart, a kinematic
// and a dynamic tool), the condensed gradient against finite differences (a kinematic and a
// dynamic tool), and bad options.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "contact_patch_bordered.hpp"
#include "finite_difference.hpp"
#include "synthetic_avatar.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

/// A 6 × 3 × 4-cube box of 1 cm cubes (top face 6 cm × 4 cm at y = 3 cm), one material.
Avatar slab(int handles) {
  test::SyntheticAvatarOptions o;
  o.nx = 6, o.ny = 3, o.nz = 4;
  o.cell = 0.01;
  o.handles = handles;
  o.handle_radius = 0.05;
  o.two_regions = false;
  o.rotated_frames = false;
  return test::make_synthetic_avatar(o);
}

/// The skin vertices on the slab's top within 1.1 cm of its centre (0, 3, 0) cm: the pinched skin.
std::vector<int> pinched_vertices(const Avatar& a) {
  std::vector<int> out;
  for (int v = 0; v < a.surface_rest.rows(); ++v) {
    const Vec3 x = a.surface_rest.row(v).transpose();
    if (std::abs(x.y() - 0.03) < 1e-9 && (x - Vec3(0, 0.03, 0)).norm() < 0.011) out.push_back(v);
  }
  return out;
}

/// A step of the slab from rest (h = 1/60 s, no gravity).
StepContext at_rest(const Avatar& a, bool bones_dynamic) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.layout.bones_dynamic = bones_dynamic;
  ctx.h = 1.0 / 60.0;
  ctx.gravity = Vec3::Zero();
  ctx.q_prev.bones = identity_bones();
  ctx.q_prev.z = VecX::Zero(a.num_reduced());
  ctx.q_prev2 = ctx.q_prev;
  return ctx;
}

/// A 1.5 cm patch converged tightly, over a subspace without mean dilatation.
ContactPatchOptions small_patch() {
  ContactPatchOptions o;
  o.patch_radius = 0.015;
  o.inner_tolerance = 1e-14;
  o.subspace_mean_dilatation = false;
  return o;
}

constexpr double kHardness = 2.0e3, kDamping = 0.5;

/// The slab's soft tissue and a tool "tool" holding its anchors: an AnchorTerm
/// (`patch_term` false) or a patch term with the anchors covering the whole body.
std::shared_ptr<const Model> pinched_model(const Avatar& a, bool patch_term, bool patch, int iterations) {
  ModelOptions mo;
  mo.h = 1.0 / 60.0;
  mo.gravity = Vec3::Zero();
  mo.newton.iterations = iterations;
  mo.newton.line_search = iterations > 1;
  mo.newton.gradient_tolerance = iterations > 1 ? 1e-11 : 0.0;
  mo.newton.max_z_step = 0;
  mo.newton.nonlinearity_tolerance = 0.0;
  ModelBuilder mb(mo);
  const int body = mb.add_body({"slab", std::make_shared<const Avatar>(a), false});
  SoftTissueOptions so;
  so.gravity = false;
  so.mean_dilatation = false;  // every tet's own volume change, as the patch integrates it
  add_soft_tissue_terms(mb, body, so);
  const AnchorOptions ao{kHardness, kDamping};
  if (!patch_term) {
    mb.add_term(std::make_shared<const AnchorTerm>("tool", PosedPoints::at_surface(a), false, ao), {body});
  } else {
    ContactPatchOptions co;
    co.subspace_mean_dilatation = so.mean_dilatation;
    co.patch = patch;
    co.patch_radius = 1.0;  // the whole body
    co.inner_tolerance = 1e-13;
    mb.add_term(std::make_shared<const ContactPatchTerm>("tool", a, nullptr, Isometry::Identity(), false, co,
                                                         PatchAnchors{"tool", ao}),
                {body});
  }
  return mb.build();
}

/// Node displacement after a step: W z at every node plus the patch's δu.
Points node_displacement(const Avatar& a, const VecX& z, const StepReport* rep) {
  Points u = Points::Zero(a.tet.num_nodes(), 3);
  for (int n = 0; n < a.tet.num_nodes(); ++n) {
    if (a.node_role[n] != int(NodeRole::Simulated)) continue;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
      u.row(n) += it.value() * z.segment<3>(3 * it.col()).transpose();
  }
  if (rep)
    for (const TermQuantityReport& q : rep->quantities)
      if (q.name == "patch_displacement")
        for (size_t i = 0; i + 3 < q.value.size(); i += 4)
          u.row(int(q.value[i])) += Vec3(q.value[i + 1], q.value[i + 2], q.value[i + 3]).transpose();
  return u;
}

Vec3 reported_force(const StepReport& r) {
  for (const TermQuantityReport& q : r.quantities)
    if (q.name == "force" && q.value.size() == 3) return Vec3(q.value[0], q.value[1], q.value[2]);
  ADD_FAILURE() << "no force reported";
  return Vec3::Constant(NAN);
}

TEST(PatchAnchors, CoveringTheWholeBodyAPinchIsTheFullSpacePinch) {
  // The nodal basis (W = I, every tet and node in the cubature) with
  // AnchorTerm, converged with Newton, is the full FEM (ReducedVsFull); the
  // coarse model has 4 handles and its anchors in a patch over every node,
  // one Newton step per time step. The tool lifts the anchored skin 0.5 mm
  // per step, to 3 mm.
  const Avatar nodal = slab(0), coarse = slab(4);
  const std::vector<int> pinched = pinched_vertices(coarse);
  ASSERT_GE(pinched.size(), 5u);
  Simulator full(pinched_model(nodal, false, false, 60)), reduced(pinched_model(coarse, true, true, 1)),
      subspace(pinched_model(coarse, true, false, 1));
  double peak = 0, worst = 0, worst_subspace = 0, force_error = 0, force_error_subspace = 0, peak_force = 0;
  for (int i = 1; i <= 6; ++i) {
    std::vector<StepReport> reports;
    for (Simulator* sim : {&full, &reduced, &subspace}) {
      StepInputs in;
      in.bodies.resize(1);
      in.bodies[0].bones = identity_bones();
      in.anchors.resize(sim->model().anchor_set_names().size());
      for (int v : pinched) {
        AnchorPoint p;
        p.point = v;
        p.position = coarse.surface_rest.row(v).transpose() + Vec3(0, 0.0005 * i, 0);
        p.velocity = Vec3(0, 0.0005 * 60, 0);
        in.anchors[size_t(sim->model().anchor_set_id("tool").index)].push_back(p);
      }
      reports.push_back(sim->step(in));
    }
    const Points uf = node_displacement(nodal, full.state().z, nullptr);
    const Points ur = node_displacement(coarse, reduced.state().z, &reports[1]);
    const Points us = node_displacement(coarse, subspace.state().z, nullptr);
    peak = std::max(peak, uf.cwiseAbs().maxCoeff());
    worst = std::max(worst, (ur - uf).cwiseAbs().maxCoeff());
    worst_subspace = std::max(worst_subspace, (us - uf).cwiseAbs().maxCoeff());
    const Vec3 ff = reported_force(reports[0]), fr = reported_force(reports[1]), fs = reported_force(reports[2]);
    peak_force = std::max(peak_force, ff.norm());
    force_error = std::max(force_error, (fr - ff).norm());
    force_error_subspace = std::max(force_error_subspace, (fs - ff).norm());
  }
  std::cout << "[ pinch limit ] peak " << peak << " m, patch vs full " << worst << " m, subspace alone " << worst_subspace
            << " m; force peak " << peak_force << " N, patch error " << force_error << " N, subspace alone "
            << force_error_subspace << " N\n";
  ASSERT_GT(peak, 1e-3);  // the skin follows a good part of the 3 mm lift
  EXPECT_LT(worst, 1e-6 * peak);
  EXPECT_LT(force_error, 1e-6 * peak_force);
  EXPECT_GT(worst_subspace, 0.1 * peak) << "the coarse subspace alone should not lift the tent";
  EXPECT_GT(force_error_subspace, 0.1 * peak_force) << "the coarse subspace alone should pull harder";
}

TEST(PatchAnchors, CondensedEnergyGradientMatchesFiniteDifferences) {
  const Avatar a = slab(6);
  const std::vector<int> pinched = pinched_vertices(a);
  const ContactPatchOptions o = small_patch();
  const ContactPatchTerm term("tool", a, nullptr, Isometry::Identity(), false, o,
                              PatchAnchors{"tool", {kHardness, kDamping}});
  EXPECT_EQ(term.name(), "anchor:tool");
  EXPECT_EQ(term.input_anchor_set(), "tool");
  EXPECT_TRUE(term.input_frames().empty());
  std::vector<AnchorPoint> anchors;
  for (int v : pinched) {
    AnchorPoint p;
    p.point = v;
    p.position = a.surface_rest.row(v).transpose() + Vec3(0.0003, 0.002, -0.0004);
    p.velocity = Vec3(0.01, 0.12, 0);
    anchors.push_back(p);
  }
  for (bool dynamic : {false, true}) {
    SCOPED_TRACE(dynamic ? "bones dynamic" : "bones kinematic");
    StepContext ctx = at_rest(a, dynamic);
    ctx.anchors = &anchors;
    Configuration q = ctx.q_prev;
    for (int i = 0; i < q.z.size(); ++i) q.z[i] = 5e-4 * std::sin(1.7 * i + 0.3);
    ctx.q_prev2.z = -0.5 * q.z;
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx));
    ASSERT_FALSE(term.patch_nodes(ctx).empty());
    const int n = ctx.layout.size();
    VecX g = VecX::Zero(n);
    const double E = term.evaluate(ctx, q, &g, nullptr);
    ASSERT_GT(E, 0);
    const VecX fd = test::fd_gradient(term, ctx, q, 1e-7);
    EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "|g| " << g.norm() << ", |fd| " << fd.norm();
    // The report: one force per anchor, summing to "force", the tool's pull up.
    const std::vector<TermQuantity> r = term.report(ctx, q);
    VecX per_anchor, points, total;
    for (const TermQuantity& t : r) {
      if (t.name == "anchor_forces") per_anchor = t.value;
      if (t.name == "anchor_points") points = t.value;
      if (t.name == "force") total = t.value;
    }
    ASSERT_EQ(points.size(), long(pinched.size()));
    ASSERT_EQ(per_anchor.size(), 3 * long(pinched.size()));
    Vec3 sum = Vec3::Zero();
    for (long i = 0; i < points.size(); ++i) sum += per_anchor.segment<3>(3 * i);
    EXPECT_LT((sum - total).norm(), 1e-12 * sum.norm());
    EXPECT_GT(total[1], 0.0);
  }
}

TEST(PatchAnchors, ADynamicToolGetsTheOppositeForceAndItsDerivativesMatchFiniteDifferences) {
  // The slab and a tool as a rigid body bound second: the term's local system
  // is [body | tool (6)]; the anchors' tool points ride on the tool's pose.
  const Avatar a = slab(6);
  const std::vector<int> pinched = pinched_vertices(a);
  const ContactPatchOptions o = small_patch();
  const ContactPatchTerm term("tool", a, nullptr, Isometry::Identity(), true, o,
                              PatchAnchors{"tool", {kHardness, kDamping}});
  EXPECT_EQ(term.name(), "anchor:tool");
  for (bool dynamic_bones : {false, true}) {
    SCOPED_TRACE(dynamic_bones ? "bones dynamic" : "bones kinematic");
    StepContext ctx = at_rest(a, dynamic_bones);
    // The tool at t 1 cm above the top, turned a little; at the iterate moved up 2 mm and turned on.
    Configuration tool_prev, tool;
    tool_prev.bones = {Isometry::Identity()};
    tool_prev.bones[0].translate(Vec3(0.001, 0.04, -0.002)).rotate(Eigen::AngleAxisd(0.1, Vec3(0, 0, 1)));
    tool_prev.z = VecX();
    tool = tool_prev;
    tool.bones[0].pretranslate(Vec3(0.0004, 0.002, -0.0003));
    tool.bones[0].rotate(Eigen::AngleAxisd(0.05, Vec3(1, 0, 0)));
    DofLayout tool_layout;
    tool_layout.num_bones = 1;
    tool_layout.num_reduced = 0;
    tool_layout.base = ctx.layout.size();
    std::vector<AnchorPoint> anchors;  // the tool points at t: the skin there
    for (int v : pinched) {
      AnchorPoint p;
      p.point = v;
      p.position = a.surface_rest.row(v).transpose();
      anchors.push_back(p);
    }
    ctx.anchors = &anchors;
    Configuration q = ctx.q_prev;
    for (int i = 0; i < q.z.size(); ++i) q.z[i] = 4e-4 * std::sin(1.3 * i + 0.2);
    ctx.bound = {{0, 0, &a, ctx.layout, &q, &ctx.q_prev, &ctx.q_prev2},
                 {1, 1, nullptr, tool_layout, &tool, &tool_prev, &tool_prev}};
    const auto cache = begin_term_step(term, ctx);
    ASSERT_FALSE(term.patch_nodes(ctx).empty());
    const int n = ctx.layout.size() + 6;
    VecX g = VecX::Zero(n);
    const double E = term.evaluate(ctx, q, &g, nullptr);
    ASSERT_GT(E, 0);
    VecX fd(n);
    const double eps = 1e-7;
    for (int i = 0; i < n; ++i) {
      double Es[2];
      for (int sgn = 0; sgn < 2; ++sgn) {
        VecX d = VecX::Zero(n);
        d[i] = sgn ? -eps : eps;
        Configuration qi = retract(q, d, ctx.layout), ti = retract(tool, d, tool_layout);
        ctx.bound[0].q = &qi;
        ctx.bound[1].q = &ti;
        Es[sgn] = term.evaluate(ctx, qi, nullptr, nullptr);
      }
      fd[i] = (Es[0] - Es[1]) / (2 * eps);
    }
    ctx.bound[0].q = &q;
    ctx.bound[1].q = &tool;
    EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "|g| " << g.norm() << ", |fd| " << fd.norm();
    VecX g_alone = VecX::Zero(n), g_with_hessian = VecX::Zero(n);
    MatX H = MatX::Zero(n, n);
    term.evaluate(ctx, q, &g_alone, nullptr);
    term.evaluate(ctx, q, &g_with_hessian, &H);
    const VecX bordered =
        test::bordered_rhs_difference(contact_patch_detail::patch_cache(ctx, term.name()), ctx.layout.z_offset(), n);
    EXPECT_LT((g_with_hessian - g_alone - bordered).norm(), 1e-12 * g_alone.norm())
        << "the gradient with and without the Hessian (they differ by the bordered system's −Φ_qp Φ_pp⁻¹ Φ_p); |bordered| "
        << bordered.norm();
    EXPECT_GT((H.bottomRightCorner<6, 6>().norm()), 0);
    // The tool's generalized force along v is the force on the flesh (it gets −f).
    Vec3 f = Vec3::Zero();
    for (const TermQuantity& t : term.report(ctx, q))
      if (t.name == "force") f = Vec3(t.value[0], t.value[1], t.value[2]);
    ASSERT_GT(f.y(), 0.1);  // the tool pulls the skin up
    EXPECT_LT((g.segment<3>(n - 3) - f).norm(), 1e-6 * f.norm());
  }
}

TEST(PatchAnchors, WithoutAPatchEachAnchorPullsByItsHardnessAndDampingByHand) {
  // The slab at rest, no patch (contact.patch's subspace-only mode): each
  // tool point is e off its vertex at t and moves by d over the step, so the
  // anchor is stretched by −(e + d) and slips by −d, and the flesh gets
  // n (k (e + d) + (c/h) d), whether the tool is kinematic (points given at
  // t + h with their velocity) or dynamic (points at t, carried by the tool's
  // pose: translated by d).
  const Avatar a = slab(6);
  const std::vector<int> pinched = pinched_vertices(a);
  ContactPatchOptions o = small_patch();
  o.patch = false;
  const Vec3 d(0.0004, 0.0015, -0.0002), e(0.0, 0.001, 0.0003);
  const double h = 1.0 / 60.0;
  const Vec3 expected = double(pinched.size()) * (kHardness * (e + d) + kDamping / h * d);
  for (bool dynamic_tool : {false, true}) {
    SCOPED_TRACE(dynamic_tool ? "dynamic tool" : "kinematic tool");
    const ContactPatchTerm term("tool", a, nullptr, Isometry::Identity(), dynamic_tool, o,
                                PatchAnchors{"tool", {kHardness, kDamping}});
    StepContext ctx = at_rest(a, false);
    std::vector<AnchorPoint> anchors;
    for (int v : pinched) {
      AnchorPoint p;
      p.point = v;
      p.position = a.surface_rest.row(v).transpose() + e + (dynamic_tool ? Vec3::Zero() : d);
      p.velocity = dynamic_tool ? Vec3::Zero() : Vec3(d / h);
      anchors.push_back(p);
    }
    ctx.anchors = &anchors;
    // The dynamic tool's body: away from the skin and turned at t (its anchor
    // offsets are then far from the points), moved by d at the iterate.
    Configuration tool_prev, tool;
    tool_prev.bones = {Isometry::Identity()};
    tool_prev.bones[0].translate(Vec3(0.01, 0.05, 0.02)).rotate(Eigen::AngleAxisd(0.4, Vec3(1, 2, 0).normalized()));
    tool_prev.z = VecX();
    tool = tool_prev;
    tool.bones[0].pretranslate(d);
    DofLayout tool_layout;
    tool_layout.num_bones = 1;
    tool_layout.base = ctx.layout.size();
    Configuration q = ctx.q_prev;
    if (dynamic_tool)
      ctx.bound = {{0, 0, &a, ctx.layout, &q, &ctx.q_prev, &ctx.q_prev2},
                   {1, 1, nullptr, tool_layout, &tool, &tool_prev, &tool_prev}};
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.patch_nodes(ctx).empty());
    Vec3 force = Vec3::Zero();
    double stretch = 0;
    for (const TermQuantity& t : term.report(ctx, q)) {
      if (t.name == "force") force = Vec3(t.value[0], t.value[1], t.value[2]);
      if (t.name == "max_stretch") stretch = t.value[0];
    }
    EXPECT_LT((force - expected).norm(), 1e-9 * expected.norm()) << force.transpose() << " vs " << expected.transpose();
    EXPECT_NEAR(stretch, (e + d).norm(), 1e-12);
  }
}

TEST(PatchAnchors, BadOptionsAreRefusedNamingTheContact) {
  const Avatar a = slab(4);
  test::expect_error([&] { ContactPatchTerm("tool", a, nullptr, Isometry::Identity(), false, {}); },
                     {"contact with 'tool'", "no field and no anchors"});
  for (double k : {0.0, -1.0, double(NAN)})
    test::expect_error(
        [&] { ContactPatchTerm("tool", a, nullptr, Isometry::Identity(), false, {}, PatchAnchors{"tool", {k, 1.0}}); },
        {"contact with 'tool'", "anchor hardness"});
  test::expect_error(
      [&] { ContactPatchTerm("tool", a, nullptr, Isometry::Identity(), false, {}, PatchAnchors{"tool", {1e3, -1.0}}); },
      {"contact with 'tool'", "anchor damping"});
  // An anchored vertex out of range names the term.
  const ContactPatchTerm term("tool", a, nullptr, Isometry::Identity(), false, {}, PatchAnchors{"tool", {}});
  StepContext ctx = at_rest(a, false);
  std::vector<AnchorPoint> anchors(1);
  anchors[0].point = int(a.surface_rest.rows());
  ctx.anchors = &anchors;
  test::expect_error([&] { begin_term_step(term, ctx); }, {"anchor:tool", "out of range"});
}

}  // namespace
}  // namespace sflsh
