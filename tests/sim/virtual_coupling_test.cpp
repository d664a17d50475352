// Virtual coupling term: the energy against its closed form
// computed by hand (½k r² + k_r (1 − cos θ) + the dampers), the gradient
// against central differences, the Hessian against second differences where
// it is exact (tool origin at the pivot, rotational damper residual zero) and
// positive semi-definite everywhere, and the reported force and torque.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/virtual_coupling.hpp"
#include "sim/finite_difference.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

constexpr double kH = 1.0 / 500.0;

struct Rig {
  DofLayout layout;
  Configuration q, q_prev;
  std::optional<WorldFrame> device;  ///< the term's input frame (device_frame_name)
  std::unique_ptr<TermCache> cache;

  StepContext context() const {
    StepContext ctx;
    ctx.layout = layout;
    ctx.h = kH;
    ctx.q_prev = q_prev;
    ctx.q_prev2 = q_prev;
    ctx.frames = {device ? &*device : nullptr};
    ctx.cache = cache.get();
    return ctx;
  }
};

Isometry pose(const Vec3& axis_angle, const Vec3& t) {
  Isometry G = Isometry::Identity();
  G.linear() = rodrigues(axis_angle);
  G.translation() = t;
  return G;
}

Rig make_rig(const VirtualCouplingTerm& term, const Isometry& tool, const Isometry& tool_prev, const WorldFrame& device) {
  Rig r;
  r.layout.num_bones = 1;
  r.layout.num_reduced = 0;
  r.layout.bone_pivots = Points::Zero(1, 3);
  r.q.bones = {tool};
  r.q.z = VecX(0);
  r.q_prev.bones = {tool_prev};
  r.q_prev.z = VecX(0);
  r.device = device;
  r.cache = term.make_cache();
  term.begin_step(r.context());
  return r;
}

}  // namespace

TEST(VirtualCoupling, EnergyMatchesTheClosedFormByHand) {
  VirtualCouplingOptions o{3000.0, 40.0, 7.0, 0.3};
  VirtualCouplingTerm term("probe", o);
  // Tool 2 cm above the device and turned 0.4 rad about z; it moved 1 mm in x
  // and 0.01 rad about z over the step; the device moves at 0.2 m/s in y.
  const double th = 0.4;
  WorldFrame dev;
  dev.pose = pose(Vec3::Zero(), Vec3(0.1, 1.0, 0.2));
  dev.linear_velocity = Vec3(0, 0.2, 0);
  const Isometry tool = pose(Vec3(0, 0, th), Vec3(0.1, 1.02, 0.2));
  const Isometry tool_prev = pose(Vec3(0, 0, th - 0.01), Vec3(0.099, 1.02, 0.2));
  Rig r = make_rig(term, tool, tool_prev, dev);
  // r = (0, 0.02, 0); s = (c − c_t) − h v_d = (0.001, 0, 0) − (0, 0.2 h, 0).
  const Vec3 s(0.001, -0.2 * kH, 0.0);
  const double expected = 0.5 * 3000 * 0.02 * 0.02 + 0.5 * (40 / kH) * s.squaredNorm() + 7.0 * (1 - std::cos(th)) +
                          0.5 * (0.3 / kH) * 0.01 * 0.01;
  EXPECT_NEAR(term.evaluate(r.context(), r.q, nullptr, nullptr), expected, 1e-9 * expected);

  // Force on the tool: −(k r + c/h s); torque about z: −k_r sin θ − c_r/h · 0.01.
  const auto rep = term.report(r.context(), r.q);
  ASSERT_EQ(rep[0].name, "force");
  const Vec3 f_expected = -(3000 * Vec3(0, 0.02, 0) + (40 / kH) * s);
  EXPECT_LT((Vec3(rep[0].value) - f_expected).norm(), 1e-9 * f_expected.norm());
  ASSERT_EQ(rep[1].name, "torque");
  EXPECT_NEAR(rep[1].value[2], -7.0 * std::sin(th) - (0.3 / kH) * 0.01, 1e-9);
  EXPECT_NEAR(rep[1].value[0], 0.0, 1e-12);
  EXPECT_NEAR(rep[3].value[0], th, 1e-12);
}

TEST(VirtualCoupling, GradientMatchesFiniteDifferencesAndHessianIsPositiveSemidefinite) {
  VirtualCouplingTerm term("probe", VirtualCouplingOptions{2.0e4, 50.0, 20.0, 0.2});
  std::mt19937 rng(11);
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 8; ++trial) {
    const Vec3 aa = 0.5 * Vec3(n(rng), n(rng), n(rng));
    const Isometry tool = pose(aa, Vec3(0.3, 1.1, -0.2) + 0.01 * Vec3(n(rng), n(rng), n(rng)));
    const Isometry tool_prev = pose(aa + 0.01 * Vec3(n(rng), n(rng), n(rng)), tool.translation() + 0.002 * Vec3(n(rng), n(rng), n(rng)));
    WorldFrame dev;
    dev.pose = pose(aa + 0.6 * Vec3(n(rng), n(rng), n(rng)), Vec3(0.3, 1.1, -0.2));
    dev.linear_velocity = 0.3 * Vec3(n(rng), n(rng), n(rng));
    dev.angular_velocity = 2.0 * Vec3(n(rng), n(rng), n(rng));
    Rig r = make_rig(term, tool, tool_prev, dev);
    const StepContext ctx = r.context();
    const test::TermDerivatives d = test::analytic(term, ctx, r.q);
    const VecX fd = test::fd_gradient(term, ctx, r.q, 1e-6);
    EXPECT_LT((d.grad - fd).norm(), 1e-5 * fd.norm()) << "trial " << trial << "\n" << d.grad.transpose() << "\n"
                                                       << fd.transpose();
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<MatX>(d.hess).eigenvalues().minCoeff(), -1e-9 * d.hess.norm());
  }
}

