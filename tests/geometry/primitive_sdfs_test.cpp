// Exact primitive SDFs against brute force (the minimum distance to a dense
// sampling of the surface, with the sign from an independent inside test),
// and their gradients/Hessians against finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "sdf_checks.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using geometry::Sdf;
constexpr double kPi = 3.14159265358979323846;

/// Points of a closed surface, at most `spacing` apart along the surface.
class SurfaceSamples {
 public:
  void add(const Vec3& p) { pts_.push_back(p); }
  /// The rectangle c + u·e1 + v·e2, |u| <= a, |v| <= b (edges included).
  void rectangle(const Vec3& c, const Vec3& e1, double a, const Vec3& e2, double b, double spacing) {
    const int nu = int(std::ceil(2 * a / spacing)) + 1, nv = int(std::ceil(2 * b / spacing)) + 1;
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) add(c + (-a + 2 * a * i / (nu - 1)) * e1 + (-b + 2 * b * j / (nv - 1)) * e2);
  }
  /// The sphere of radius r around c restricted to sign(y − c.y)·side >= 0
  /// (side = 0: the whole sphere), latitude–longitude rings.
  void sphere(const Vec3& c, double r, double spacing, int side = 0) {
    const int nlat = int(std::ceil(kPi * r / spacing)) + 1;
    for (int i = 0; i < nlat; ++i) {
      const double th = kPi * i / (nlat - 1), y = r * std::cos(th), ring = r * std::sin(th);
      if (side * y < 0) continue;
      const int nlon = std::max(1, int(std::ceil(2 * kPi * ring / spacing)));
      for (int j = 0; j < nlon; ++j) {
        const double ph = 2 * kPi * j / nlon;
        add(c + Vec3(ring * std::cos(ph), y, ring * std::sin(ph)));
      }
    }
  }
  /// The side of the cylinder ρ = r, |y − c.y| <= h.
  void tube(const Vec3& c, double r, double h, double spacing) {
    const int ny = int(std::ceil(2 * h / spacing)) + 1, nt = int(std::ceil(2 * kPi * r / spacing));
    for (int i = 0; i < ny; ++i)
      for (int j = 0; j < nt; ++j) {
        const double y = ny > 1 ? -h + 2 * h * i / (ny - 1) : 0, ph = 2 * kPi * j / nt;
        add(c + Vec3(r * std::cos(ph), y, r * std::sin(ph)));
      }
  }
  /// The disk ρ <= r at height c.y (a square grid clipped to it; the rim comes from tube()).
  void disk(const Vec3& c, double r, double spacing) {
    const int n = int(std::ceil(2 * r / spacing)) + 1;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double x = -r + 2 * r * i / (n - 1), z = -r + 2 * r * j / (n - 1);
        if (x * x + z * z <= r * r) add(c + Vec3(x, 0, z));
      }
  }
  /// Distance from q to the nearest sample.
  double distance(const Vec3& q) const {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& p : pts_) best = std::min(best, (p - q).squaredNorm());
    return std::sqrt(best);
  }

 private:
  std::vector<Vec3> pts_;
};

constexpr double kSpacing = 0.002;  // m between surface samples
// A surface point is at most this far from its nearest sample (half the
// diagonal of a sample cell, rounded up for the curved samplings).
constexpr double kSampleGap = kSpacing * 0.75;

/// |φ| equals the brute-force distance within the sampling gap, and the sign
/// matches `inside`; the closest-point projection x − φ∇φ lands on the surface.
void expect_matches_brute_force(const Sdf& f, const SurfaceSamples& surface, const std::function<bool(const Vec3&)>& inside,
                                const std::vector<Vec3>& queries) {
  for (const Vec3& x : queries) {
    const auto s = f.evaluate(x);
    const double bf = surface.distance(x);
    EXPECT_LE(std::abs(s.distance), bf + 1e-12) << "x = " << x.transpose();
    EXPECT_GE(std::abs(s.distance), bf - kSampleGap) << "x = " << x.transpose();
    if (std::abs(s.distance) > 1e-9) {
      EXPECT_EQ(s.distance < 0, inside(x)) << "x = " << x.transpose();
    }
    EXPECT_NEAR(s.gradient.norm(), 1.0, 1e-12);
    EXPECT_LE(surface.distance(x - s.distance * s.gradient), kSampleGap) << "x = " << x.transpose();
  }
}

