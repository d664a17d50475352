// Contact sampled over the skin's faces and the full-space patch under it
// (sim/energies/contact_patch.hpp): the force of a uniform penetration by
// hand (κ × depth × area, whatever the sampling), the gradient of the
// condensed energy against finite differences, the patch's limit (covering
// the whole body, a coarse subspace plus the patch takes the same step as the
// nodal full space), and bad options.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/material.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/energies/contact_patch_cache.hpp"
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

StepContext context(const Avatar& a, const std::map<std::string, WorldFrame>* frames, bool bones_dynamic) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.layout.bones_dynamic = bones_dynamic;
  ctx.h = 1.0 / 60.0;
  ctx.gravity = Vec3::Zero();
  ctx.q_prev.bones = identity_bones();
  ctx.q_prev.z = VecX::Zero(a.num_reduced());
  ctx.q_prev2 = ctx.q_prev;
  // The term's one input frame: the only one these tests give.
  if (frames)
    for (const auto& [name, f] : *frames) ctx.frames.push_back(&f);
  return ctx;
}

double quantity(const std::vector<TermQuantity>& r, const std::string& name, int i = 0) {
  for (const TermQuantity& q : r)
    if (q.name == name) return q.value[i];
  ADD_FAILURE() << "no quantity " << name;
  return NAN;
}

TEST(ContactPatch, UniformPenetrationGivesPressureStiffnessTimesDepthTimesArea) {
  // The slab's skin reduced to its top face (y = 3 cm, 6 cm × 4 cm), and a
  // half-space whose surface is 0.7 mm below it: every sample is 0.7 mm deep,
  // so the force is κ δ A along −y, at any spacing.
  Avatar a = slab(0);
  std::vector<int> top;
  for (int f = 0; f < a.surface_faces.rows(); ++f) {
    bool on_top = true;
    for (int i = 0; i < 3; ++i) on_top = on_top && a.surface_rest(a.surface_faces(f, i), 1) > 0.03 - 1e-9;
    if (on_top) top.push_back(f);
  }
  a.surface_faces = Triangles(a.surface_faces(top, Eigen::all));
  ASSERT_EQ(int(top.size()), 2 * 6 * 4);
  std::map<std::string, WorldFrame> frames;
  frames["floor"].pose = Isometry::Identity();
  frames["floor"].pose.linear() = Eigen::AngleAxisd(M_PI, Vec3::UnitX()).toRotationMatrix();  // normal −y
  frames["floor"].pose.translation() = Vec3(0, 0.03 - 0.0007, 0);
  const double kappa = 3.0e7, depth = 0.0007, area = 0.06 * 0.04;
  for (double spacing : {0.02, 0.004, 0.0015}) {
    ContactPatchOptions o;
    o.pressure_stiffness = kappa;
    o.spacing = spacing;
    o.patch = false;
    const ContactPatchTerm term("floor", a, std::make_shared<geometry::PlaneSdf>(Vec3(0, 1, 0), 0.0),
                                Isometry::Identity(), false, o);
    StepContext ctx = context(a, &frames, false);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_TRUE(term.active(ctx));
    const auto r = term.report(ctx, ctx.q_prev);
    EXPECT_NEAR(quantity(r, "force", 1), -kappa * depth * area, 1e-9 * kappa * depth * area) << spacing;
    EXPECT_NEAR(quantity(r, "force", 0), 0.0, 1e-12);
    EXPECT_NEAR(quantity(r, "max_penetration"), depth, 1e-12);
    EXPECT_NEAR(quantity(r, "contact_area"), area, 1e-12 * area) << spacing;
    // A uniform pressure acts at the face's centre (the top face's box: 6 cm × 4 cm at y = 3 cm).
    Vec3 lo = Vec3::Constant(1e9), hi = Vec3::Constant(-1e9);
    for (int f = 0; f < a.surface_faces.rows(); ++f)
      for (int i = 0; i < 3; ++i) {
        lo = lo.cwiseMin(Vec3(a.surface_rest.row(a.surface_faces(f, i)).transpose()));
        hi = hi.cwiseMax(Vec3(a.surface_rest.row(a.surface_faces(f, i)).transpose()));
      }
    ASSERT_NEAR(hi.x() - lo.x(), 0.06, 1e-12);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(quantity(r, "contact_point", k), 0.5 * (lo[k] + hi[k]), 1e-9) << spacing;
    EXPECT_NEAR(term.evaluate(ctx, ctx.q_prev, nullptr, nullptr), 0.5 * kappa * depth * depth * area,
                1e-9 * kappa * depth * depth * area);
  }
}

TEST(ContactPatch, CondensedEnergyGradientMatchesFiniteDifferences) {
  const Avatar a = slab(6);
  // A 1.2 cm ball 2 mm (large strain on 1 cm cells) and 0.5 mm into the top.
  for (double press : {0.002, 0.0005}) {
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - press, -0.003);
  ContactPatchOptions o;
  o.pressure_stiffness = 2.0e7;
  o.spacing = 0.003;
  o.patch_radius = 0.015;
  o.inner_tolerance = 1e-13;
  o.subspace_mean_dilatation = false;  // as the elastic term of the Hessian check below
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false, o);
  for (bool dynamic : {false, true}) {
    StepContext ctx = context(a, &frames, dynamic);
    // Some subspace displacement and a moved body, so every piece is non-trivial.
    Configuration q = ctx.q_prev;
    for (int i = 0; i < q.z.size(); ++i) q.z[i] = press * 0.5 * std::sin(1.7 * i + 0.3);
    ctx.q_prev2.z = -0.5 * q.z;
    const auto cache = begin_term_step(term, ctx);
    ASSERT_FALSE(term.patch_nodes(ctx).empty());
    const int n = ctx.layout.size();
    VecX g = VecX::Zero(n);
    const double E = term.evaluate(ctx, q, &g, nullptr);
    ASSERT_GT(E, 0);
    const VecX fd = test::fd_gradient(term, ctx, q, 1e-7);
    EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "bones dynamic " << dynamic << ", " << press << " m: |g| " << g.norm()
                                                  << ", |fd| " << fd.norm();
    // The gradient asked with the Hessian (the Newton iteration) is the one
    // asked alone (the final report), back to back at one q (one minimizer),
    // but for what the bordered system's right-hand side takes of the
    // minimizer's last inner step (below 1e-13 m): −Φ_qp Φ_pp⁻¹ Φ_p.
    VecX g_alone = VecX::Zero(n), g_with_hessian = VecX::Zero(n);
    MatX H_unused = MatX::Zero(n, n);
    term.evaluate(ctx, q, &g_alone, nullptr);
    term.evaluate(ctx, q, &g_with_hessian, &H_unused);
    const VecX bordered =
        test::bordered_rhs_difference(contact_patch_detail::patch_cache(ctx, term.name()), ctx.layout.z_offset(), n);
    EXPECT_LT((g_with_hessian - g_alone - bordered).norm(), 1e-12 * g_alone.norm())
        << "the gradient with and without the Hessian; |bordered| " << bordered.norm();
    // The term alone subtracts the subspace's stiffness of the patch's tets
    // (the patch takes their load): with the subspace's own elasticity and
    // inertia, the step's Hessian is positive semi-definite at small strain
    // (the bones without skinning weight carry no mass: zero eigenvalues).
    // At 20 % strain the left-out K(Wz + δu) − K(Wz) makes it indefinite by
    // ~2e-4 of its norm, which Newton's regularization absorbs.
    if (press > 0.001) continue;
    MatX H = MatX::Zero(n, n);
    term.evaluate(ctx, q, nullptr, &H);
    const ElasticTerm elastic(a, true, true, false);
    const InertiaTerm inertia(a);
    for (const EnergyTerm* t : {static_cast<const EnergyTerm*>(&elastic), static_cast<const EnergyTerm*>(&inertia)}) {
      StepContext tctx = ctx;
      const auto tcache = begin_term_step(*t, tctx);
      t->evaluate(tctx, q, nullptr, &H);
    }
    const Eigen::SelfAdjointEigenSolver<MatX> eig(0.5 * (H + H.transpose()));
    EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff());
  }
  }
}

