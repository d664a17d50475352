// Sample masses take the density of their own tet's region: a synthetic
// avatar with two regions of very different density, one inertia sample per
// tet (weight = the tet's volume), ordered so that the first sample lies in
// the lighter region. Masses are checked per sample against ρ_region · V_tet
// computed here from the node coordinates, and in total against the mesh mass.
#include <gtest/gtest.h>

#include "sflsh/sim/energies/inertia.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

double tet_volume(const Avatar& a, int t) {
  Mat3 D;
  for (int c = 1; c < 4; ++c)
    D.col(c - 1) = (a.tet.nodes.row(a.tet.elements(t, c)) - a.tet.nodes.row(a.tet.elements(t, 0))).transpose();
  return D.determinant() / 6;
}

TEST(InertiaDensity, EachSampleTakesTheDensityOfItsOwnRegion) {
  test::SyntheticAvatarOptions o;
  o.handles = 4;
  Avatar a = test::make_synthetic_avatar(o);
  ASSERT_EQ(a.materials.size(), 2u);
  a.materials[0].density = 900;
  a.materials[1].density = 1500;
  // One sample per tet, region-0 tets first, at an off-centre point.
  std::vector<int> order;
  for (int region : {0, 1})
    for (int t = 0; t < a.tet.num_elements(); ++t)
      if (a.tet_region[t] == region) order.push_back(t);
  const int S = int(order.size());
  a.inertia.elements.resize(S);
  a.inertia.barycentric.resize(S, 4);
  a.inertia.weights.resize(S);
  for (int s = 0; s < S; ++s) {
    a.inertia.elements[s] = order[s];
    a.inertia.barycentric.row(s) << 0.1, 0.2, 0.3, 0.4;
    a.inertia.weights[s] = tet_volume(a, order[s]);
  }
  int in_region1 = 0;
  for (int t : order) in_region1 += a.tet_region[t] == 1;
  ASSERT_GT(in_region1, 0);
  ASSERT_LT(in_region1, S);

  const InertiaTerm term(a);
  const VecX& m = term.masses();
  ASSERT_EQ(m.size(), S);
  double mesh_mass = 0;
  for (int s = 0; s < S; ++s) {
    const int t = order[s];
    const double rho = a.tet_region[t] == 0 ? 900.0 : 1500.0;
    EXPECT_NEAR(m[s], rho * tet_volume(a, t), 1e-12 * rho * tet_volume(a, t)) << "sample " << s << " in tet " << t;
    mesh_mass += rho * tet_volume(a, t);
  }
  EXPECT_NEAR(m.sum(), mesh_mass, 1e-12 * mesh_mass);
  EXPECT_NEAR(cubature_masses(a, a.inertia).sum(), mesh_mass, 1e-12 * mesh_mass);
}

// The kinetic term in closed form for a rigid translation: with every bone
// moved by 0 at t − h and by d at t (z = 0), the prediction is x₀ + 2d, so at
// q = q_prev the energy is Σ m_s |d|² / (2h²) = M |d|² / (2h²) — the body
// keeps its velocity d/h. (Predicting x_prev, i.e. dropping the velocity,
// gives 0 here and passed every finite-difference test.)
TEST(InertiaDensity, RigidTranslationEnergyIsTheKineticEnergyOfTheVelocity) {
  test::SyntheticAvatarOptions o;
  o.handles = 4;
  const Avatar a = test::make_synthetic_avatar(o);
  InertiaTerm term(a);
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = true;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.h = 1.0 / 60;
  const Vec3 d(0.003, -0.002, 0.001);
  Configuration rest, moved;
  rest.z = moved.z = VecX::Zero(a.num_reduced());
  for (int j = 0; j < 24; ++j) {
    rest.bones.push_back(Isometry::Identity());
    Isometry G = Isometry::Identity();
    G.translation() = d;
    moved.bones.push_back(G);
  }
  ctx.q_prev2 = rest;
  ctx.q_prev = moved;
  const auto cache = begin_term_step(term, ctx);
  const double M = term.masses().sum();
  EXPECT_NEAR(term.evaluate(ctx, moved, nullptr, nullptr), M * d.squaredNorm() / (2 * ctx.h * ctx.h),
              1e-9 * M * d.squaredNorm() / (ctx.h * ctx.h));
  // At the prediction itself (moved by 2d) the energy is 0.
  Configuration predicted = moved;
  for (auto& G : predicted.bones) G.translation() = 2 * d;
  EXPECT_NEAR(term.evaluate(ctx, predicted, nullptr, nullptr), 0.0, 1e-12 * M * d.squaredNorm() / (ctx.h * ctx.h));
}

}  // namespace
}  // namespace sflsh
