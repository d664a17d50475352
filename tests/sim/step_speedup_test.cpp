// The exact speed-ups of the step ("Faster") change no result:
// - the inertia Hessian assembled from J's block structure equals the dense
//   product Jᵀ M J of the points' full Jacobian (PosedPoints::jacobian);
// - the elastic Hessian assembled into an upper-triangle scratch equals the
//   dense Σ_k c_k G_kᵀ ΠPSD(∂²Ψ/∂F²) G_k, with G_k read off deformation_gradient;
// - a run of dynamic-bone steps ends where the code before the speed-ups
//   ended (golden values recorded with it, to 1e-12);
// - a batch of avatars stepped on several threads gives bit-identical states
//   to stepping them one after the other.
#include <random>

#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/batch_step.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/material.hpp"
#include "sflsh/sim/simulator.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

std::shared_ptr<const Avatar> small_avatar(bool all_tets) {
  test::SyntheticAvatarOptions o;
  o.handles = 8;
  o.handle_radius = 0.07;
  o.all_tets = all_tets;
  o.samples = 12;
  return std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
}

/// A configuration away from rest: bent, moved bones and a random z.
Configuration random_configuration(const Avatar& a, std::mt19937& rng, double z_scale) {
  Configuration q;
  q.bones = test::synthetic_motion(a, 0.13, 0.05, 0.6);
  std::normal_distribution<double> n(0.0, 1.0);
  for (Isometry& G : q.bones) G.translation() += Vec3(0.01 * n(rng), 0.01 * n(rng), 0.01 * n(rng));
  q.z = VecX::NullaryExpr(a.num_reduced(), [&] { return z_scale * n(rng); });
  return q;
}

StepContext context(const Avatar& a, bool bones_dynamic) { return test::soft_step_context(a, bones_dynamic); }

double max_abs(const MatX& m) { return m.cwiseAbs().maxCoeff(); }

TEST(StepSpeedup, InertiaHessianEqualsTheDenseJacobianProduct) {
  const auto a = small_avatar(false);
  const InertiaTerm term(*a);
  std::mt19937 rng(3);
  for (bool dynamic : {false, true}) {
    StepContext ctx = context(*a, dynamic);
    ctx.q_prev = random_configuration(*a, rng, 0.003);
    ctx.q_prev2 = random_configuration(*a, rng, 0.003);
    const auto cache = begin_term_step(term, ctx);
    const Configuration q = random_configuration(*a, rng, 0.003);
    const int n = ctx.layout.size();
    MatX H = MatX::Zero(n, n);
    VecX g = VecX::Zero(n);
    term.evaluate(ctx, q, &g, &H);
    // Reference: the dense Jacobian of every point, rows scaled by √(m_s)/h.
    MatX J;
    term.points().jacobian(q, ctx.layout, J, (term.masses() / (ctx.h * ctx.h)).cwiseSqrt());
    const MatX H_ref = J.transpose() * J;
    ASSERT_GT(max_abs(H_ref), 0.0);
    EXPECT_LE(max_abs(H - H_ref), 1e-12 * max_abs(H_ref)) << (dynamic ? "dynamic" : "kinematic") << " bones";
    EXPECT_LE(max_abs(H - H.transpose()), 1e-15 * max_abs(H_ref));  // symmetric to round-off
  }
}

/// Σ_k c_k G_kᵀ ΠPSD(∂²Ψ/∂F²(F_k)) G_k with dense G_k (9 by 3K); `minus_linear`
/// subtracts the linearized Hessian from each sample (the exact_quadratic split).
MatX dense_sample_hessian(const Avatar& a, const ElasticTerm& term, const VecX& z, bool minus_linear) {
  const int n = a.num_reduced();
  MatX H = MatX::Zero(n, n);
  for (int k = 0; k < term.num_samples(); ++k) {
    // F is affine in z: column j of G is vec(F(e_j)) − vec(I), exactly.
    Eigen::Matrix<double, 9, Eigen::Dynamic> G(9, n);
    for (int j = 0; j < n; ++j) {
      const Mat3 D = term.deformation_gradient(k, VecX::Unit(n, j)) - Mat3::Identity();
      G.col(j) = Eigen::Map<const Vec9>(D.data());
    }
    const int t = a.elastic.elements[k];
    const MaterialPoint m(tet_material(a, t), tet_frame(a, t));
    Mat3 P;
    Mat9 Hk;
    strain_energy_density(term.deformation_gradient(k, z), m, &P, &Hk, true);
    if (minus_linear) Hk -= linearized_hessian(m);
    H += a.elastic.weights[k] * G.transpose() * Hk * G;
  }
  return H;
}

