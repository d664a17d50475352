// Proximity sensors: ray hits against the posed skin of the
// synthetic avatar compared with brute force over every triangle, computed
// here independently (plane intersection, then inside-test and barycentric
// coordinates from sub-triangle areas).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/proximity_sensor.hpp"
#include "sim/synthetic_avatar.hpp"

using namespace sflsh;

namespace {

struct BruteHit {
  bool hit = false;
  int face = -1;
  double t = 0;
  Vec3 bary = Vec3::Zero();
};

/// Nearest hit within range by testing every triangle: t from the plane, bary from signed areas.
BruteHit brute_force(const Points& V, const Triangles& F, const Vec3& o, const Vec3& d, double range) {
  BruteHit best;
  for (int f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    const double denom = n.dot(d);
    if (std::abs(denom) < 1e-14) continue;
    const double t = n.dot(a - o) / denom;
    if (t < 0 || t > range || (best.hit && t >= best.t)) continue;
    const Vec3 p = o + t * d;
    const double area = n.squaredNorm();
    const Vec3 w((c - b).cross(p - b).dot(n) / area, (a - c).cross(p - c).dot(n) / area,
                 (b - a).cross(p - a).dot(n) / area);
    if (w.minCoeff() < -1e-12) continue;
    best = {true, f, t, w};
  }
  return best;
}

TEST(ProximitySensor, RandomRaysOnThePosedSkinMatchBruteForce) {
  test::SyntheticAvatarOptions o;
  o.nx = 4, o.ny = 6, o.nz = 3;
  o.cell = 0.02;
  o.handles = 5;
  o.handle_radius = 0.06;
  const Avatar a = test::make_synthetic_avatar(o);
  // A posed configuration: bones turned, soft DoFs displaced.
  std::mt19937 rng(3);
  std::normal_distribution<double> n;
  Configuration q;
  for (int j = 0; j < 24; ++j) {
    Isometry G = Isometry::Identity();
    G.linear() = Eigen::AngleAxisd(0.3, Vec3(0.2, 1, 0.1).normalized()).toRotationMatrix();
    G.translation() = Vec3(0.1, -0.2, 0.3);
    q.bones.push_back(G);
  }
  q.z = VecX::NullaryExpr(a.num_reduced(), [&](Eigen::Index) { return 0.003 * n(rng); });
  const Points V = PosedPoints::at_surface(a).world(q);
  const TriangleRaycaster caster(V, a.surface_faces);
  const Vec3 center = V.colwise().mean().transpose();
  int hits = 0, misses = 0;
  double tested = 0;
  for (int trial = 0; trial < 400; ++trial) {
    // Rays from a shell around the body aimed near its centre (most hit), some away (miss).
    const Vec3 o_ray = center + 0.15 * Vec3(n(rng), n(rng), n(rng)).normalized();
    const Vec3 aim = center + 0.05 * Vec3(n(rng), n(rng), n(rng));
    const Vec3 d = (trial % 5 == 0 ? Vec3(n(rng), n(rng), n(rng)) : Vec3(aim - o_ray)).normalized();
    const double range = trial % 3 == 0 ? 0.12 : 1.0;
    const RayHit h = caster.cast(o_ray, d, range);
    tested += caster.last_tests();
    const BruteHit b = brute_force(V, a.surface_faces, o_ray, d, range);
    ASSERT_EQ(h.hit, b.hit) << "trial " << trial;
    if (!b.hit) {
      ++misses;
      continue;
    }
    ++hits;
    EXPECT_NEAR(h.distance, b.t, 1e-10) << "trial " << trial;
    // The face may differ only on a shared edge (then the points coincide).
    EXPECT_LT((h.point - (o_ray + b.t * d)).norm(), 1e-10);
    if (h.face == b.face) {
      EXPECT_LT((h.bary - b.bary).norm(), 1e-9);
    } else {
      EXPECT_LT(b.bary.minCoeff(), 1e-6) << "different faces away from an edge, trial " << trial;
    }
    const Vec3 p = h.bary[0] * V.row(a.surface_faces(h.face, 0)) + h.bary[1] * V.row(a.surface_faces(h.face, 1)) +
                   h.bary[2] * V.row(a.surface_faces(h.face, 2));
    EXPECT_LT((p - h.point).norm(), 1e-10);
  }
  EXPECT_GT(hits, 100);
  EXPECT_GT(misses, 20);
  std::printf("%d hits, %d misses; %.1f of %d triangles tested per ray\n", hits, misses, tested / 400,
              int(a.surface_faces.rows()));
  // The broad phase tests a fraction of the triangles per ray.
  EXPECT_LT(tested / 400, 0.25 * a.surface_faces.rows()) << a.surface_faces.rows() << " faces";
}

TEST(ProximitySensor, ASensorInAToolFrameAndItsRange) {
  // One triangle in the plane y = 0; a sensor 5 mm above it looking down its tool's −y.
  Points V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 0, 1;
  Triangles F(1, 3);
  F << 0, 1, 2;
  const TriangleRaycaster caster(V, F);
  Isometry tool = Isometry::Identity();
  tool.linear() = Eigen::AngleAxisd(M_PI, Vec3(0, 0, 1)).toRotationMatrix();  // tool's −y is world +y
  tool.translation() = Vec3(0.2, 0.005, 0.3);
  ProximitySensor s{Vec3::Zero(), Vec3(0, 1, 0), 0.01};  // tool +y = world −y
  const RayHit h = sense(s, tool, caster);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 0.005, 1e-15);
  EXPECT_LT((h.point - Vec3(0.2, 0, 0.3)).norm(), 1e-15);
  EXPECT_LT((h.bary - Vec3(0.5, 0.2, 0.3)).norm(), 1e-12);
  s.range = 0.004;
  EXPECT_FALSE(sense(s, tool, caster).hit);
  EXPECT_THROW(caster.cast(Vec3::Zero(), Vec3::Zero(), 1.0), Error);
}

}  // namespace