/// The patch options of a 1.2 cm ball on the slab, minimized to round-off.
ContactPatchOptions ball_options() {
  ContactPatchOptions o;
  o.pressure_stiffness = 2.0e7;
  o.spacing = 0.003;
  o.patch_radius = 0.015;
  o.inner_tolerance = 1e-14;
  return o;
}

/// The patch's δu the term reports at q (its "patch_displacement", by node).
std::map<int, Vec3> reported_patch(const ContactPatchTerm& term, const StepContext& ctx, const Configuration& q) {
  std::map<int, Vec3> du;
  for (const TermQuantity& r : term.report(ctx, q))
    if (r.name == "patch_displacement")
      for (Eigen::Index i = 0; i + 3 < r.value.size(); i += 4)
        du[int(r.value[i])] = Vec3(r.value[i + 1], r.value[i + 2], r.value[i + 3]);
  return du;
}

double patch_distance(const std::map<int, Vec3>& a, const std::map<int, Vec3>& b) {
  double d2 = 0;
  for (const auto& [n, u] : a) d2 += (u - b.at(n)).squaredNorm();
  return std::sqrt(d2);
}

TEST(ContactPatch, ATrialTakesTheBorderedNewtonStepsPatchDisplacement) {
  // A Newton iteration minimizes δu at its start q0; its trials q0 ⊕ αΔ take
  // δu from the bordered system's back-substitution, δu0 − Φ_pp⁻¹ Φ_pq Δ,
  // not from a new minimization. Against the minimizer at the trial, that is
  // first-order exact: its error falls about four-fold when Δ halves (3.6
  // here), while δu itself moves linearly. With the cross block the Schur
  // complement takes (the subspace's small-strain K0, not the dented tets'
  // K1) or its guarded Φ_pp, the error was first order (a ratio of 2) and a
  // third of the move. With bones dynamic the bones' rows are approximate
  // (δu's rotation with them is not differentiated): a ratio of 3.0.
  const Avatar a = slab(6);
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - 0.001, -0.003);
  const ContactPatchOptions o = ball_options();
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false, o);
  for (bool dynamic : {false, true}) {
    StepContext ctx = context(a, &frames, dynamic);
    Configuration q0 = ctx.q_prev;
    for (int i = 0; i < q0.z.size(); ++i) q0.z[i] = 0.0004 * std::sin(1.7 * i + 0.3);
    const int n = ctx.layout.size();
    VecX step = VecX::Zero(n);
    for (int i = 0; i < n; ++i) step[i] = 0.0006 * std::cos(0.9 * i + 0.2);  // m in z; rad and m for the bones
    double last_error = 0;
    for (double alpha : {1.0, 0.5}) {
      const Configuration q1 = retract(q0, alpha * step, ctx.layout);
      // The minimizer at q1: a fresh step asked for the Hessian there.
      const auto fresh = begin_term_step(term, ctx);
      MatX H = MatX::Zero(n, n);
      term.evaluate(ctx, q1, nullptr, &H);
      const std::map<int, Vec3> minimizer = reported_patch(term, ctx, q1);
      // The iteration from q0 and its trial at q1.
      const auto cache = begin_term_step(term, ctx);
      H.setZero();
      term.evaluate(ctx, q0, nullptr, &H);
      const std::map<int, Vec3> at_start = reported_patch(term, ctx, q0);
      const double E_trial = term.evaluate(ctx, q1, nullptr, nullptr);
      const std::map<int, Vec3> trial = reported_patch(term, ctx, q1);
      ASSERT_EQ(trial.size(), minimizer.size());
      ASSERT_FALSE(trial.empty());
      const double moved = patch_distance(minimizer, at_start), error = patch_distance(trial, minimizer);
      EXPECT_GT(moved, 1e-7) << "the step should move the patch";
      EXPECT_LT(error, 0.05 * moved) << "bones dynamic " << dynamic << ", α " << alpha;
      // Not minimized: the trial's energy is at or above the minimum there.
      const auto again = begin_term_step(term, ctx);
      EXPECT_GE(E_trial, term.evaluate(ctx, q1, nullptr, nullptr) - 1e-12 * std::abs(E_trial));
      if (alpha == 0.5) {
        EXPECT_GT(last_error / error, dynamic ? 2.5 : 3.2) << "bones dynamic " << dynamic << ": errors " << last_error << ", " << error;
        EXPECT_LT(last_error / error, 5.5) << "bones dynamic " << dynamic << ": errors " << last_error << ", " << error;
      }
      last_error = error;
    }
  }
}