TEST(StepSpeedup, ElasticHessianEqualsTheDenseSampleSum) {
  const auto a = small_avatar(false);
  std::mt19937 rng(5);
  const VecX z = VecX::NullaryExpr(a->num_reduced(), [&] { return std::normal_distribution<double>(0, 0.004)(rng); });
  for (bool exact_quadratic : {false, true}) {
    const ElasticTerm term(*a, true, exact_quadratic, /*mean_dilatation=*/false);  // the samples alone (no guard)
    StepContext ctx = context(*a, false);
    const auto cache = begin_term_step(term, ctx);  // the State's scratch, as in a step
    Configuration q;
    q.bones = identity_bones();
    q.z = z;
    const int n = a->num_reduced();
    MatX H = MatX::Zero(n, n), H0 = MatX::Zero(n, n);
    VecX g = VecX::Zero(n);
    term.evaluate(ctx, q, &g, &H);
    MatX H_ref = dense_sample_hessian(*a, term, z, exact_quadratic);
    if (exact_quadratic) {
      // H(z) − H(0) = Σ_k c_k Gᵀ (ΠPSD H_k(z) − ΠPSD H_k(0)) G: the exact quadratic K cancels.
      q.z.setZero();
      term.evaluate(ctx, q, nullptr, &H0);
      H -= H0;
      H_ref -= dense_sample_hessian(*a, term, VecX::Zero(n), true);
    }
    ASSERT_GT(max_abs(H_ref), 0.0);
    EXPECT_LE(max_abs(H - H_ref), 1e-12 * max_abs(H_ref)) << "exact_quadratic " << exact_quadratic;
    // The same with no cache (EnergyTerm::evaluate on a bare context).
    StepContext bare = context(*a, false);
    MatX H2 = MatX::Zero(n, n);
    q.z = z;
    term.evaluate(bare, q, nullptr, &H2);
    MatX H1 = MatX::Zero(n, n);
    term.evaluate(ctx, q, nullptr, &H1);
    EXPECT_EQ(max_abs(H1 - H2), 0.0);
  }
}

/// `steps` dynamic-bone steps of the synthetic avatar under synthetic_motion.
Configuration run_dynamic(int steps) {
  SimulatorOptions o;
  o.bones_dynamic = true;
  o.mean_dilatation = false;  // the golden values were recorded with every tet's own volume change
  const auto a = small_avatar(false);
  SkeletonTermsOptions skeleton;
  skeleton.spring_inertia = SkeletonTermsOptions::SpringInertia::Segments;  // the springs of that time
  Simulator sim(avatar_model(a, o, &skeleton));
  for (int i = 1; i <= steps; ++i) {
    const StepReport rep = sim.step(test::synthetic_motion(*a, i * o.h));
    EXPECT_EQ(rep.outcome, StepOutcome::Accepted) << "step " << i;
  }
  return sim.state();
}

TEST(StepSpeedup, DynamicBoneRunEndsWhereThePreviousCodeEnded) {
  const Configuration q = run_dynamic(20);
  // Recorded with the code before the speed-ups (commit cb01f7a), %.17g.
  const double z_golden[4] = {-0.00078067552669551727, 0.00032962342673042126, -0.0004424139427351456, -0.00049327620671407496};
  const double t_golden[3] = {-0.00012465486312393653, -0.00078737584978359602, 6.2526056848181372e-05};
  const double r_golden = 0.0017392517334986102;
  const int n = int(q.z.size());
  // Within 1e-12 relative: the speed-ups only reassociate sums (1e-16 per step).
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q.z[i * (n - 1) / 3], z_golden[i], 1e-12 * std::abs(z_golden[i])) << i;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(q.bones[6].translation()[c], t_golden[c], 1e-12 * std::abs(t_golden[c])) << c;
  EXPECT_NEAR(q.bones[3].linear()(0, 1), r_golden, 1e-12 * std::abs(r_golden));
}

TEST(StepSpeedup, ThreadedBatchEqualsSerialStepsBitForBit) {
  SimulatorOptions o;
  o.bones_dynamic = true;
  const auto a = small_avatar(false);
  const SkeletonTermsOptions skeleton;
  const auto model = avatar_model(a, o, &skeleton);
  const int A = 5;
  std::vector<const Model*> models(A, model.get());
  std::vector<State> serial(A, rest_state(*model));
  // Each avatar starts with its own soft deformation (the targets drive
  // only the bones' tracking; the pose targets are the rest pose).
  std::mt19937 rng(11);
  for (int i = 0; i < A; ++i) {
    VecX& z = serial[i].bodies[0].q.z;
    z = VecX::NullaryExpr(z.size(), [&] { return std::normal_distribution<double>(0, 0.002)(rng); });
    serial[i].bodies[0].q_prev.z = z;
  }
  std::vector<State> threaded = serial;
  for (int step = 1; step <= 8; ++step) {
    std::vector<StepInputs> in(A);
    for (int i = 0; i < A; ++i) in[i].bodies.push_back({test::synthetic_motion(*a, step * o.h + 0.1 * i), {}});
    step_batch(models, serial, in, 1);
    std::vector<StepReport> reports;
    step_batch(models, threaded, in, 3, &reports);
    ASSERT_EQ(reports.size(), size_t(A));
  }
  for (int i = 0; i < A; ++i) {
    const Configuration &s = serial[i].bodies[0].q, &t = threaded[i].bodies[0].q;
    EXPECT_EQ(s.z, t.z) << "avatar " << i;  // bit-identical
    for (int j = 0; j < 24; ++j) EXPECT_EQ(s.bones[j].matrix(), t.bones[j].matrix()) << "avatar " << i << " bone " << j;
    EXPECT_EQ(serial[i].time, threaded[i].time);
  }
  // The avatars differ (different phases), so the comparison is not trivial.
  EXPECT_GT((serial[0].bodies[0].q.z - serial[1].bodies[0].q.z).norm(), 0.0);
  // Bad input: one clear error.
  std::vector<StepInputs> too_few(A - 1);
  EXPECT_THROW(step_batch(models, serial, too_few, 2), Error);
}

}  // namespace
}  // namespace sflsh
