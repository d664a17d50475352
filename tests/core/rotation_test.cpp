#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/rotation.hpp"

using namespace sflsh;

TEST(Rotation, RodriguesMatchesEigenAngleAxis) {
  for (Vec3 aa : {Vec3(0.3, -0.2, 0.9), Vec3(1e-10, 0, 0), Vec3(0, 3.1, 0), Vec3(-2.0, 0.5, 0.1)}) {
    Mat3 R = rodrigues(aa);
    Mat3 ref = aa.norm() > 0 ? Eigen::AngleAxisd(aa.norm(), aa.normalized()).toRotationMatrix() : Mat3::Identity();
    EXPECT_LT((R - ref).norm(), 1e-12) << aa.transpose();
    EXPECT_LT((R * R.transpose() - Mat3::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  }
}

TEST(Rotation, LogInvertsRodrigues) {
  Vec3 aa(0.4, -1.1, 0.7);
  EXPECT_LT((rotation_log(rodrigues(aa)) - aa).norm(), 1e-12);
}

TEST(Rotation, HatIsCrossProduct) {
  Vec3 w(1, 2, 3), v(-0.5, 4, 0.25);
  EXPECT_LT((hat(w) * v - w.cross(v)).norm(), 1e-14);
}