TEST(ContactPatch, AnUnconvergedPatchEntersTheStepThroughTheBorderedRightHandSide) {
  // The inner minimization may stop short of the minimizer (inner_tolerance):
  // then the Newton iteration's gradient is the bordered system's right-hand
  // side, Φ_q − Φ_qp Φ_pp⁻¹ Φ_p, which is the gradient at q0 of the energy
  // its trials see, f(q) = Φ(q, δu_lin(q)) with δu_lin(q) = δu0 − Φ_pp⁻¹ (Φ_p
  // + Φ_pq (q ⊖ q0)). Here the inner minimization takes one Newton step from
  // no displacement. Without the Φ_p term the gradient misses f's by the
  // remaining step's reaction (the gradient asked alone, at δu0, shows it).
  const Avatar a = slab(6);
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - 0.0005, -0.003);
  ContactPatchOptions o = ball_options();
  o.max_inner_iterations = 1;
  o.inner_tolerance = 0;
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false, o);
  StepContext ctx = context(a, &frames, false);
  Configuration q0 = ctx.q_prev;
  for (int i = 0; i < q0.z.size(); ++i) q0.z[i] = 0.0002 * std::sin(1.7 * i + 0.3);
  const auto cache = begin_term_step(term, ctx);
  const int n = ctx.layout.size();
  VecX g = VecX::Zero(n), g_at_start = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  term.evaluate(ctx, q0, &g, &H);
  term.evaluate(ctx, q0, &g_at_start, nullptr);  // Φ_q at (q0, δu0)
  const VecX fd = test::fd_gradient(term, ctx, q0, 1e-7);
  const double error = (g - fd).norm(), without = (g_at_start - fd).norm();
  EXPECT_GT(without, 1e-3 * fd.norm()) << "the inner minimization should stop short here";
  EXPECT_LT(error, 0.05 * without) << "|g − ∇f| " << error << ", without the Φ_p term " << without << ", |∇f| " << fd.norm();
}

TEST(ContactPatch, TheNextStepsStartTakesBackTheLastStepsMove) {
  // A step starts z at q(t) but extrapolates δu to t + h; du_back takes the
  // last step's move q(t) ⊖ q(t − h) back through its linearization,
  // Φ_pp⁻¹ Φ_pq (q1 ⊖ q0). To first order that is minus the change of the
  // minimizer, −(δu*(q1) − δu*(q0)), each minimizer found afresh. The value
  // is read where a checkpoint keeps it (saved_state: a node, then δu, d_t,
  // δu_next, d_next and du_back_next).
  const Avatar a = slab(6);
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - 0.001, -0.003);
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false,
                              ball_options());
  StepContext ctx = context(a, &frames, false);
  for (int i = 0; i < ctx.q_prev.z.size(); ++i) ctx.q_prev.z[i] = 0.0004 * std::sin(1.7 * i + 0.3);
  const Configuration q0 = ctx.q_prev;
  VecX step = VecX::Zero(ctx.layout.size());
  for (int i = 0; i < step.size(); ++i) step[i] = 0.0002 * std::cos(0.9 * i + 0.2);
  const Configuration q1 = retract(q0, step, ctx.layout);
  MatX H = MatX::Zero(step.size(), step.size());
  const auto at_q0 = begin_term_step(term, ctx);
  term.evaluate(ctx, q0, nullptr, &H);
  const std::map<int, Vec3> du0 = reported_patch(term, ctx, q0);
  const auto at_q1 = begin_term_step(term, ctx);
  term.evaluate(ctx, q1, nullptr, &H);
  const std::map<int, Vec3> du1 = reported_patch(term, ctx, q1);  // the report fixes du_back_next
  const std::vector<double> saved = at_q1->saved_state();
  std::map<int, Vec3> back;
  for (size_t i = 0; i + 16 <= saved.size(); i += 16) back[int(saved[i])] = Vec3(saved[i + 13], saved[i + 14], saved[i + 15]);
  ASSERT_EQ(du0.size(), du1.size());
  ASSERT_FALSE(du1.empty());
  double change2 = 0, error2 = 0;
  for (const auto& [n, u1] : du1) {
    ASSERT_TRUE(back.count(n)) << "node " << n << " has no saved du_back_next";
    const Vec3 change = u1 - du0.at(n);
    change2 += change.squaredNorm();
    error2 += (back.at(n) + change).squaredNorm();
  }
  EXPECT_GT(std::sqrt(change2), 1e-7) << "the move should change the minimizer";
  EXPECT_LT(std::sqrt(error2), 0.1 * std::sqrt(change2)) << "du_back against minus the minimizer's change";
}

TEST(ContactPatch, WhatThePatchSubtractsIsWhatTheSubspaceHolds) {
  // The patch subtracts each tet's share of the subspace's elastic energy.
  // With mean dilatation the subspace holds only α = 0.2 of each tet's own
  // bulk stiffness (and its cubature a few tets' remainder); subtracting the
  // exact energy of the tets instead leaves volume changes inside the patch
  // with a negative stiffness: the step's Hessian is indefinite by about the
  // bulk modulus and a deep press runs away. Here the step's Hessian (the
  // term, the mean-dilatation elastic term and the inertia) at a strained
  // state is positive semi-definite, on a cubature that holds every tet and
  // on one that holds every third tet (three times the weight).
  Avatar a = slab(6);
  for (int every : {1, 3}) {
    Avatar b = a;
    Cubature cub;
    std::vector<int> tets;
    for (int t = 0; t < b.tet.num_elements(); t += every) tets.push_back(t);
    cub.elements = Eigen::Map<const VecXi>(tets.data(), int(tets.size()));
    cub.barycentric = MatXr::Constant(int(cub.elements.size()), 4, 0.25);
    const VecX volume = fem::tet_volumes(b.tet);
    cub.weights = VecX(int(cub.elements.size()));
    for (int k = 0; k < cub.size(); ++k) cub.weights[k] = every * volume[cub.elements[k]];
    b.elastic = cub;
    std::map<std::string, WorldFrame> frames;
    frames["ball"].pose.translation() = Vec3(0.004, 0.03 + 0.012 - 0.001, -0.003);
    ContactPatchOptions o;
    o.pressure_stiffness = 2.0e7;
    o.spacing = 0.003;
    o.patch_radius = 0.015;
    const ContactPatchTerm term("ball", b, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), false, o);
    StepContext ctx = context(b, &frames, false);
    Configuration q = ctx.q_prev;
    for (int i = 0; i < q.z.size(); ++i) q.z[i] = 0.002 * std::sin(1.3 * i + 0.7);
    const auto cache = begin_term_step(term, ctx);
    ASSERT_FALSE(term.patch_nodes(ctx).empty());
    const int n = ctx.layout.size();
    MatX H = MatX::Zero(n, n);
    term.evaluate(ctx, q, nullptr, &H);
    const ElasticTerm elastic(b, true, true, true);
    const InertiaTerm inertia(b);
    for (const EnergyTerm* t : {static_cast<const EnergyTerm*>(&elastic), static_cast<const EnergyTerm*>(&inertia)}) {
      StepContext tctx = ctx;
      const auto tcache = begin_term_step(*t, tctx);
      t->evaluate(tctx, q, nullptr, &H);
    }
    const Eigen::SelfAdjointEigenSolver<MatX> eig(0.5 * (H + H.transpose()));
    EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * eig.eigenvalues().maxCoeff())
        << "cubature on every " << every << " tet(s): eigenvalues " << eig.eigenvalues().minCoeff() << " .. "
        << eig.eigenvalues().maxCoeff();
  }
}

