#pragma once
// Signed distance fields (rigid ↔ flesh contact; seed §5). A field
// lives in its object's local frame: φ(x) < 0 inside, > 0 outside, 0 on the
// surface (m). The contact penalty ½k·min(φ,0)² of a sample needs φ and ∇φ
// (and ∇²φ for an exact Hessian; the Gauss–Newton one k∇φ∇φᵀ needs only ∇φ).
// WorldSdf places a field in the world with a rigid pose.
#include <memory>

#include "sflsh/core/types.hpp"
#include "sflsh/geometry/aabb.hpp"

namespace sflsh::geometry {

/// One evaluation of a field at a point.
struct SdfSample {
  double distance = 0;              ///< φ(x), m (negative inside)
  Vec3 gradient = Vec3::Zero();     ///< ∇φ(x): the unit outward normal for exact fields
  /// ∇²φ(x) (1/m), filled only when asked for and `has_hessian`; zero otherwise.
  Mat3 hessian = Mat3::Zero();
  /// The field defines ∇²φ here (false on a medial axis, or for fields without one).
  bool has_hessian = false;
};

/// A signed distance field in its local frame (immutable, thread-safe to query).
class Sdf {
 public:
  virtual ~Sdf() = default;
  /// φ(x) at a local point x (m).
  virtual double distance(const Vec3& x) const { return evaluate(x, false).distance; }
  /// φ, ∇φ and, with `want_hessian`, ∇²φ at a local point x (m). On a
  /// medial axis (where ∇φ jumps) one of the one-sided gradients is returned.
  virtual SdfSample evaluate(const Vec3& x, bool want_hessian = false) const = 0;
  /// Local box holding the whole surface (and, for finite shapes, the
  /// interior); Aabb::unbounded() for a half-space.
  virtual Aabb bounds() const = 0;
};

using SdfPtr = std::shared_ptr<const Sdf>;

/// A field placed in the world: φ_world(x) = φ(pose⁻¹·x), with the gradient
/// rotated to the world (R∇φ) and the Hessian R∇²φRᵀ.
class WorldSdf {
 public:
  /// `field` must be non-null; `pose` maps local to world coordinates.
  WorldSdf(SdfPtr field, const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity());
  void set_pose(const Eigen::Isometry3d& pose) { pose_ = pose; }
  const Eigen::Isometry3d& pose() const { return pose_; }
  const Sdf& field() const { return *field_; }
  const SdfPtr& field_ptr() const { return field_; }
  /// φ at a world point (m).
  double distance(const Vec3& x_world) const { return field_->distance(pose_.inverse() * x_world); }
  /// φ, ∇φ and (optionally) ∇²φ at a world point, all in world axes.
  SdfSample evaluate(const Vec3& x_world, bool want_hessian = false) const;
  /// World box of the surface (the local bounds under the pose).
  Aabb bounds() const { return field_->bounds().transformed(pose_); }

 private:
  SdfPtr field_;
  Eigen::Isometry3d pose_;
};

}  // namespace sflsh::geometry
