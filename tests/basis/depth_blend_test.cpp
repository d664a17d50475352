// The default basis: bounded biharmonic weights with free bones,
// normalized to a partition of unity and blended to 0 at the bone by the
// harmonic depth fraction, so every simulated region's skin moves.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "box_mesh.hpp"
#include "limbed_body_mesh.hpp"
#include "mesh_boundary.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/basis/basis_coverage.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/basis/depth_fraction.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"

namespace sflsh::basis {
namespace {

BbwOptions quiet(BoneCondition c = BoneCondition::DepthBlend) {
  BbwOptions o;
  o.show_progress = false;
  o.bone_condition = c;
  return o;
}

/// A 0.3 m cube of flesh on a bone face y = 0 (6 cubes a side).
struct Cube {
  TetMesh mesh = test::box_tet_mesh(6, 6, 6, 0.3, 0.3, 0.3);
  VecXi role = test::bone_floor_roles(mesh);
};

TEST(DepthFraction, ZeroAtBoneOneOnSkinHarmonicInside) {
  const Cube c;
  // Skin: the boundary nodes that are not Bone (brute force).
  std::set<int> skin;
  for (int i : test::boundary_nodes(c.mesh))
    if (c.role(i) == 0) skin.insert(i);
  const VecXi found = skin_nodes(c.mesh, c.role);
  EXPECT_EQ(std::set<int>(found.data(), found.data() + found.size()), skin);
  ASSERT_EQ(int(skin.size()), 7 * 7 * 7 - 5 * 5 * 5 - 7 * 7);  // boundary nodes minus the bone face

  const VecX b = depth_fraction(c.mesh, c.role);
  const VecX Lb = fem::stiffness_laplacian(c.mesh) * b;
  int interior = 0;
  for (int i = 0; i < c.mesh.num_nodes(); ++i) {
    if (c.role(i) != 0) {
      EXPECT_EQ(b(i), 0.0) << "bone node " << i;
    } else if (skin.count(i)) {
      EXPECT_EQ(b(i), 1.0) << "skin node " << i;
    } else {
      ++interior;
      EXPECT_NEAR(Lb(i), 0.0, 1e-12) << "interior node " << i << ": not harmonic";  // the defining equation
      EXPECT_GT(b(i), 0.0);
      EXPECT_LT(b(i), 1.0);
    }
  }
  EXPECT_EQ(interior, 5 * 5 * 5);
  // Maximum principle along the centre column: rising from the bone.
  double prev = 0.0;
  for (int j = 1; j <= 5; ++j) {
    for (int i = 0; i < c.mesh.num_nodes(); ++i)
      if ((c.mesh.nodes.row(i) - Eigen::RowVector3d(0.15, 0.05 * j, 0.15)).norm() < 1e-12) {
        EXPECT_GT(b(i), prev) << "height " << j;
        prev = b(i);
      }
  }
}

// Every stored row is b_i · w̃_i / max(Σ w̃_i, floor), with w̃ the QP solutions
// recomputed here with bones free (only handles and Skinned nodes fixed).
TEST(DepthBlend, RowsAreNormalizedFreeBoneSolutionsTimesDepth) {
  const test::LimbedBody body;
  const VecXi region = node_regions_from_tets(body.mesh, body.tet_region, 3);
  const int K = 8;
  const HandleSet hs = select_handles(body.mesh, body.role, K, body.thickness, region);
  BbwOptions o = quiet();
  o.drop_tolerance = 0.0;
  BbwReport rep;
  const MatX W = MatX(bounded_biharmonic_weights(body.mesh, body.role, hs.nodes, o, &rep));
  std::vector<int> fixed(hs.nodes.data(), hs.nodes.data() + K);
  for (int i = 0; i < body.mesh.num_nodes(); ++i)
    if (body.role(i) == int(NodeRole::Skinned)) fixed.push_back(i);
  MatX bc = MatX::Zero(Eigen::Index(fixed.size()), K);
  for (int k = 0; k < K; ++k) bc(k, k) = 1.0;
  const MatX Q = bounded_biharmonic_qp(body.mesh, Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size())), bc, o);
  const VecX b = depth_fraction(body.mesh, body.role);
  double worst = 0.0;
  for (int i = 0; i < body.mesh.num_nodes(); ++i) {
    const Eigen::RowVectorXd expected = body.role(i) == 0 ? Eigen::RowVectorXd(b(i) * Q.row(i) / std::max(Q.row(i).sum(), o.normalization_floor))
                                               : Eigen::RowVectorXd(Eigen::RowVectorXd::Zero(K));
    worst = std::max(worst, (W.row(i) - expected).lpNorm<Eigen::Infinity>());
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(rep.partition_error, 1e-12);
  EXPECT_LT(rep.max_bound_violation, 1e-12);
}

TEST(DepthBlend, CoversEveryRegionsSkinOfTheLimbedBody) {
  const test::LimbedBody body;
  const VecXi region = node_regions_from_tets(body.mesh, body.tet_region, 3);
  const int K = 12;
  const HandleSet hs = select_handles(body.mesh, body.role, K, body.thickness, region);
  const auto Ws = bounded_biharmonic_weights(body.mesh, body.role, hs.nodes, quiet());
  const MatX W = MatX(Ws);
  const MatX W_old = MatX(bounded_biharmonic_weights(body.mesh, body.role, hs.nodes, quiet(BoneCondition::Dirichlet)));
  const VecX b = depth_fraction(body.mesh, body.role);
  int skin[3] = {0, 0, 0}, covered[3] = {0, 0, 0}, covered_old[3] = {0, 0, 0};
  for (int i : test::boundary_nodes(body.mesh)) {
    if (body.role(i) != 0) continue;
    const int r = test::LimbedBody::region_at(body.mesh.nodes(i, 0));
    ++skin[r];
    covered[r] += W.row(i).sum() >= 0.5;
    covered_old[r] += W_old.row(i).sum() >= 0.5;
  }
  for (int r = 0; r < 3; ++r) {
    std::printf("region %d: %d skin nodes, sum >= 0.5: Dirichlet bones %d, depth blend %d\n", r, skin[r],
                covered_old[r], covered[r]);
    EXPECT_GE(covered[r], 0.95 * skin[r]) << "region " << r;  // the issue-13 target
  }
  EXPECT_LT(covered_old[1], 0.5 * skin[1]);  // the defect the blend fixes
  // Partition of unity with the bone complement 1 − b, bounds, Dirichlet zeros,
  // handle interpolation on the skin.
  const VecXi skin_list = skin_nodes(body.mesh, body.role);
  const std::set<int> on_skin(skin_list.data(), skin_list.data() + skin_list.size());
  EXPECT_GE(W.minCoeff(), 0.0);
  for (int i = 0; i < body.mesh.num_nodes(); ++i) {
    if (body.role(i) != 0) {
      EXPECT_EQ(W.row(i).lpNorm<Eigen::Infinity>(), 0.0) << "Dirichlet node " << i;
      continue;
    }
    EXPECT_NEAR(W.row(i).sum(), b(i), K * BbwOptions().drop_tolerance) << "node " << i;
  }
  for (int k = 0; k < K; ++k)
    if (on_skin.count(hs.nodes(k)))
      for (int j = 0; j < K; ++j) EXPECT_EQ(W(hs.nodes(k), j), k == j ? 1.0 : 0.0) << "handle " << k;
  // The library's coverage agrees.
  const BasisCoverage cov = basis_coverage(Ws, body.role, skin_list, region, 3, hs.nodes);
  EXPECT_EQ(cov.covered, covered[0] + covered[1] + covered[2]);
  EXPECT_GE(cov.share(), 0.95);
}

TEST(DepthBlend, RejectsANonPositiveFloor) {
  const Cube c;
  BbwOptions o = quiet();
  o.normalization_floor = 0.0;
  EXPECT_THROW(bounded_biharmonic_weights(c.mesh, c.role, select_handles(c.mesh, c.role, 2).nodes, o), Error);
}

}  // namespace
}  // namespace sflsh::basis
