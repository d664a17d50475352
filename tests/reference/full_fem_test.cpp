// The full-FEM reference: convergence, stationarity, rest, equilibrium.
#include <gtest/gtest.h>

#include "sflsh/reference/full_fem.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh {
namespace {

std::shared_ptr<const Avatar> mesh_avatar() {
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  return std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
}

TEST(FullFem, RestStaysAtRest) {
  FullFemOptions o;
  o.gravity = Vec3::Zero();
  FullFem fem(mesh_avatar(), o);
  for (int i = 0; i < 5; ++i) {
    const FullFemReport rep = fem.step(std::vector<Isometry>(24, Isometry::Identity()));
    EXPECT_TRUE(rep.converged);
  }
  EXPECT_EQ(fem.displacement().norm(), 0.0);
}

TEST(FullFem, ConvergesQuadraticallyToAStationaryPoint) {
  const auto a = mesh_avatar();
  FullFem fem(a);
  for (int i = 1; i <= 6; ++i) {
    const FullFemReport rep = fem.step(test::synthetic_motion(*a, i / 60.0, 0.03, 0.5));
    EXPECT_TRUE(rep.converged) << "step " << i;
    EXPECT_LE(rep.iterations, 12) << "step " << i;
    EXPECT_LT(rep.grad_norm, 1e-9 * rep.grad_norm_initial);
  }
  // Stationarity by finite differences of the step energy at the result.
  const Points u = fem.displacement();
  const double E = fem.energy(u), eps = 1e-7;
  double worst = 0, scale = 0;
  for (int n = 0; n < u.rows(); ++n) {
    if (a->node_role[n] != int(NodeRole::Simulated)) continue;
    for (int c = 0; c < 3; ++c) {
      Points up = u, um = u;
      up(n, c) += eps;
      um(n, c) -= eps;
      const double Ep = fem.energy(up), Em = fem.energy(um);
      worst = std::max(worst, std::abs(Ep - Em) / (2 * eps));
      scale = std::max(scale, (Ep - 2 * E + Em) / (eps * eps) * u.cwiseAbs().maxCoeff());
      EXPECT_GE(std::min(Ep, Em), E - 1e-15 * std::abs(E));
    }
  }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, 1e-6 * scale);  // |∂E/∂u| ≪ stiffness × displacement
  EXPECT_GT(u.cwiseAbs().maxCoeff(), 1e-5);
}

TEST(FullFem, SurfaceFollowsTheNodes) {
  const auto a = mesh_avatar();
  FullFem fem(a);
  const auto bones = test::synthetic_motion(*a, 0.1);
  fem.step(bones);
  const Points s = fem.posed_surface(), u = fem.soft_displacement();
  for (int v = 0; v < s.rows(); ++v) {
    const int n = a->surface_nodes[v];
    EXPECT_LT((u.row(v) - fem.displacement().row(n)).norm(), 1e-15);
    Vec3 x = Vec3::Zero();
    const Vec3 y = (a->tet.nodes.row(n) + fem.displacement().row(n)).transpose();
    for (int j = 0; j < 24; ++j) x += a->node_weights(n, j) * (bones[j] * y);
    EXPECT_LT((s.row(v).transpose() - x).norm(), 1e-14);
  }
}

}  // namespace
}  // namespace sflsh
