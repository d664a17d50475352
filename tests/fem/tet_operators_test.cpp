#include "sflsh/fem/tet_operators.hpp"

#include <gtest/gtest.h>

#include "basis/box_mesh.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::fem {
namespace {

TEST(TetOperators, BoxMeshIsPositiveAndFillsTheBox) {
  const TetMesh m = test::box_tet_mesh(3, 4, 2, 0.3, 0.2, 0.1);
  const VecX v = tet_volumes(m);
  EXPECT_GT(v.minCoeff(), 0.0);
  EXPECT_NEAR(v.sum(), 0.3 * 0.2 * 0.1, 1e-15);
}

TEST(TetOperators, WeightedLaplacianIntegratesTheWeightedGradient) {
  // w = 3 on the tets with centroid x < 0.5, 1 elsewhere: for f = a·x,
  // fᵀLf = Σ_e w_e V_e |a|² = |a|² (3·0.5 + 1·0.5)·0.6·0.5 (each half is whole cubes).
  const TetMesh m = test::box_tet_mesh(4, 3, 3, 1.0, 0.6, 0.5);
  VecX w(m.num_elements());
  for (int e = 0; e < m.num_elements(); ++e) {
    double cx = 0;
    for (int c = 0; c < 4; ++c) cx += m.nodes(m.elements(e, c), 0) / 4;
    w[e] = cx < 0.5 ? 3.0 : 1.0;
  }
  const Vec3 a(0.3, -1.2, 2.0);
  const VecX f = m.nodes * a;
  EXPECT_NEAR(f.dot(stiffness_laplacian(m, w) * f), a.squaredNorm() * 2.0 * 0.6 * 0.5, 1e-10);
  EXPECT_THROW(stiffness_laplacian(m, VecX::Ones(3)), Error);
}

TEST(TetOperators, LaplacianAnnihilatesLinearFieldsAndIsSymmetricPsd) {
  const TetMesh m = test::box_tet_mesh(4, 3, 3, 1.0, 0.6, 0.5);
  const auto L = stiffness_laplacian(m);
  const VecX ones = VecX::Ones(m.num_nodes());
  EXPECT_LT((L * ones).lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_LT((Eigen::SparseMatrix<double>(L.transpose()) - L).norm(), 1e-12);
  // f = a·x: L f vanishes at interior nodes, and fᵀLf = ∫|∇f|² = |a|²·volume.
  const Vec3 a(0.3, -1.2, 2.0);
  const VecX f = m.nodes * a;
  const VecX Lf = L * f;
  int interior = 0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const auto x = m.nodes.row(i);
    const bool inner = x(0) > 1e-9 && x(0) < 1.0 - 1e-9 && x(1) > 1e-9 && x(1) < 0.6 - 1e-9 && x(2) > 1e-9 &&
                       x(2) < 0.5 - 1e-9;
    if (inner) {
      EXPECT_NEAR(Lf(i), 0.0, 1e-12) << "node " << i;
      ++interior;
    }
  }
  EXPECT_EQ(interior, 3 * 2 * 2);
  EXPECT_NEAR(f.dot(Lf), a.squaredNorm() * 0.3, 1e-12);
  // PSD on random fields.
  for (int t = 0; t < 5; ++t) {
    const VecX r = VecX::Random(m.num_nodes());
    EXPECT_GE(r.dot(L * r), 0.0);
  }
}

TEST(TetOperators, MassMatricesIntegrateConstantsAndLinears) {
  const TetMesh m = test::box_tet_mesh(3, 2, 5, 0.4, 0.2, 1.0);
  const double V = 0.4 * 0.2 * 1.0;
  const VecX ml = lumped_mass(m);
  const auto M = consistent_mass(m);
  const VecX ones = VecX::Ones(m.num_nodes());
  EXPECT_NEAR(ml.sum(), V, 1e-14);
  EXPECT_NEAR(ones.dot(M * ones), V, 1e-14);
  // ∫ z dV = V·0.5 (consistent and linear integration), ∫ z² dV = V/3 (z is P1, so its consistent-mass norm is exact).
  const VecX z = m.nodes.col(2);
  EXPECT_NEAR(ones.dot(M * z), 0.5 * V, 1e-14);
  EXPECT_NEAR(integrate_linear(m, z)(0), 0.5 * V, 1e-14);
  EXPECT_NEAR(z.dot(M * z), V / 3.0, 1e-14);
}

TEST(TetOperators, RejectsInvertedTetsAndBadIndices) {
  TetMesh m = test::box_tet_mesh(1, 1, 1, 1, 1, 1);
  std::swap(m.elements(2, 0), m.elements(2, 1));
  try {
    tet_gradients(m);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("element 2"), std::string::npos) << e.what();
  }
  TetMesh bad = test::box_tet_mesh(1, 1, 1, 1, 1, 1);
  bad.elements(0, 3) = 99;
  EXPECT_THROW(tet_volumes(bad), Error);
}

}  // namespace
}  // namespace sflsh::fem
