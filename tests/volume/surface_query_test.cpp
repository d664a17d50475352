#include <gtest/gtest.h>

#include <random>

#include "sflsh/volume/surface_query.hpp"

namespace sflsh {
namespace {

// A closed octahedron |x|+|y|+|z| = 1: sharp edges and vertices exercise the
// pseudo-normal cases of signed_distance().
void octahedron(Points& V, Triangles& F) {
  V.resize(6, 3);
  V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  F.resize(8, 3);
  int f = 0;
  for (int sx : {0, 1})
    for (int sy : {2, 3})
      for (int sz : {4, 5}) {
        // Orient counter-clockwise from outside: check the sign of the normal.
        const Vec3 a = V.row(sx), b = V.row(sy), c = V.row(sz);
        if ((b - a).cross(c - a).dot(a + b + c) > 0)
          F.row(f++) << sx, sy, sz;
        else
          F.row(f++) << sx, sz, sy;
      }
}

TEST(SurfaceQuery, SignedDistanceAgreesWithRayParityAndExactDistance) {
  Points V;
  Triangles F;
  octahedron(V, F);
  const SurfaceQuery q(V, F);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const double l1 = x.cwiseAbs().sum();
    const double sd = q.signed_distance(x);
    EXPECT_EQ(sd < 0, l1 < 1) << x.transpose();
    EXPECT_EQ(q.inside(x), l1 < 1) << x.transpose();
    inside += l1 < 1;
    if (l1 < 1) {  // distance to the nearest face plane
      EXPECT_NEAR(-sd, (1 - l1) / std::sqrt(3.0), 1e-12);
    }
    EXPECT_NEAR(std::abs(sd), q.distance(x), 1e-12);
  }
  EXPECT_GT(inside, 50);  // the octahedron fills 4/81 of the box
  // Closest point and barycentric coordinates of a point above a face centre.
  int face;
  Vec3 bary;
  const Vec3 c = q.closest_point(Vec3(1, 1, 1), &face, &bary);
  EXPECT_LT((c - Vec3::Constant(1.0 / 3)).norm(), 1e-12);
  EXPECT_LT((bary - Vec3::Constant(1.0 / 3)).norm(), 1e-12);
}

}  // namespace
}  // namespace sflsh