/// Node displacement of a body after a step: W z at every node, plus the
/// patch's δu from the term's report ("patch_displacement": node, δu).
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

std::shared_ptr<const Model> pressed_model(const Avatar& a, bool patch, int iterations, bool gravity = false) {
  ModelOptions mo;
  mo.h = 1.0 / 60.0;
  mo.gravity = gravity ? Vec3(0, -9.81, 0) : Vec3::Zero();
  mo.newton.iterations = iterations;
  mo.newton.line_search = iterations > 1;
  mo.newton.gradient_tolerance = iterations > 1 ? 1e-11 : 0.0;
  mo.newton.max_z_step = 0;
  mo.newton.nonlinearity_tolerance = 0.0;
  ModelBuilder mb(mo);
  const int body = mb.add_body({"slab", std::make_shared<const Avatar>(a), false});
  SoftTissueOptions so;
  so.gravity = gravity;
  so.mean_dilatation = false;  // every tet's own volume change, as the patch integrates it
  add_soft_tissue_terms(mb, body, so);
  ContactPatchOptions co;
  co.subspace_mean_dilatation = so.mean_dilatation;
  co.pressure_stiffness = 2.0e7;
  co.spacing = 0.003;
  co.patch = patch;
  co.patch_radius = 1.0;  // the whole body
  co.inner_tolerance = 1e-13;
  mb.add_term(std::make_shared<const ContactPatchTerm>("ball", a, std::make_shared<geometry::SphereSdf>(0.012),
                                                       Isometry::Identity(), false, co),
              {body});
  return mb.build();
}

TEST(ContactPatch, CoveringTheWholeBodyTheStepIsTheFullSpaceStep) {
  // The nodal basis (one handle per Simulated node, W = I, every tet and node
  // in the cubature) is the full FEM (ReducedVsFull); converged with Newton it
  // is the reference here. The coarse model has 4 handles and the patch over
  // every node, and takes one Newton step per time step.
  const Avatar nodal = slab(0), coarse = slab(4);
  Simulator full(pressed_model(nodal, false, 60)), reduced(pressed_model(coarse, true, 1)),
      subspace(pressed_model(coarse, false, 1));
  StepInputs in;
  in.bodies.resize(1);
  in.bodies[0].bones = identity_bones();
  double peak = 0, worst = 0, worst_subspace = 0;
  for (int i = 1; i <= 6; ++i) {
    // A 1.2 cm ball pressed 0.5 mm further each step, to 3 mm.
    in.frames["ball"].pose.translation() = Vec3(0.003, 0.03 + 0.012 - 0.0005 * i, -0.002);
    in.frames["ball"].linear_velocity = Vec3(0, -0.0005 * 60, 0);
    const StepReport rf = full.step(in), rr = reduced.step(in), rs = subspace.step(in);
    const Points uf = node_displacement(nodal, full.state().z, nullptr);
    const Points ur = node_displacement(coarse, reduced.state().z, &rr);
    const Points us = node_displacement(coarse, subspace.state().z, nullptr);
    peak = std::max(peak, uf.cwiseAbs().maxCoeff());
    worst = std::max(worst, (ur - uf).cwiseAbs().maxCoeff());
    worst_subspace = std::max(worst_subspace, (us - uf).cwiseAbs().maxCoeff());
  }
  std::cout << "[ patch limit ] peak " << peak << " m, patch vs full " << worst << " m, subspace alone vs full " << worst_subspace << " m\n";
  ASSERT_GT(peak, 5e-4);  // a dent of a fraction of the 3 mm
  EXPECT_LT(worst, 1e-6 * peak) << "peak " << peak;
  EXPECT_GT(worst_subspace, 0.1 * peak) << "the coarse subspace alone should not make the dent";
}

TEST(ContactPatch, UnderGravityTheWholeBodyPatchIsStillTheFullSpaceStep) {
  // As above with gravity (the patch nodes carry their weight, m g·δu, in the
  // condensed energy): the slab sags and is dented, and the patch step is the
  // full-space one.
  const Avatar nodal = slab(0), coarse = slab(4);
  Simulator full(pressed_model(nodal, false, 60, true)), reduced(pressed_model(coarse, true, 1, true));
  StepInputs in;
  in.bodies.resize(1);
  in.bodies[0].bones = identity_bones();
  double peak = 0, worst = 0;
  for (int i = 1; i <= 3; ++i) {
    in.frames["ball"].pose.translation() = Vec3(0.003, 0.03 + 0.012 - 0.0005 * i, -0.002);
    in.frames["ball"].linear_velocity = Vec3(0, -0.0005 * 60, 0);
    full.step(in);
    const StepReport rr = reduced.step(in);
    const Points uf = node_displacement(nodal, full.state().z, nullptr);
    const Points ur = node_displacement(coarse, reduced.state().z, &rr);
    peak = std::max(peak, uf.cwiseAbs().maxCoeff());
    worst = std::max(worst, (ur - uf).cwiseAbs().maxCoeff());
  }
  ASSERT_GT(peak, 1e-4);
  EXPECT_LT(worst, 1e-6 * peak) << "peak " << peak;
}

