// Segment–segment closest points and capsule gaps against brute-force
// sampling of both segments, including parallel and degenerate segments.
#include <gtest/gtest.h>

#include <random>

#include "sflsh/geometry/capsule_distance.hpp"

namespace sflsh {
namespace {

using geometry::closest_points_on_segments;

/// Minimum of |a(s) − b(t)| over a 401×401 grid of (s, t), refined twice
/// around the best node (the distance is convex in (s, t)).
double brute_force_distance(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  double s_lo = 0, s_hi = 1, t_lo = 0, t_hi = 1, best = 1e300;
  for (int level = 0; level < 3; ++level) {
    const int n = 400;
    double bs = 0, bt = 0;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double s = s_lo + (s_hi - s_lo) * i / n, t = t_lo + (t_hi - t_lo) * j / n;
        const double d = (a0 + s * (a1 - a0) - b0 - t * (b1 - b0)).norm();
        if (d < best) best = d, bs = s, bt = t;
      }
    const double ds = 2 * (s_hi - s_lo) / n, dt = 2 * (t_hi - t_lo) / n;
    s_lo = std::max(0.0, bs - ds), s_hi = std::min(1.0, bs + ds);
    t_lo = std::max(0.0, bt - dt), t_hi = std::min(1.0, bt + dt);
  }
  return best;
}

void expect_exact(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const auto c = closest_points_on_segments(a0, a1, b0, b1);
  const double bf = brute_force_distance(a0, a1, b0, b1);
  EXPECT_LE(c.distance, bf + 1e-12) << a0.transpose() << " | " << a1.transpose() << " | " << b0.transpose() << " | " << b1.transpose();
  EXPECT_GE(c.distance, bf - 1e-9);
  EXPECT_GE(c.s, 0.0);
  EXPECT_LE(c.s, 1.0);
  EXPECT_GE(c.t, 0.0);
  EXPECT_LE(c.t, 1.0);
  EXPECT_LT((c.point_a - (a0 + c.s * (a1 - a0))).norm(), 1e-15);
  EXPECT_LT((c.point_b - (b0 + c.t * (b1 - b0))).norm(), 1e-15);
  EXPECT_NEAR(c.distance, (c.point_a - c.point_b).norm(), 1e-15);
}

TEST(CapsuleDistance, RandomSegmentsMatchBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  auto r = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  for (int i = 0; i < 60; ++i) expect_exact(r(), r(), r(), r());
}

TEST(CapsuleDistance, ParallelCrossingAndDegenerateSegments) {
  const Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  // Parallel, overlapping: distance 0.1, witness in the middle of the overlap [0.5, 1] on a.
  auto c = closest_points_on_segments(Vec3::Zero(), x, 0.5 * x + 0.1 * y, 1.5 * x + 0.1 * y);
  EXPECT_NEAR(c.distance, 0.1, 1e-15);
  EXPECT_NEAR(c.s, 0.75, 1e-15);
  EXPECT_NEAR(c.t, 0.25, 1e-15);
  expect_exact(Vec3::Zero(), x, 0.5 * x + 0.1 * y, 1.5 * x + 0.1 * y);
  // Anti-parallel overlapping, parallel disjoint (end to end), collinear disjoint.
  expect_exact(Vec3::Zero(), x, 1.5 * x + 0.1 * z, 0.2 * x + 0.1 * z);
  expect_exact(Vec3::Zero(), x, 1.3 * x + 0.2 * y, 2.0 * x + 0.2 * y);
  c = closest_points_on_segments(Vec3::Zero(), x, 1.3 * x, 2.0 * x);
  EXPECT_NEAR(c.distance, 0.3, 1e-15);
  // Nearly parallel.
  expect_exact(Vec3::Zero(), x, 0.2 * x + 0.1 * y, 0.9 * x + 0.1 * y + 1e-9 * z);
  // Crossing segments touch: distance 0.
  c = closest_points_on_segments(-x, x, -y, y);
  EXPECT_NEAR(c.distance, 0.0, 1e-15);
  // Degenerate: point–segment, segment–point, point–point.
  expect_exact(0.3 * y, 0.3 * y, -x, x);
  expect_exact(-x, x, 2 * x + y, 2 * x + y);
  c = closest_points_on_segments(y, y, z, z);
  EXPECT_NEAR(c.distance, std::sqrt(2.0), 1e-15);
}

TEST(CapsuleDistance, CapsuleGapWitnessesAndEndpointGradient) {
  const geometry::Capsule a{Vec3(0, 0, 0), Vec3(0.4, 0, 0), 0.05};
  const geometry::Capsule b{Vec3(0.1, 0.08, -0.2), Vec3(0.2, 0.08, 0.3), 0.04};
  const auto c = geometry::capsule_distance(a, b);
  // The axes are 0.08 apart (b runs at y = 0.08 across a's axis), radii 0.09: overlap 0.01.
  EXPECT_NEAR(c.distance, -0.01, 1e-14);
  EXPECT_LT((c.normal - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_NEAR((c.witness_a - c.axes.point_a).norm(), a.radius, 1e-15);
  EXPECT_NEAR((c.witness_b - c.axes.point_b).norm(), b.radius, 1e-15);
  EXPECT_NEAR((c.witness_a - c.witness_b).norm(), 0.01, 1e-14);
  // Envelope-theorem gradient of the gap against finite differences.
  const double s = c.axes.s, t = c.axes.t, eps = 1e-7;
  const Vec3 n = c.normal;
  const Vec3 expected[4] = {-(1 - s) * n, -s * n, (1 - t) * n, t * n};
  for (int e = 0; e < 4; ++e)
    for (int k = 0; k < 3; ++k) {
      geometry::Capsule ap = a, am = a, bp = b, bm = b;
      Vec3* pp[4] = {&ap.p0, &ap.p1, &bp.p0, &bp.p1};
      Vec3* pm[4] = {&am.p0, &am.p1, &bm.p0, &bm.p1};
      (*pp[e])[k] += eps;
      (*pm[e])[k] -= eps;
      const double fd = (geometry::capsule_distance(ap, bp).distance - geometry::capsule_distance(am, bm).distance) / (2 * eps);
      EXPECT_NEAR(fd, expected[e][k], 1e-6) << "endpoint " << e << " axis " << k;
    }
  // Axes that touch: the normal is perpendicular to both.
  const auto touch = geometry::capsule_distance({Vec3(-1, 0, 0), Vec3(1, 0, 0), 0.1}, {Vec3(0, -1, 0), Vec3(0, 1, 0), 0.1});
  EXPECT_NEAR(touch.distance, -0.2, 1e-15);
  EXPECT_NEAR(std::abs(touch.normal.z()), 1.0, 1e-15);
}

}  // namespace
}  // namespace sflsh
