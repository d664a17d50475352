#include "sflsh/geometry/capsule_distance.hpp"

#include <algorithm>
#include <cmath>

namespace sflsh::geometry {
namespace {

double clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

/// Some unit vector perpendicular to v (v may be zero: then +X).
Vec3 any_perpendicular(const Vec3& v) {
  if (v.squaredNorm() == 0) return Vec3::UnitX();
  Vec3 p = v.cross(std::abs(v.x()) < 0.9 * v.norm() ? Vec3::UnitX() : Vec3::UnitY());
  return p.normalized();
}

}  // namespace

SegmentClosestPoints closest_points_on_segments(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  // Squared lengths below this are points (1e-15 m segments).
  constexpr double kTiny = 1e-30;
  double s = 0, t = 0;
  if (a <= kTiny && e <= kTiny) {
    s = t = 0;
  } else if (a <= kTiny) {
    t = clamp01(f / e);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = clamp01(-c / a);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;  // = a·e·sin²(angle)
      if (denom > 1e-14 * a * e) {
        s = clamp01((b * f - c * e) / denom);
      } else {
        // Parallel: b's endpoints project to s = −c/a and (b − c)/a on a's line;
        // take the middle of the overlap with [0, 1] (or the nearer end).
        const double sb0 = -c / a, sb1 = (b - c) / a;
        const double lo = std::max(0.0, std::min(sb0, sb1)), hi = std::min(1.0, std::max(sb0, sb1));
        s = lo <= hi ? 0.5 * (lo + hi) : clamp01(lo);
      }
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = clamp01(-c / a);
      } else if (t > 1) {
        t = 1;
        s = clamp01((b - c) / a);
      }
    }
  }
  SegmentClosestPoints out;
  out.s = s;
  out.t = t;
  out.point_a = a0 + s * d1;
  out.point_b = b0 + t * d2;
  out.distance = (out.point_a - out.point_b).norm();
  return out;
}

CapsuleContact capsule_distance(const Capsule& a, const Capsule& b) {
  CapsuleContact c;
  c.axes = closest_points_on_segments(a.p0, a.p1, b.p0, b.p1);
  const Vec3 diff = c.axes.point_b - c.axes.point_a;
  if (c.axes.distance > 0) {
    c.normal = diff / c.axes.distance;
  } else {
    const Vec3 cross = (a.p1 - a.p0).cross(b.p1 - b.p0);
    c.normal = cross.norm() > 0 ? Vec3(cross.normalized()) : any_perpendicular(a.p1 - a.p0);
  }
  c.distance = c.axes.distance - a.radius - b.radius;
  c.witness_a = c.axes.point_a + a.radius * c.normal;
  c.witness_b = c.axes.point_b - b.radius * c.normal;
  return c;
}

}  // namespace sflsh::geometry