TEST(ContactPatch, OutOfContactThePatchDecaysWithItsReleaseTimeAndLeaves) {
  // The ball dents the slab for 4 steps, then jumps 10 cm away: from the
  // next step on, δu is prescribed, e^(−h/τ) times the last one (τ = 20 ms),
  // and the nodes leave once it is below 1 µm; the subspace takes the rest.
  const Avatar coarse = slab(4);
  Simulator sim(pressed_model(coarse, true, 1));
  StepInputs in;
  in.bodies.resize(1);
  in.bodies[0].bones = identity_bones();
  auto patch_quantity = [](const StepReport& r, const std::string& name) {
    for (const TermQuantityReport& q : r.quantities)
      if (q.name == name && q.value.size() == 1) return q.value[0];
    return -1.0;  // the term was inactive: no patch
  };
  double last = 0;
  for (int i = 1; i <= 4; ++i) {
    in.frames["ball"].pose.translation() = Vec3(0.003, 0.03 + 0.012 - 0.0005 * i, -0.002);
    last = patch_quantity(sim.step(in), "max_patch_displacement");
  }
  ASSERT_GT(last, 1e-4);
  in.frames["ball"].pose.translation() = Vec3(0.003, 0.15, -0.002);
  const double decay = std::exp(-(1.0 / 60.0) / ContactPatchOptions().release_time);
  int released_at = -1;
  for (int i = 1; i <= 30 && released_at < 0; ++i) {
    const StepReport r = sim.step(in);
    const double now = patch_quantity(r, "max_patch_displacement");
    if (now < 0) {
      released_at = i;
      break;
    }
    EXPECT_NEAR(now, decay * last, 1e-12 * last) << "step " << i << " after the contact";
    EXPECT_EQ(patch_quantity(r, "patch_iterations"), 0.0) << "a released patch is not minimized";
    last = now;
  }
  // From ~1e-3 m to 1e-6 m at a factor 0.435 a step: about 9 steps (the node
  // of the largest δu leaves last), not the 30 allowed.
  EXPECT_GT(released_at, 5);
  EXPECT_LT(released_at, 15);
  EXPECT_TRUE(sim.state().z.allFinite());
}

/// F_t of the subspace's state W z alone, tet t.
Mat3 subspace_gradient(const Avatar& a, const VecX& z, const std::vector<fem::TetGradient>& g, int t) {
  Mat3 F = Mat3::Identity();
  for (int k = 0; k < 4; ++k) {
    const int n = a.tet.elements(t, k);
    Vec3 u = Vec3::Zero();
    for (int h = 0; h < a.num_handles(); ++h) u += a.W.coeff(n, h) * z.segment<3>(3 * h);
    F += u * g[size_t(t)].row(k);
  }
  return F;
}

/// det F of every tet under the subspace's displacement W z (brute force).
VecX subspace_determinants(const Avatar& a, const VecX& z) {
  const std::vector<fem::TetGradient> g = fem::tet_gradients(a.tet);
  VecX det(a.tet.num_elements());
  for (int t = 0; t < a.tet.num_elements(); ++t) det[t] = subspace_gradient(a, z, g, t).determinant();
  return det;
}

TEST(ContactPatch, ANodeInATetTheSubspaceInvertsIsLeftOutAndTheStepStartsAdmissible) {
  // The elastic cubature samples few tets, so the subspace can invert one it
  // does not sample; the patch integrates its tets exactly and no δu starts
  // such a tet admissible. A hat handle near the ball displaced by s along e
  // gives det F = 1 − s/R on its side (x − h) ∥ e: s = 1.6 R inverts the tets
  // there. The term must leave their nodes out (and keep the others), so that
  // its energy at the step's start is finite: with them in, the step failed
  // ("not finite at the start of iteration 0"; a ball thrown at the belly).
  const Avatar a = slab(4);
  const double R = 0.012;
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.003, 0.03 + R - 0.001, -0.002);
  ContactPatchOptions o;
  o.patch_radius = 0.02;
  o.patch_radius_per_contact_radius = 0;  // a fixed radius, for the count below
  o.max_patch_nodes = 100000;
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(R), Isometry::Identity(), false, o);
  const PosedPoints skin = PosedPoints::at_surface(a);
  int tried = 0, kept = 0;
  for (int h = 0; h < a.num_handles(); ++h)
    for (int axis = 0; axis < 3; ++axis) {
      StepContext ctx = context(a, &frames, false);
      ctx.q_prev.z.segment<3>(3 * h)[axis] = 1.6 * 0.05;  // slab(): hat radius 5 cm
      ctx.q_prev2 = ctx.q_prev;
      const VecX det = subspace_determinants(a, ctx.q_prev.z);
      // The patch without the subspace's displacement: which nodes it would take.
      StepContext rest = context(a, &frames, false);
      const auto rest_cache = begin_term_step(term, rest);
      const std::vector<int> all = term.patch_nodes(rest);
      std::vector<char> in_inverted(size_t(a.tet.num_nodes()), 0);
      for (int t = 0; t < a.tet.num_elements(); ++t)
        if (det[t] <= 0)
          for (int k = 0; k < 4; ++k) in_inverted[size_t(a.tet.elements(t, k))] = 1;
      int inverted_in_patch = 0;
      for (int n : all) inverted_in_patch += in_inverted[size_t(n)];
      if (inverted_in_patch == 0 || inverted_in_patch == int(all.size())) continue;  // not a mixed case
      ++tried;
      const auto cache = begin_term_step(term, ctx);
      const std::vector<int> nodes = term.patch_nodes(ctx);
      kept += !nodes.empty();  // (the displaced skin can leave the ball: no patch)
      // By brute force: the Simulated nodes within the radius (unposed) of a
      // skin vertex near the ball at W z, less those of an inverted tet. Only
      // those leave: the others stay.
      std::vector<Vec3> near;
      for (int v = 0; v < a.surface_rest.rows(); ++v)
        if ((skin.world_point(v, ctx.q_prev) - frames["ball"].pose.translation()).norm() - R < o.margin)
          near.push_back(a.surface_rest.row(v).transpose());
      std::vector<int> expected;
      for (int n = 0; n < a.tet.num_nodes(); ++n) {
        if (a.node_role[n] != int(NodeRole::Simulated) || in_inverted[size_t(n)]) continue;
        const Vec3 y = a.tet.nodes.row(n).transpose();
        bool within = false;
        for (const Vec3& x : near) within = within || (y - x).norm() <= o.patch_radius;
        if (within) expected.push_back(n);
      }
      EXPECT_EQ(nodes, expected) << "handle " << h << " axis " << axis;
      VecX g = VecX::Zero(ctx.layout.size());
      const double E = term.evaluate(ctx, ctx.q_prev, &g, nullptr);
      EXPECT_TRUE(std::isfinite(E) && g.allFinite()) << "handle " << h << " axis " << axis << ": E = " << E;
    }
  EXPECT_GT(tried, 0) << "no displacement inverted some of the patch's tets and not all";
  EXPECT_GT(kept, 0) << "no case kept a patch";
}