/// Random points in the box [-e, e] plus points just off `features` (edges,
/// corners, rims) in every direction, 1 and 5 mm away.
std::vector<Vec3> query_points(const Vec3& e, const std::vector<Vec3>& features, int n_random, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> q;
  for (int i = 0; i < n_random; ++i) q.push_back(Vec3(u(rng), u(rng), u(rng)).cwiseProduct(e));
  for (const Vec3& c : features)
    for (int k = 0; k < 8; ++k)
      for (double r : {0.001, 0.005}) q.push_back(c + r * Vec3(u(rng), u(rng), u(rng)).normalized());
  return q;
}

/// Derivatives against central differences (step 1e-7 m: the query points
/// 1 mm off an edge see curvatures of 1000/m) away from the medial surfaces.
void expect_fd_consistent(const Sdf& f, const std::vector<Vec3>& queries) {
  int checked = 0;
  for (const Vec3& x : queries) {
    if (test::near_gradient_jump(f, x, 2e-7)) continue;
    test::expect_derivatives_match_fd(f, x, 1e-6, 1e-4, 1e-7);
    ++checked;
  }
  EXPECT_GT(checked, int(queries.size()) * 9 / 10);
}

TEST(PrimitiveSdf, PlaneIsTheSignedHeightAboveIt) {
  const Vec3 n = Vec3(1, 2, -2) / 3.0;
  const geometry::PlaneSdf plane(Vec3(1, 2, -2), 0.5);
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(-2, 0.3, 4)}) {
    // Distance to the plane point p0 = 0.5 n along n, by hand.
    EXPECT_NEAR(plane.distance(x), (x - 0.5 * n).dot(n), 1e-15);
    EXPECT_LT((plane.evaluate(x).gradient - n).norm(), 1e-15);
  }
  EXPECT_TRUE(plane.bounds().is_unbounded());
  test::expect_error([] { geometry::PlaneSdf(Vec3::Zero()); }, {"plane", "normal"});
}

TEST(PrimitiveSdf, SphereMatchesBruteForce) {
  const double r = 0.12;
  const geometry::SphereSdf f(r);
  SurfaceSamples s;
  s.sphere(Vec3::Zero(), r, kSpacing);
  const auto q = query_points(Vec3::Constant(0.2), {}, 200, 1);
  expect_matches_brute_force(f, s, [&](const Vec3& x) { return x.norm() < r; }, q);
  expect_fd_consistent(f, q);
  test::expect_error([] { geometry::SphereSdf(-1.0); }, {"sphere", "radius", "> 0"});
}

TEST(PrimitiveSdf, BoxMatchesBruteForceInsideOutsideAndAtEdgesAndCorners) {
  const Vec3 b(0.1, 0.15, 0.05);
  const geometry::BoxSdf f(b);
  SurfaceSamples s;
  for (int a = 0; a < 3; ++a)
    for (double side : {-1.0, 1.0}) {
      const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
      Vec3 c = Vec3::Zero();
      c[a] = side * b[a];
      s.rectangle(c, Vec3::Unit(a1), b[a1], Vec3::Unit(a2), b[a2], kSpacing);
    }
  std::vector<Vec3> features;
  for (int c = 0; c < 8; ++c) features.push_back(b.cwiseProduct(Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1)));
  for (int a = 0; a < 3; ++a)  // edge midpoints
    for (int c = 0; c < 4; ++c) {
      Vec3 p = b;
      p[a] = 0;
      p[(a + 1) % 3] *= (c & 1) ? 1 : -1;
      p[(a + 2) % 3] *= (c & 2) ? 1 : -1;
      features.push_back(p);
    }
  const auto q = query_points(1.6 * b, features, 250, 2);
  expect_matches_brute_force(f, s, [&](const Vec3& x) { return (x.cwiseAbs().array() < b.array()).all(); }, q);
  expect_fd_consistent(f, q);
  // By hand: a corner region point, an edge region point, a deep inside point.
  EXPECT_NEAR(f.distance(b + Vec3(0.03, 0.04, 0)), 0.05, 1e-15);
  EXPECT_NEAR(f.distance(Vec3(0.13, 0, 0.09)), 0.05, 1e-15);
  EXPECT_NEAR(f.distance(Vec3(0.0, 0.01, 0.01)), -0.04, 1e-15);
}

