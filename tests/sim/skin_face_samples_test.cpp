// The face quadrature of the contact (skin_face_samples.hpp): n² sub-triangle
// centroids with n = ⌈longest edge / spacing⌉, each standing for area / n².
// Checked by hand on one triangle: the count, the weights' sum (the area), the
// weighted centroid (the triangle's: the rule is exact for linear functions),
// and no two samples at one point.
#include "sflsh/sim/skin_face_samples.hpp"

#include <gtest/gtest.h>

#include <set>

namespace sflsh {
namespace {

TEST(SkinFaceSamples, OneTriangleByHand) {
  Points rest(3, 3);
  rest << 0, 0, 0, 0.03, 0, 0, 0, 0.02, 0;
  Triangles faces(1, 3);
  faces << 0, 1, 2;
  // Longest edge √(0.03² + 0.02²) = 36.06 mm: 4 subdivisions at 10 mm, 1 at 40 mm.
  EXPECT_EQ(face_subdivisions(rest, faces, 0, 0.01), 4);
  EXPECT_EQ(face_subdivisions(rest, faces, 0, 0.04), 1);
  EXPECT_EQ(face_subdivisions(rest, faces, 0, std::sqrt(0.03 * 0.03 + 0.02 * 0.02)), 1);  // exactly one edge long
  std::vector<SkinFaceSample> s;
  append_face_samples(rest, faces, 0, 0.01, s);
  ASSERT_EQ(s.size(), 16u);
  const double area = 0.5 * 0.03 * 0.02;
  double sum = 0;
  Vec3 centroid = Vec3::Zero();
  std::set<std::pair<long, long>> points;
  for (const SkinFaceSample& x : s) {
    EXPECT_EQ(x.face, 0);
    EXPECT_NEAR(x.area, area / 16, 1e-18);
    EXPECT_NEAR(x.lambda.sum(), 1.0, 1e-15);
    EXPECT_GT(x.lambda.minCoeff(), 0.0);
    sum += x.area;
    const Vec3 p = x.lambda[0] * rest.row(0).transpose() + x.lambda[1] * rest.row(1).transpose() +
                   x.lambda[2] * rest.row(2).transpose();
    centroid += x.area * p;
    EXPECT_TRUE(points.insert({std::lround(p.x() * 1e9), std::lround(p.y() * 1e9)}).second) << "two samples at " << p.transpose();
  }
  EXPECT_NEAR(sum, area, 1e-15);
  EXPECT_LT((centroid / area - Vec3(0.01, 0.02 / 3, 0)).norm(), 1e-15);
}

}  // namespace
}  // namespace sflsh
