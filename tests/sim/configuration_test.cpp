#include <cmath>

#include <gtest/gtest.h>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {
namespace {

DofLayout two_bones(bool pivots, int base) {
  DofLayout L;
  L.num_bones = 2;
  L.num_reduced = 6;
  L.base = base;
  if (pivots) {
    L.bone_pivots = Points(2, 3);
    L.bone_pivots << 0.1, 0.9, -0.2, -0.3, 0.4, 0.05;
  }
  return L;
}

Configuration start() {
  Configuration q;
  q.bones.assign(2, Isometry::Identity());
  q.bones[0].linear() = rodrigues(Vec3(0.3, -0.2, 0.5));
  q.bones[0].translation() = Vec3(0.2, 1.1, -0.4);
  q.bones[1].linear() = rodrigues(Vec3(-1.1, 0.7, 0.2));
  q.bones[1].translation() = Vec3(-0.5, 0.3, 0.8);
  q.z = VecX::LinSpaced(6, -0.01, 0.02);
  return q;
}

// A quarter turn about z of bone 0 with no pivot: t' = E t + v, so from
// t = (0.2, 1.1, −0.4) to E t = (−1.1, 0.2, −0.4) the step's v is zero; a
// further shift of (0.01, 0, 0) is v. Values by hand.
TEST(TangentBetween, RecoversAQuarterTurnAndAShiftByHand) {
  const DofLayout L = two_bones(false, 0);
  const Configuration from = start();
  Configuration to = from;
  const Mat3 E = rodrigues(Vec3(0, 0, M_PI / 2));
  to.bones[0].linear() = E * from.bones[0].linear();
  to.bones[0].translation() = Vec3(-1.1 + 0.01, 0.2, -0.4);
  to.z[4] += 0.003;
  const VecX d = tangent_between(to, from, L);
  ASSERT_EQ(d.size(), 18);
  EXPECT_NEAR(d[0], 0, 1e-12);
  EXPECT_NEAR(d[1], 0, 1e-12);
  EXPECT_NEAR(d[2], M_PI / 2, 1e-12);
  EXPECT_NEAR(d[3], 0.01, 1e-12);
  EXPECT_NEAR(d[4], 0, 1e-12);
  EXPECT_NEAR(d[5], 0, 1e-12);
  EXPECT_NEAR(d.segment<6>(6).norm(), 0, 1e-12);  // bone 1 did not move
  EXPECT_NEAR(d[12 + 4], 0.003, 1e-15);
  EXPECT_NEAR(d.segment<6>(12).norm(), 0.003, 1e-15);
}

// retract(from, tangent_between(retract(from, δ), from)) = retract(from, δ):
// the inverse, with and without pivots and at an offset in a larger system.
TEST(TangentBetween, InvertsRetractWithPivotsAndAnOffset) {
  for (bool pivots : {false, true})
    for (int base : {0, 7}) {
      const DofLayout L = two_bones(pivots, base);
      const Configuration from = start();
      VecX delta = VecX::Zero(L.end());
      delta.tail(L.size()) << 0.4, -0.9, 1.3, 0.05, -0.02, 0.3,  // bone 0: |ω| ≈ 1.6 rad
          -0.2, 0.1, 0.05, -0.4, 0.6, 0.01,                      // bone 1
          0.001, -0.002, 0.003, 0.004, -0.005, 0.006;            // z
      const Configuration to = retract(from, delta, L);
      const VecX back = tangent_between(to, from, L);
      ASSERT_EQ(back.size(), L.end());
      EXPECT_LT((back - delta).cwiseAbs().maxCoeff(), 1e-12) << "pivots " << pivots << ", base " << base;
      EXPECT_EQ(back.head(base).norm(), 0.0);
    }
}

TEST(TangentBetween, KinematicBonesGiveOnlyZ) {
  DofLayout L = two_bones(false, 3);
  L.bones_dynamic = false;
  const Configuration from = start();
  Configuration to = from;
  to.bones[1].translation().x() += 1.0;  // prescribed bones: not part of the step
  to.z[0] += 0.25;
  const VecX d = tangent_between(to, from, L);
  ASSERT_EQ(d.size(), 9);
  EXPECT_EQ(d[3], 0.25);
  EXPECT_EQ(d.norm(), 0.25);
}

TEST(TangentBetween, RefusesAMismatchedConfiguration) {
  const DofLayout L = two_bones(false, 0);
  Configuration to = start();
  to.z.resize(3);
  EXPECT_THROW(tangent_between(to, start(), L), std::exception);
}

}  // namespace
}  // namespace sflsh