TEST(ContactPatch, UnderThePatchTheSubspaceKeepsItsNonlinearRemainder) {
  // The patch subtracts only the quadratic part Ψ₂ of what the subspace holds
  // of its tets; the cubature's nonlinear remainder Ψ − Ψ₂ at W z stays, so a
  // subspace state that crushes a sample under the patch costs what it costs
  // without one. With the remainder cancelled as well, δu relaxed the crushed
  // tets and the handles there were nearly free: a football at 6 m/s stepped
  // at 1/120 s drove z to crush a sample (0.76 MJ held by the subspace and
  // cancelled by the patch) until the patch released it, with a 32 kN spike.
  // Here the cubature holds every tet, and a hat handle near the ball
  // displaced by 0.8 R gives det F = 0.2 on its side. At q = q(t) = q(t − h)
  // (no inertial residual), without gravity, the term's energy is the exact
  // energy of its tets at W z + δu, its nodes' inertia and the contact (each
  // ≥ 0, minimized over δu) less Σ V Ψ₂(W z) over its tets: E + Σ V Ψ₂ ≥ 0
  // for any z. With the remainder cancelled, E + Σ V Ψ₂ would be that
  // minimum less Σ V (Ψ − Ψ₂)(W z): below 0 wherever a crushed tet's
  // remainder exceeds what δu leaves of the tets' energy (checked: such cases occur).
  Avatar a = slab(4);
  Cubature every_tet;
  every_tet.elements = VecXi::LinSpaced(a.tet.num_elements(), 0, a.tet.num_elements() - 1);
  every_tet.barycentric = MatXr::Constant(a.tet.num_elements(), 4, 0.25);
  every_tet.weights = fem::tet_volumes(a.tet);
  a.elastic = every_tet;
  const double R = 0.012;
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = Vec3(0.003, 0.03 + R - 0.001, -0.002);
  ContactPatchOptions o;
  o.subspace_mean_dilatation = false;  // Ψ₂ is then the material's own small-strain energy
  o.patch_radius = 0.02;
  o.patch_radius_per_contact_radius = 0;
  o.max_patch_nodes = 100000;
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(R), Isometry::Identity(), false, o);
  const std::vector<fem::TetGradient> grads = fem::tet_gradients(a.tet);
  const VecX volume = fem::tet_volumes(a.tet);
  int tried = 0, discriminating = 0;
  for (int h = 0; h < a.num_handles(); ++h)
    for (int axis = 0; axis < 3; ++axis)
      for (double sign : {1.0, -1.0}) {
        StepContext ctx = context(a, &frames, false);
        ctx.q_prev.z.segment<3>(3 * h)[axis] = sign * 0.8 * 0.05;  // slab(): hat radius 5 cm
        ctx.q_prev2 = ctx.q_prev;
        const auto cache = begin_term_step(term, ctx);
        const std::vector<int> nodes = term.patch_nodes(ctx);
        if (nodes.empty()) continue;
        std::vector<char> in_patch(size_t(a.tet.num_nodes()), 0);
        for (int n : nodes) in_patch[size_t(n)] = 1;
        double quadratic = 0, remainder = 0, min_det = 1;
        for (int t = 0; t < a.tet.num_elements(); ++t) {
          bool patch_tet = false;
          for (int k = 0; k < 4; ++k) patch_tet = patch_tet || in_patch[size_t(a.tet.elements(t, k))];
          if (!patch_tet) continue;
          const MaterialPoint m(tet_material(a, t), tet_frame(a, t));
          const Mat3 F = subspace_gradient(a, ctx.q_prev.z, grads, t);
          const Mat3 D = F - Mat3::Identity();
          const Eigen::Map<const Vec9> d(D.data());
          const double psi2 = 0.5 * d.dot(linearized_hessian(m) * d);
          quadratic += volume[t] * psi2;
          remainder += volume[t] * (strain_energy_density(F, m) - psi2);
          min_det = std::min(min_det, F.determinant());
        }
        ++tried;
        const double E = term.evaluate(ctx, ctx.q_prev, nullptr, nullptr);
        ASSERT_TRUE(std::isfinite(E)) << "handle " << h << " axis " << axis;
        EXPECT_GE(E + quadratic, -1e-9 * quadratic)
            << "handle " << h << " axis " << axis << " sign " << sign << ": E " << E << ", Σ V Ψ₂ " << quadratic
            << ", min det F " << min_det;
        if (min_det < 0.5 && remainder > E + quadratic) ++discriminating;
      }
  EXPECT_GT(tried, 0) << "no case had a patch";
  EXPECT_GT(discriminating, 0) << "no case crushed a patch tet so that its remainder exceeds the relaxed energy";
}

TEST(ContactPatch, ThePatchIsTheSimulatedNodesWithinItsRadiusOfTheNearSkin) {
  // A 1.2 cm ball 1 mm into the slab's top, body and ball at rest: the near
  // skin is the vertices within the margin of the ball (φ < margin), and the
  // patch every Simulated node within patch_radius of one of them (counted
  // here by brute force).
  const Avatar a = slab(4);
  const double R = 0.012;
  const Vec3 centre(0.003, 0.03 + R - 0.001, -0.002);
  std::map<std::string, WorldFrame> frames;
  frames["ball"].pose.translation() = centre;
  for (double radius : {0.006, 0.011}) {
    ContactPatchOptions o;
    o.patch_radius = radius;
    o.max_patch_nodes = 100000;
    const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(R), Isometry::Identity(), false, o);
    StepContext ctx = context(a, &frames, false);
    const auto cache = begin_term_step(term, ctx);
    const auto r = term.report(ctx, ctx.q_prev);
    std::vector<Vec3> near;
    for (int v = 0; v < a.surface_rest.rows(); ++v) {
      const Vec3 x = a.surface_rest.row(v).transpose();
      if ((x - centre).norm() - R < o.margin) near.push_back(x);
    }
    ASSERT_FALSE(near.empty());
    int expected = 0;
    for (int n = 0; n < a.tet.num_nodes(); ++n) {
      if (a.node_role[n] != int(NodeRole::Simulated)) continue;
      const Vec3 y = a.tet.nodes.row(n).transpose();
      bool within = false;
      for (const Vec3& x : near) within = within || (y - x).norm() <= radius;
      expected += within;
    }
    ASSERT_GT(expected, 0);
    EXPECT_EQ(quantity(r, "patch_nodes"), expected) << "radius " << radius;
  }
}

