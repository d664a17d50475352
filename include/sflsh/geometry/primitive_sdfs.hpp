#pragma once
// Exact signed distance fields of the analytic primitives, in their local
// frames (axes of symmetry along local +Y, centred at the origin). Each gives
// φ, the unit gradient and the Hessian wherever φ is twice differentiable
// (everywhere off the medial axis and the surface's edge/corner normal
// cones' boundaries). Closed forms: Quílez, "distance functions" (box and
// capped cylinder as a 2-D box in (ρ, y)); the Hessians are (P − n nᵀ)/d,
// P the projector onto the directions the closest feature does not follow.
#include "sflsh/geometry/sdf.hpp"

namespace sflsh::geometry {

/// The half-space {x : n·x ≤ offset} (inside is below the plane).
class PlaneSdf : public Sdf {
 public:
  /// `normal` (non-zero, normalized here) points out of the solid; `offset`
  /// (m) is the plane's distance from the origin along it. Defaults: the
  /// floor y ≤ 0.
  explicit PlaneSdf(const Vec3& normal = Vec3::UnitY(), double offset = 0.0);
  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  Aabb bounds() const override { return Aabb::unbounded(); }
  const Vec3& normal() const { return n_; }
  double offset() const { return c_; }

 private:
  Vec3 n_;
  double c_;
};

/// A ball of radius r (m) centred at the origin.
class SphereSdf : public Sdf {
 public:
  explicit SphereSdf(double radius);
  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  Aabb bounds() const override;
  double radius() const { return r_; }

 private:
  double r_;
};

/// The box [-b, b] (b: half extents, m, each > 0); exact inside and outside,
/// at faces, edges and corners.
class BoxSdf : public Sdf {
 public:
  explicit BoxSdf(const Vec3& half_extents);
  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  Aabb bounds() const override { return Aabb(-b_, b_); }
  const Vec3& half_extents() const { return b_; }

 private:
  Vec3 b_;
};

/// Points within `radius` of the segment from (0, −h, 0) to (0, h, 0)
/// (h = half_length ≥ 0, m; h = 0 is a sphere).
class CapsuleSdf : public Sdf {
 public:
  CapsuleSdf(double radius, double half_length);
  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  Aabb bounds() const override;
  double radius() const { return r_; }
  double half_length() const { return h_; }

 private:
  double r_, h_;
};

/// The finite capped cylinder {ρ ≤ R, |y| ≤ H} (ρ = √(x² + z²); R = radius,
/// H = half_height, m, both > 0); exact at the rims and inside.
class CylinderSdf : public Sdf {
 public:
  CylinderSdf(double radius, double half_height);
  SdfSample evaluate(const Vec3& x, bool want_hessian = false) const override;
  Aabb bounds() const override;
  double radius() const { return r_; }
  double half_height() const { return h_; }

 private:
  double r_, h_;
};

}  // namespace sflsh::geometry
