// The reduced solver with all handles (W = identity on Simulated nodes, elastic
// cubature = every tet at its barycentre with its volume, inertia cubature =
// nodes with lumped volumes) is the same discretization as the full-FEM
// reference; converged, both must agree on a prescribed motion.
#include <iostream>

#include <gtest/gtest.h>

#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh {
namespace {

TEST(ReducedVsFull, AllHandlesAgreeWithTheReference) {
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  o.two_regions = false;  // lumped node masses use one tet's density: equal only for one region
  const auto a = std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
  SimulatorOptions so;
  so.newton.iterations = 50;
  so.newton.line_search = true;
  so.newton.gradient_tolerance = 1e-13;
  so.newton.max_z_step = 0;
  so.mean_dilatation = false;  // the nodal basis is full FEM only with every tet's own volume change
  Simulator reduced(avatar_model(a, so));
  FullFem full(a);
  std::vector<int> handle_node;  // handle k sits on Simulated node handle_node[k]
  for (int n = 0; n < a->tet.num_nodes(); ++n)
    if (a->node_role[n] == int(NodeRole::Simulated)) handle_node.push_back(n);
  ASSERT_EQ(int(handle_node.size()), a->num_handles());

  double worst = 0, peak = 0;
  for (int i = 1; i <= 12; ++i) {
    const auto bones = test::synthetic_motion(*a, i * so.h, 0.03, 0.5);
    reduced.step(bones);
    const FullFemReport rep = full.step(bones);
    ASSERT_TRUE(rep.converged) << "step " << i;
    for (int k = 0; k < a->num_handles(); ++k) {
      const Vec3 diff = reduced.state().z.segment<3>(3 * k) - full.displacement().row(handle_node[k]).transpose();
      worst = std::max(worst, diff.norm());
      peak = std::max(peak, full.displacement().row(handle_node[k]).norm());
    }
    EXPECT_LT((reduced.posed_surface() - full.posed_surface()).cwiseAbs().maxCoeff(), 1e-6 * peak + 1e-12);
  }
  std::cout << "[ reduced vs full ] peak |u| " << peak << " m, largest nodal difference " << worst << " m\n";
  ASSERT_GT(peak, 1e-4);
  EXPECT_LT(worst, 1e-6 * peak);
}

}  // namespace
}  // namespace sflsh