TEST(ContactPatch, ABroadContactGrowsThePatchToAMultipleOfTheContactRadius) {
  // A half-space 1 mm into the slab's whole top face: the touching skin is
  // its 7 × 5 vertices (1 cm apart), whose spread is 4 cm² along x and 2 cm²
  // along z (a uniform lattice of n points h apart: (n² − 1) h² / 12). The
  // contact radius is 2 σ₂ = 2 √2 cm, and the patch's radius 1.5 times that,
  // 4.243 cm, over the 1 cm given; with the factor 0 it stays 1 cm. Either
  // way the patch is every Simulated node within it of a near vertex.
  const Avatar a = slab(4);
  std::map<std::string, WorldFrame> frames;
  frames["floor"].pose.linear() = Eigen::AngleAxisd(M_PI, Vec3::UnitX()).toRotationMatrix();  // normal −y
  frames["floor"].pose.translation() = Vec3(0, 0.03 - 0.001, 0);
  for (double factor : {1.5, 0.0}) {
    ContactPatchOptions o;
    o.patch_radius = 0.01;
    o.patch_radius_per_contact_radius = factor;
    o.max_patch_nodes = 100000;
    const ContactPatchTerm term("floor", a, std::make_shared<geometry::PlaneSdf>(Vec3(0, 1, 0), 0.0),
                                Isometry::Identity(), false, o);
    StepContext ctx = context(a, &frames, false);
    const auto cache = begin_term_step(term, ctx);
    const auto r = term.report(ctx, ctx.q_prev);
    const double radius = factor > 0 ? 1.5 * 2.0 * std::sqrt(2.0) * 0.01 : 0.01;
    EXPECT_NEAR(quantity(r, "patch_radius"), radius, 1e-12) << factor;
    std::vector<Vec3> near;  // the top face, and the side vertices within the margin of the plane
    for (int v = 0; v < a.surface_rest.rows(); ++v)
      if (0.029 - a.surface_rest(v, 1) < o.margin) near.push_back(a.surface_rest.row(v).transpose());
    int expected = 0;
    for (int n = 0; n < a.tet.num_nodes(); ++n) {
      if (a.node_role[n] != int(NodeRole::Simulated)) continue;
      bool within = false;
      for (const Vec3& x : near) within = within || (a.tet.nodes.row(n).transpose() - x).norm() <= radius;
      expected += within;
    }
    EXPECT_EQ(quantity(r, "patch_nodes"), expected) << factor;
  }
}

TEST(ContactPatch, ADynamicObjectGetsTheOppositeForceAndItsDerivativesMatchFiniteDifferences) {
  // The slab (bones kinematic, 6 handles) and a ball as a rigid body bound
  // second: the term's local system is [z (18) | ball (6)].
  const Avatar a = slab(6);
  const ContactPatchOptions o = ball_options();
  const ContactPatchTerm term("ball", a, std::make_shared<geometry::SphereSdf>(0.012), Isometry::Identity(), true, o);
  for (bool dynamic_bones : {false, true}) {
  SCOPED_TRACE(dynamic_bones ? "bones dynamic" : "bones kinematic");
  StepContext ctx = context(a, nullptr, dynamic_bones);
  Configuration ball, ball_prev;
  ball.bones = {Isometry::Identity()};
  ball.bones[0].translation() = Vec3(0.004, 0.03 + 0.012 - 0.0015, -0.003);  // 1.5 mm into the top
  ball.z = VecX();
  ball_prev = ball;
  DofLayout ball_layout;
  ball_layout.num_bones = 1;
  ball_layout.num_reduced = 0;
  ball_layout.base = ctx.layout.size();
  Configuration q = ctx.q_prev;
  for (int i = 0; i < q.z.size(); ++i) q.z[i] = 4e-4 * std::sin(1.3 * i + 0.2);
  ctx.bound = {{0, 0, &a, ctx.layout, &q, &ctx.q_prev, &ctx.q_prev2},
               {1, 1, nullptr, ball_layout, &ball, &ball_prev, &ball_prev}};
  const auto cache = begin_term_step(term, ctx);
  ASSERT_FALSE(term.patch_nodes(ctx).empty());
  const int n = ctx.layout.size() + 6;
  VecX g = VecX::Zero(n);
  const double E = term.evaluate(ctx, q, &g, nullptr);
  ASSERT_GT(E, 0);
  // Central differences over the body's z and the ball's (ω, v).
  VecX fd(n);
  const double eps = 1e-7;
  for (int i = 0; i < n; ++i) {
    double Es[2];
    for (int sgn = 0; sgn < 2; ++sgn) {
      VecX d = VecX::Zero(n);
      d[i] = sgn ? -eps : eps;
      Configuration qi = retract(q, d, ctx.layout), bi = retract(ball, d, ball_layout);
      ctx.bound[0].q = &qi;
      ctx.bound[1].q = &bi;
      Es[sgn] = term.evaluate(ctx, qi, nullptr, nullptr);
    }
    fd[i] = (Es[0] - Es[1]) / (2 * eps);
  }
  ctx.bound[0].q = &q;
  ctx.bound[1].q = &ball;
  EXPECT_LT((g - fd).norm(), 1e-5 * fd.norm()) << "|g| " << g.norm() << ", |fd| " << fd.norm();
  // The gradient asked with the Hessian (the Newton iteration) is the one asked
  // alone (the final report): the gradient-only evaluation skips only Hessian work.
  // (Asked back to back at one q, both see the same minimizer; the Newton
  // iteration's also takes −Φ_qp Φ_pp⁻¹ Φ_p of its last inner step, below 1e-14 m.)
  VecX g_alone = VecX::Zero(n), g_with_hessian = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  term.evaluate(ctx, q, &g_alone, nullptr);
  term.evaluate(ctx, q, &g_with_hessian, &H);
  const VecX bordered =
      test::bordered_rhs_difference(contact_patch_detail::patch_cache(ctx, term.name()), ctx.layout.z_offset(), n);
  EXPECT_LT((g_with_hessian - g_alone - bordered).norm(), 1e-12 * g_alone.norm()) << "|bordered| " << bordered.norm();
  EXPECT_GT(H.norm(), 0);
  {
    // The q blocks hold nonzeros only in the rows begin_step collected: an
    // evaluation zeroes, and the condensation reads, only those (a row it
    // missed would keep old values and be left out of the step).
    const contact_patch_detail::PatchCache& c = contact_patch_detail::patch_cache(ctx, term.name());
    const int z0 = ctx.layout.z_offset();
    std::vector<char> collected(size_t(n), 0);
    for (int r : c.q_rows) collected[size_t(r)] = 1;
    EXPECT_TRUE(collected[size_t(ctx.layout.size())]) << "the ball's rows";
    for (int r = 0; r < n; ++r) {
      if (collected[size_t(r)]) continue;
      EXPECT_EQ(c.start.Hqq.row(r).cwiseAbs().maxCoeff() + c.start.Hqq.col(r).cwiseAbs().maxCoeff(), 0) << r;
      EXPECT_EQ(c.Hqp.row(r).cwiseAbs().maxCoeff(), 0) << r;
      if (r >= z0 && r < z0 + c.Hzp_stiffening.rows()) {
        EXPECT_EQ(c.Hzp_stiffening.row(r - z0).cwiseAbs().maxCoeff(), 0) << r;
      }
    }
  }
  // The ball's generalized force is the reaction of the contact force on the body: −f along v.
  const auto r = term.report(ctx, q);
  const Vec3 f(quantity(r, "force", 0), quantity(r, "force", 1), quantity(r, "force", 2));
  ASSERT_LT(f.y(), -0.01);  // the ball pushes the slab's top down
  // ∂E/∂v_ball = Σ κ a φ ∂φ/∂v = −Σ κ a φ ∇φ: the force on the body, so the ball gets −f.
  EXPECT_LT((g.segment<3>(ctx.layout.size() + 3) - f).norm(), 1e-6 * f.norm());
  }
}

