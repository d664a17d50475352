// The point broad phase against brute force, and Aabb basics.
#include <gtest/gtest.h>

#include <random>

#include "sflsh/geometry/point_grid.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using geometry::Aabb;

std::vector<int> brute_force(const Points& p, const Aabb& box) {
  std::vector<int> out;
  for (int i = 0; i < p.rows(); ++i)
    if (box.contains(p.row(i).transpose())) out.push_back(i);
  return out;
}

TEST(PointGrid, QueriesMatchBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.5, 0.5), size(0.0, 0.3);
  Points p(3000, 3);
  for (int i = 0; i < p.rows(); ++i) p.row(i) << u(rng), 2 * u(rng), u(rng);
  p.row(7) = p.row(3);  // duplicates
  const geometry::PointGrid grid(p, 0.05);
  EXPECT_EQ(grid.num_points(), 3000);
  std::vector<int> got;
  for (int q = 0; q < 200; ++q) {
    const Vec3 c(u(rng), 2 * u(rng), u(rng)), e(size(rng), size(rng), size(rng));
    const Aabb box(c - e, c + e);
    grid.query(box, got);
    EXPECT_EQ(got, brute_force(p, box));
  }
  // Boxes larger than the cloud, unbounded, half-unbounded, disjoint, empty.
  const Aabb huge(Vec3::Constant(-10), Vec3::Constant(10));
  EXPECT_EQ(grid.query(huge).size(), 3000u);
  EXPECT_EQ(grid.query(Aabb::unbounded()).size(), 3000u);
  const double inf = std::numeric_limits<double>::infinity();
  const Aabb below(Vec3(-inf, -inf, -inf), Vec3(inf, -0.2, inf));
  EXPECT_EQ(grid.query(below), brute_force(p, below));
  EXPECT_TRUE(grid.query(Aabb(Vec3::Constant(5), Vec3::Constant(6))).empty());
  EXPECT_TRUE(grid.query(Aabb()).empty());
  // A point exactly on the box boundary counts (closed box).
  const Vec3 p0 = p.row(0).transpose();
  EXPECT_EQ(grid.query(Aabb(p0, p0 + Vec3::Constant(1e-12))).front(), 0);
  test::expect_error([&] { geometry::PointGrid(p, 0.0); }, {"cell size"});
}

TEST(PointGrid, NearestMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5), reach(0.0, 0.4);
  Points p(2000, 3);
  for (int i = 0; i < p.rows(); ++i) p.row(i) << u(rng), 0.3 * u(rng), u(rng);  // a slab: empty cells around it
  const geometry::PointGrid grid(p, 0.03);
  int hits = 0, misses = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3 x(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));  // inside and outside the cloud's cells
    const double max_distance = reach(rng);
    int want = -1;
    double want_d = max_distance;
    for (int i = 0; i < p.rows(); ++i) {
      const double d = (p.row(i).transpose() - x).norm();
      if (d < want_d || (d == want_d && want < 0)) want = i, want_d = d;
    }
    double d = -1;
    const int got = grid.nearest(x, max_distance, &d);
    EXPECT_EQ(got, want) << "query " << q;
    if (want >= 0) {
      EXPECT_DOUBLE_EQ(d, want_d);
      ++hits;
    } else {
      EXPECT_TRUE(std::isinf(d));
      ++misses;
    }
  }
  EXPECT_GT(hits, 50);  // both outcomes exercised
  EXPECT_GT(misses, 50);
  EXPECT_EQ(geometry::PointGrid(Points(0, 3), 0.1).nearest(Vec3::Zero(), 1.0), -1);
  // occupied(): false only where a box query finds nothing; true at every point.
  const geometry::PointGrid coarse(p, 0.12);
  int empty = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3 x(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
    const Aabb box = Aabb(x, x).inflated(reach(rng) / 4);
    if (!coarse.occupied(box)) {
      EXPECT_TRUE(grid.query(box).empty()) << "query " << q;
      ++empty;
    }
  }
  EXPECT_GT(empty, 50);
  for (int i = 0; i < p.rows(); i += 97) EXPECT_TRUE(coarse.occupied(Aabb(p.row(i).transpose(), p.row(i).transpose())));
}

TEST(Aabb, ExtendInflateIntersectTransform) {
  Aabb b;
  EXPECT_TRUE(b.empty());
  b.extend(Vec3(1, 2, 3));
  b.extend(Vec3(-1, 0, 4));
  EXPECT_EQ(b.min, Vec3(-1, 0, 3));
  EXPECT_EQ(b.max, Vec3(1, 2, 4));
  EXPECT_TRUE(b.inflated(0.5).contains(Vec3(1.5, -0.5, 4.5)));
  EXPECT_TRUE(b.intersects(Aabb(Vec3(1, 2, 4), Vec3(3, 3, 5))));
  EXPECT_FALSE(b.intersects(Aabb(Vec3(1.01, 2, 4), Vec3(3, 3, 5))));
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.5 * 3.14159265358979, Vec3::UnitZ()).toRotationMatrix();  // x -> y
  const Aabb t = b.transformed(pose);
  EXPECT_NEAR(t.min.x(), -2, 1e-12);
  EXPECT_NEAR(t.max.y(), 1, 1e-12);
  EXPECT_TRUE(Aabb::unbounded().transformed(pose).is_unbounded());
}

}  // namespace
}  // namespace sflsh
