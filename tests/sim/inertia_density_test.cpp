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

}  // namespace
}  // namespace sflsh