/// The skin displacement the patches add: each skin vertex takes its tet's
/// nodes' δu barycentrically, summed over the terms of its body; other
/// bodies' reports and other quantities are ignored; a malformed report throws.
TEST(ContactPatch, TheSkinTakesItsTetsNodesPatchDisplacementBarycentrically) {
  const Avatar a = slab(4);
  const int v = 5, t = a.surface_tet[v];
  const int n0 = a.tet.elements(t, 0), n2 = a.tet.elements(t, 2);
  StepReport rep;
  // Two terms displace node n0, one node n2; a third term is on body 1.
  rep.quantities.push_back({"contact:a", 0, "patch_displacement", "m", {double(n0), 1e-3, -2e-3, 0.5e-3}});
  rep.quantities.push_back({"contact:b", 0, "patch_displacement", "m", {double(n0), 2e-3, 0.0, 0.0, double(n2), 0.0, 0.0, 4e-3}});
  rep.quantities.push_back({"contact:c", 1, "patch_displacement", "m", {double(n2), 9.0, 9.0, 9.0}});
  rep.quantities.push_back({"contact:a", 0, "force", "N", {1.0, 2.0, 3.0, 4.0}});
  const Points u = patch_surface_displacement(a, rep, 0);
  ASSERT_EQ(u.rows(), a.surface_rest.rows());
  const double b0 = a.surface_bary(v, 0), b2 = a.surface_bary(v, 2);
  const Vec3 expected = b0 * Vec3(3e-3, -2e-3, 0.5e-3) + b2 * Vec3(0, 0, 4e-3);
  EXPECT_LT((u.row(v).transpose() - expected).norm(), 1e-15) << u.row(v);
  EXPECT_GT(expected.norm(), 1e-4);  // the vertex is displaced at all (barycentric weights not 0)
  // A vertex whose tet has neither node stays.
  for (int w = 0; w < u.rows(); ++w) {
    bool touched = false;
    for (int c = 0; c < 4; ++c) touched |= a.tet.elements(a.surface_tet[w], c) == n0 || a.tet.elements(a.surface_tet[w], c) == n2;
    if (!touched) {
      EXPECT_TRUE(u.row(w).isZero()) << "vertex " << w;
    }
  }
  EXPECT_TRUE(patch_surface_displacement(a, StepReport(), 0).isZero());
  StepReport bad;
  bad.quantities.push_back({"contact:a", 0, "patch_displacement", "m", {double(n0), 1e-3, 0.0}});
  EXPECT_THROW(patch_surface_displacement(a, bad, 0), Error);
  bad.quantities[0].value = {double(a.tet.num_nodes()), 0.0, 0.0, 0.0};
  EXPECT_THROW(patch_surface_displacement(a, bad, 0), Error);
}

TEST(ContactPatch, BadOptionsAreRefusedNamingTheContact) {
  const Avatar a = slab(4);
  auto sphere = std::make_shared<geometry::SphereSdf>(0.01);
  auto make = [&](ContactPatchOptions o) { ContactPatchTerm("probe", a, sphere, Isometry::Identity(), false, o); };
  for (double k : {0.0, -1.0, double(NAN)}) {
    ContactPatchOptions o;
    o.pressure_stiffness = k;
    test::expect_error([&] { make(o); }, {"contact with 'probe'", "pressure stiffness"});
  }
  for (double r : {0.0, -0.01, double(NAN)}) {
    ContactPatchOptions o;
    o.patch_radius = r;
    test::expect_error([&] { make(o); }, {"contact with 'probe'", "patch radius"});
  }
  for (double t : {0.0, -1.0, double(NAN)}) {
    ContactPatchOptions o;
    o.release_time = t;
    test::expect_error([&] { make(o); }, {"contact with 'probe'", "release_time"});
  }
  for (double f : {-1.0, double(NAN)}) {
    ContactPatchOptions o;
    o.patch_radius_per_contact_radius = f;
    test::expect_error([&] { make(o); }, {"contact with 'probe'", "patch_radius_per_contact_radius"});
  }
  ContactPatchOptions o;
  o.spacing = 0;
  test::expect_error([&] { make(o); }, {"contact with 'probe'", "spacing"});
}

}  // namespace
}  // namespace sflsh
