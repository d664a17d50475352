#include "sflsh/basis/handle_placement.hpp"

#include <gtest/gtest.h>

#include <set>

#include "box_mesh.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

struct Slab {
  TetMesh mesh = test::box_tet_mesh(16, 3, 8, 0.4, 0.06, 0.2);
  VecXi role = test::bone_floor_roles(mesh);
};

TEST(HandlePlacement, DeterministicDistinctSimulated) {
  const Slab s;
  const HandleSet a = select_handles(s.mesh, s.role, 12);
  const HandleSet b = select_handles(s.mesh, s.role, 12);
  ASSERT_EQ(a.nodes.size(), 12);
  EXPECT_EQ(a.nodes, b.nodes);
  std::set<int> unique(a.nodes.data(), a.nodes.data() + a.nodes.size());
  EXPECT_EQ(unique.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    EXPECT_EQ(s.role(a.nodes(k)), 0);
    EXPECT_EQ(a.positions.row(k), s.mesh.nodes.row(a.nodes(k)));
  }
  // Spread out: no two handles closer than a cell diagonal.
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < k; ++j) EXPECT_GT((a.positions.row(k) - a.positions.row(j)).norm(), 0.04);
}

TEST(HandlePlacement, DenserWhereTissueIsThicker) {
  const Slab s;
  VecX thick(s.mesh.num_nodes());
  for (int i = 0; i < s.mesh.num_nodes(); ++i) thick(i) = s.mesh.nodes(i, 0) > 0.2 ? 0.06 : 0.02;
  const int K = 20;
  const HandleSet hs = select_handles(s.mesh, s.role, K, thick);
  int in_thick = 0;
  for (int k = 0; k < K; ++k) in_thick += hs.positions(k, 0) > 0.2;
  std::printf("handles in the 3x thicker half: %d of %d\n", in_thick, K);
  EXPECT_GE(in_thick, 14);  // uniform thickness would give about half
  const HandleSet uniform = select_handles(s.mesh, s.role, K);
  int in_half = 0;
  for (int k = 0; k < K; ++k) in_half += uniform.positions(k, 0) > 0.2;
  EXPECT_LE(in_half, 12);
}

TEST(HandlePlacement, RejectsImpossibleRequests) {
  const Slab s;
  EXPECT_THROW(select_handles(s.mesh, s.role, 0), Error);
  EXPECT_THROW(select_handles(s.mesh, s.role, s.mesh.num_nodes()), Error);
  EXPECT_THROW(select_handles(s.mesh, s.role, 3, VecX::Constant(s.mesh.num_nodes(), -1.0)), Error);
  EXPECT_THROW(select_handles(s.mesh, VecXi::Zero(5), 3), Error);
}

TEST(HandlePlacement, SnapsUserPositionsAndRejectsOutsideOnes) {
  const Slab s;
  Points p(2, 3);
  p << 0.101, 0.041, 0.049,  // near node (0.1, 0.04, 0.05)
      0.3, 0.06 + 0.005, 0.1;  // 5 mm above the top face: within 1 cm
  const HandleSet hs = snap_handles(s.mesh, s.role, p, 0.01);
  EXPECT_LT((hs.positions.row(0) - Eigen::RowVector3d(0.1, 0.04, 0.05)).norm(), 1e-12);
  EXPECT_LT((hs.positions.row(1) - Eigen::RowVector3d(0.3, 0.06, 0.1)).norm(), 1e-12);
  Points far(1, 3);
  far << 0.2, 0.2, 0.1;  // 14 cm above
  try {
    snap_handles(s.mesh, s.role, far, 0.01);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("handle 0"), std::string::npos) << e.what();
  }
  Points twice(2, 3);
  twice << 0.1, 0.04, 0.05, 0.1001, 0.04, 0.05;
  EXPECT_THROW(snap_handles(s.mesh, s.role, twice, 0.01), Error);
  // A position on the bone face snaps to the nearest Simulated node above it.
  Points bone(1, 3);
  bone << 0.1, 0.0, 0.05;
  EXPECT_NEAR(snap_handles(s.mesh, s.role, bone).positions(0, 1), 0.02, 1e-12);
}

}  // namespace
}  // namespace sflsh::basis
