#pragma once
// Axis-aligned bounding boxes (broad phase of contact). An empty box has
// min > max; an unbounded one (a plane's half-space) has infinite corners.
#include <limits>

#include "sflsh/core/types.hpp"

namespace sflsh::geometry {

struct Aabb {
  /// Corners (m). The default box is empty (min = +inf, max = -inf).
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  Aabb() = default;
  Aabb(const Vec3& lo, const Vec3& hi) : min(lo), max(hi) {}
  /// The whole space (every corner infinite).
  static Aabb unbounded();
  /// The box of #N by 3 points (empty for N = 0).
  static Aabb of_points(const Points& x);

  bool empty() const { return (min.array() > max.array()).any(); }
  /// Some corner coordinate is infinite.
  bool is_unbounded() const { return !min.allFinite() || !max.allFinite(); }
  /// Grows the box to hold `p`.
  void extend(const Vec3& p);
  /// Grows the box to hold `b`.
  void extend(const Aabb& b);
  /// The box grown by `margin` (m, >= 0) on every side.
  Aabb inflated(double margin) const;
  /// Closed containment test (points on the boundary are inside).
  bool contains(const Vec3& p) const;
  /// The boxes share at least one point (closed boxes).
  bool intersects(const Aabb& b) const;
  /// Smallest box holding this box's image under `pose` (its eight corners
  /// transformed); unbounded stays unbounded, empty stays empty.
  Aabb transformed(const Eigen::Isometry3d& pose) const;
};

}  // namespace sflsh::geometry
