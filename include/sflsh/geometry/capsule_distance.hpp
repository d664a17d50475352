#pragma once
// Exact closest points between two segments and the signed gap between two
// capsules (body ↔ body contact through bone capsules; seed §5).
// Method: Ericson, Real-Time Collision Detection §5.1.9, with the parallel
// case resolved at the middle of the overlap (so that the witness points of
// two parallel bones sit symmetrically) and zero-length segments handled as
// points.
#include "sflsh/core/types.hpp"

namespace sflsh::geometry {

/// Closest points a(s) = a0 + s(a1 − a0) and b(t) = b0 + t(b1 − b0).
struct SegmentClosestPoints {
  double s = 0, t = 0;       ///< segment parameters in [0, 1]
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  ///< m
  double distance = 0;       ///< |point_a − point_b|, m
};

/// The closest pair between the segments [a0, a1] and [b0, b1] (m). The
/// distance is the exact minimum; where the pair is not unique (parallel
/// overlapping segments) the middle of the overlap on segment a is chosen.
/// Zero-length segments are points.
SegmentClosestPoints closest_points_on_segments(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1);

/// A capsule: the points within `radius` (m, >= 0) of the segment [p0, p1].
struct Capsule {
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero();
  double radius = 0;
};

/// The gap between two capsules.
struct CapsuleContact {
  /// Signed gap |point_a − point_b| − r_a − r_b (m); negative when they overlap.
  double distance = 0;
  /// Unit direction from capsule a's axis point to capsule b's; when the axes
  /// touch, a direction perpendicular to both axes (or any perpendicular one).
  Vec3 normal = Vec3::UnitX();
  /// Witness points on the two surfaces: point_a + r_a·normal and point_b − r_b·normal.
  Vec3 witness_a = Vec3::Zero(), witness_b = Vec3::Zero();
  /// The closest axis points.
  SegmentClosestPoints axes;
};

/// Gap, normal and witnesses of capsules a and b. Because the axis points
/// minimize the distance, the gap's gradient with respect to the endpoints is
/// (envelope theorem) ∂/∂a0 = −(1−s)·n, ∂/∂a1 = −s·n, ∂/∂b0 = (1−t)·n,
/// ∂/∂b1 = t·n (n = normal), wherever the closest pair is unique.
CapsuleContact capsule_distance(const Capsule& a, const Capsule& b);

}  // namespace sflsh::geometry