TEST(VirtualCoupling, HessianMatchesSecondDifferencesWhereItIsExact) {
  // Tool origin at the pivot (the translation does not depend on ω) and the
  // rotational damper's residual zero (device angular velocity = the tool's):
  // every neglected curvature vanishes, so H is the exact Hessian.
  VirtualCouplingTerm term("probe", VirtualCouplingOptions{2.0e4, 50.0, 20.0, 0.2});
  const Isometry tool_prev = pose(Vec3(0.2, -0.1, 0.3), Vec3(0.001, 0, 0));
  const Isometry tool = pose(Vec3(0.21, -0.08, 0.33), Vec3::Zero());
  WorldFrame dev;
  dev.pose = pose(Vec3(-0.3, 0.4, 0.1), Vec3(0.004, -0.003, 0.002));
  dev.linear_velocity = Vec3(0.1, 0, 0);
  dev.angular_velocity = rotation_log(tool.linear() * tool_prev.linear().transpose()) / kH;
  Rig r = make_rig(term, tool, tool_prev, dev);
  const StepContext ctx = r.context();
  const test::TermDerivatives d = test::analytic(term, ctx, r.q);
  std::mt19937 rng(3);
  EXPECT_LT(test::hessian_fd_error(term, ctx, r.q, d.hess, 1e-4, 20, rng), 1e-5);
  // The translation block is (k + c/h) I.
  EXPECT_LT((d.hess.block<3, 3>(3, 3) - (2.0e4 + 50.0 / kH) * Mat3::Identity()).norm(), 1e-6);
}

TEST(VirtualCoupling, RejectsBadOptionsAndAMissingDeviceFrame) {
  test::expect_error([] { VirtualCouplingTerm("probe", VirtualCouplingOptions{0.0, 1, 1, 1}); }, {"probe", "stiffness"});
  test::expect_error([] { VirtualCouplingTerm("probe", VirtualCouplingOptions{1, -1, 1, 1}); }, {"probe", "damping"});
  VirtualCouplingTerm term("probe", VirtualCouplingOptions{});
  Rig r = make_rig(term, Isometry::Identity(), Isometry::Identity(), WorldFrame{});
  r.device.reset();
  test::expect_error([&] { term.begin_step(r.context()); }, {"coupling:probe", "probe/device"});
}

TEST(VirtualCoupling, TheRotationalDamperSeesTheDeviceTurning) {
  // The device turns at ω_d = 2 rad/s about z; the tool turned 0.01 rad about z
  // over the step. The damper's residual is e = φ − h ω_d = (0.01 − 2 h) ẑ: it
  // resists the tool turning relative to the device (a device turning with the
  // tool leaves no damping), energy ½ (c_r/h) e², torque −(c_r/h) e (φ small
  // and along z: J_l⁻¹(φ)ᵀ e = e).
  VirtualCouplingOptions o{3000.0, 40.0, 7.0, 0.3};
  VirtualCouplingTerm term("probe", o);
  WorldFrame dev;
  dev.pose = pose(Vec3(0, 0, 0.2), Vec3(0.1, 1.0, 0.2));
  dev.angular_velocity = Vec3(0, 0, 2.0);
  const Isometry tool = pose(Vec3(0, 0, 0.2), Vec3(0.1, 1.0, 0.2));
  const Isometry tool_prev = pose(Vec3(0, 0, 0.19), Vec3(0.1, 1.0, 0.2));
  Rig r = make_rig(term, tool, tool_prev, dev);
  const double e = 0.01 - 2.0 * kH;
  const double expected = 0.5 * (0.3 / kH) * e * e;  // translation and spring terms are zero here
  EXPECT_NEAR(term.evaluate(r.context(), r.q, nullptr, nullptr), expected, 1e-9 * expected);
  const auto rep = term.report(r.context(), r.q);
  ASSERT_EQ(rep[1].name, "torque");
  EXPECT_NEAR(rep[1].value[2], -(0.3 / kH) * e, 1e-9);
  // The device turning exactly with the tool (ω_d h = 0.01): no damping torque.
  dev.angular_velocity = Vec3(0, 0, 0.01 / kH);
  Rig same = make_rig(term, tool, tool_prev, dev);
  EXPECT_NEAR(term.report(same.context(), same.q)[1].value[2], 0.0, 1e-9);
}