TEST(PrimitiveSdf, CapsuleMatchesBruteForce) {
  const double r = 0.06, h = 0.1;
  const geometry::CapsuleSdf f(r, h);
  SurfaceSamples s;
  s.tube(Vec3::Zero(), r, h, kSpacing);
  s.sphere(Vec3(0, h, 0), r, kSpacing, +1);
  s.sphere(Vec3(0, -h, 0), r, kSpacing, -1);
  const auto q = query_points(Vec3(0.12, 0.2, 0.12), {Vec3(r, h, 0), Vec3(0, -h, -r)}, 250, 3);
  const auto inside = [&](const Vec3& x) {
    // Distance to the segment by dense sampling of the axis (independent of the clamp).
    double best = 1e9;
    for (int i = 0; i <= 20000; ++i) best = std::min(best, (x - Vec3(0, -h + 2 * h * i / 20000.0, 0)).norm());
    return best < r;
  };
  expect_matches_brute_force(f, s, inside, q);
  expect_fd_consistent(f, q);
  EXPECT_TRUE(geometry::CapsuleSdf(0.1, 0.0).bounds().contains(Vec3(0.1, 0.1, 0.1)));
  test::expect_error([] { geometry::CapsuleSdf(0.1, -0.2); }, {"capsule", "half length"});
}

TEST(PrimitiveSdf, CylinderMatchesBruteForceIncludingRims) {
  const double R = 0.08, H = 0.12;
  const geometry::CylinderSdf f(R, H);
  SurfaceSamples s;
  s.tube(Vec3::Zero(), R, H, kSpacing);
  s.disk(Vec3(0, H, 0), R, kSpacing);
  s.disk(Vec3(0, -H, 0), R, kSpacing);
  std::vector<Vec3> rims;
  for (int k = 0; k < 6; ++k)
    for (double y : {-H, H}) rims.push_back(Vec3(R * std::cos(k), y, R * std::sin(k)));
  const auto q = query_points(Vec3(0.15, 0.2, 0.15), rims, 250, 4);
  expect_matches_brute_force(
      f, s, [&](const Vec3& x) { return std::hypot(x.x(), x.z()) < R && std::abs(x.y()) < H; }, q);
  expect_fd_consistent(f, q);
  // By hand: beyond the rim diagonally (3-4-5), and inside nearer the cap.
  EXPECT_NEAR(f.distance(Vec3(R + 0.03, H + 0.04, 0)), 0.05, 1e-15);
  EXPECT_NEAR(f.distance(Vec3(0, H - 0.01, 0.02)), -0.01, 1e-15);
}

TEST(PrimitiveSdf, WorldPoseMovesAndRotatesTheField) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Vec3(0.3, -0.2, 1.0);
  const geometry::WorldSdf world(std::make_shared<geometry::BoxSdf>(Vec3(0.1, 0.2, 0.3)), pose);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < 50; ++i) {
    const Vec3 x = pose.translation() + Vec3(u(rng), u(rng), u(rng));
    const Vec3 x_local = pose.linear().transpose() * (x - pose.translation());
    const auto s = world.evaluate(x, true);
    EXPECT_NEAR(s.distance, world.field().distance(x_local), 1e-14);
    Vec3 g_fd;
    Mat3 H_fd;
    for (int a = 0; a < 3; ++a) {
      const Vec3 d = 1e-6 * Vec3::Unit(a);
      g_fd[a] = (world.distance(x + d) - world.distance(x - d)) / 2e-6;
      H_fd.col(a) = (world.evaluate(x + d).gradient - world.evaluate(x - d).gradient) / 2e-6;
    }
    EXPECT_LT((s.gradient - g_fd).norm(), 1e-6);
    EXPECT_LT((s.hessian - H_fd).norm(), 1e-4 * (1 + H_fd.norm()));
  }
  // The world box holds the transformed corners.
  const auto box = world.bounds();
  for (int c = 0; c < 8; ++c)
    EXPECT_TRUE(box.inflated(1e-12).contains(pose * Vec3(c & 1 ? 0.1 : -0.1, c & 2 ? 0.2 : -0.2, c & 4 ? 0.3 : -0.3)));
}

}  // namespace
}  // namespace sflsh
