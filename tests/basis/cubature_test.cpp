#include "sflsh/basis/cubature.hpp"

#include <gtest/gtest.h>

#include "box_mesh.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/fem/tet_operators.hpp"

namespace sflsh::basis {
namespace {

struct Basis {
  TetMesh mesh = test::box_tet_mesh(12, 4, 8, 0.3, 0.1, 0.2);
  VecXi role;
  HandleSet handles;
  Eigen::SparseMatrix<double, Eigen::RowMajor> W;
  explicit Basis(int K) {
    role = VecXi::Zero(mesh.num_nodes());
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (mesh.nodes(i, 1) < 1e-12) role(i) = int(NodeRole::Bone);
    handles = select_handles(mesh, role, K);
    BbwOptions o;
    o.show_progress = false;
    W = bounded_biharmonic_weights(mesh, role, handles.nodes, o);
  }
};

TEST(Cubature, DataObliviousIsExactOnConstantsAndSitsAtHandles) {
  const Basis b(12);
  // Two bone regions split at x = 0.15.
  VecXi dominant(b.mesh.num_nodes());
  for (int i = 0; i < b.mesh.num_nodes(); ++i) dominant(i) = b.mesh.nodes(i, 0) < 0.15 ? 3 : 7;
  const Cubature c = data_oblivious_cubature(b.mesh, b.W, b.handles.nodes, dominant);
  ASSERT_EQ(c.size(), 12 + 2);
  EXPECT_GT(c.weights.minCoeff(), 0.0);
  const Points x = cubature_points(b.mesh, c);
  for (int k = 0; k < 12; ++k) {
    EXPECT_LT((x.row(k) - b.handles.positions.row(k)).norm(), 1e-15);
    EXPECT_NEAR(c.weights(k), fem::integrate_linear(b.mesh, MatX(b.W).col(k))(0), 1e-15);
  }
  // Bone samples lie in their own region.
  EXPECT_LT(x(12, 0), 0.15);
  EXPECT_GT(x(13, 0), 0.15);
  const VecX rho = VecX::Constant(b.mesh.num_elements(), 1060.0);
  const CubatureErrors e = cubature_errors(b.mesh, c, rho);
  std::printf("cubature (K=12, 2 bone regions): volume %.2e, mass %.2e, quadratic %.3f\n", e.volume_error,
              e.mass_error, e.quadratic_error);
  EXPECT_NEAR(e.volume_full, 0.3 * 0.1 * 0.2, 1e-15);
  EXPECT_LT(std::abs(e.volume_error), 1e-10);
  EXPECT_LT(std::abs(e.mass_error), 1e-10);
  EXPECT_NEAR(e.mass_full, 1060.0 * 0.006, 1e-10);
  // The quadratic field is only approximated (reported above); check the sum itself.
  const Eigen::RowVector3d ctr(0.15, 0.05, 0.1);  // the box centroid
  double q = 0.0;
  for (int s = 0; s < c.size(); ++s) q += c.weights(s) * (x.row(s) - ctr).squaredNorm();
  EXPECT_NEAR(e.quadratic_cubature, q, 1e-15);
  EXPECT_LT(std::abs(e.quadratic_error), 1.0);
}

TEST(Cubature, ErrorsAgainstFullIntegrationAreComputedExactly) {
  const Basis b(4);
  // A one-sample cubature at the box centre with the full volume: volume exact,
  // the quadratic field |x − c|² is 0 there, so its relative error is −1.
  Cubature c;
  const TetMesh& m = b.mesh;
  int centre_tet = -1;
  for (int e = 0; e < m.num_elements() && centre_tet < 0; ++e)
    for (int a = 0; a < 4; ++a)
      if ((m.nodes.row(m.elements(e, a)) - Eigen::RowVector3d(0.15, 0.05, 0.1)).norm() < 1e-12) centre_tet = e;
  ASSERT_GE(centre_tet, 0);
  c.elements = VecXi::Constant(1, centre_tet);
  c.barycentric = MatXr::Zero(1, 4);
  for (int a = 0; a < 4; ++a)
    if ((m.nodes.row(m.elements(centre_tet, a)) - Eigen::RowVector3d(0.15, 0.05, 0.1)).norm() < 1e-12)
      c.barycentric(0, a) = 1.0;
  c.weights = VecX::Constant(1, 0.006);
  const CubatureErrors e = cubature_errors(m, c);
  EXPECT_NEAR(e.volume_error, 0.0, 1e-12);
  EXPECT_NEAR(e.quadratic_error, -1.0, 1e-12);
  // ∫ |x − c|² over the box = V (a² + b² + c²) / 12.
  EXPECT_NEAR(e.quadratic_full, 0.006 * (0.09 + 0.01 + 0.04) / 12.0, 1e-15);
  // A density jump: the sample's tet density stands for the whole volume.
  VecX rho = VecX::Constant(m.num_elements(), 1000.0);
  for (int t = 0; t < m.num_elements(); ++t) {
    double cx = 0;
    for (int a = 0; a < 4; ++a) cx += 0.25 * m.nodes(m.elements(t, a), 0);
    if (cx > 0.15) rho(t) = 2000.0;
  }
  const CubatureErrors em = cubature_errors(m, c, rho);
  EXPECT_NEAR(em.mass_full, 0.003 * 1000.0 + 0.003 * 2000.0, 1e-9);
}

}  // namespace
}  // namespace sflsh::basis
