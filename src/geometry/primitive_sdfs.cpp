#include "sflsh/geometry/primitive_sdfs.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh::geometry {
namespace {

void require_length(double v, const char* shape, const char* what, bool allow_zero = false) {
  require(std::isfinite(v) && (allow_zero ? v >= 0 : v > 0), shape, ": ", what, " must be ",
          allow_zero ? "finite and >= 0" : "finite and > 0", " (m), got ", v);
}

double sign_of(double v) { return v < 0 ? -1.0 : 1.0; }

/// Unit direction of v (its norm goes to *norm); `fallback` when v vanishes
/// (a point on the medial axis, where any direction is a one-sided gradient).
Vec3 unit_or(const Vec3& v, const Vec3& fallback, double* norm) {
  *norm = v.norm();
  return *norm > 0 ? Vec3(v / *norm) : fallback;
}

}  // namespace

PlaneSdf::PlaneSdf(const Vec3& normal, double offset) : c_(offset) {
  require(normal.allFinite() && normal.norm() > 0, "plane: normal must be a finite non-zero vector");
  require(std::isfinite(offset), "plane: offset must be finite, got ", offset);
  n_ = normal.normalized();
}

SdfSample PlaneSdf::evaluate(const Vec3& x, bool) const {
  SdfSample s;
  s.distance = n_.dot(x) - c_;
  s.gradient = n_;
  s.has_hessian = true;  // zero
  return s;
}

SphereSdf::SphereSdf(double radius) : r_(radius) { require_length(radius, "sphere", "radius"); }

SdfSample SphereSdf::evaluate(const Vec3& x, bool want_hessian) const {
  SdfSample s;
  double rho;
  s.gradient = unit_or(x, Vec3::UnitY(), &rho);
  s.distance = rho - r_;
  s.has_hessian = rho > 0;
  if (want_hessian && s.has_hessian) s.hessian = (Mat3::Identity() - s.gradient * s.gradient.transpose()) / rho;
  return s;
}

Aabb SphereSdf::bounds() const { return Aabb(Vec3::Constant(-r_), Vec3::Constant(r_)); }

BoxSdf::BoxSdf(const Vec3& half_extents) : b_(half_extents) {
  for (int i = 0; i < 3; ++i) require_length(half_extents[i], "box", "each half extent");
}

SdfSample BoxSdf::evaluate(const Vec3& x, bool want_hessian) const {
  SdfSample s;
  const Vec3 q = x.cwiseAbs() - b_;
  int axis;
  const double qmax = q.maxCoeff(&axis);
  s.has_hessian = true;
  if (qmax <= 0) {
    // Inside: the nearest face; φ is linear there (zero Hessian).
    s.distance = qmax;
    s.gradient = Vec3::Zero();
    s.gradient[axis] = sign_of(x[axis]);
    return s;
  }
  // Outside: distance to the nearest face, edge or corner, i.e. to the
  // clamped point; only the axes with q > 0 are "active".
  const Vec3 r = q.cwiseMax(0.0);
  const double d = r.norm();
  Mat3 D = Mat3::Zero();
  for (int i = 0; i < 3; ++i) {
    s.gradient[i] = sign_of(x[i]) * r[i] / d;
    D(i, i) = q[i] > 0 ? 1.0 : 0.0;
  }
  s.distance = d;
  if (want_hessian) s.hessian = (D - s.gradient * s.gradient.transpose()) / d;
  return s;
}

CapsuleSdf::CapsuleSdf(double radius, double half_length) : r_(radius), h_(half_length) {
  require_length(radius, "capsule", "radius");
  require_length(half_length, "capsule", "half length", true);
}

SdfSample CapsuleSdf::evaluate(const Vec3& x, bool want_hessian) const {
  SdfSample s;
  const double t = std::clamp(x.y(), -h_, h_);
  double rho;
  s.gradient = unit_or(Vec3(x.x(), x.y() - t, x.z()), Vec3::UnitX(), &rho);
  s.distance = rho - r_;
  s.has_hessian = rho > 0;
  if (want_hessian && s.has_hessian) {
    // Along the segment's interior the closest point slides with y.
    Mat3 P = Mat3::Identity();
    if (std::abs(x.y()) < h_) P(1, 1) = 0.0;
    s.hessian = (P - s.gradient * s.gradient.transpose()) / rho;
  }
  return s;
}

Aabb CapsuleSdf::bounds() const { return Aabb(Vec3(-r_, -h_ - r_, -r_), Vec3(r_, h_ + r_, r_)); }

CylinderSdf::CylinderSdf(double radius, double half_height) : r_(radius), h_(half_height) {
  require_length(radius, "cylinder", "radius");
  require_length(half_height, "cylinder", "half height");
}

SdfSample CylinderSdf::evaluate(const Vec3& x, bool want_hessian) const {
  // A 2-D box in (ρ, y): q = (ρ − R, |y| − H).
  SdfSample s;
  double rho;
  const Vec3 u = unit_or(Vec3(x.x(), 0, x.z()), Vec3::UnitX(), &rho);
  const Vec3 a = sign_of(x.y()) * Vec3::UnitY();
  const double q0 = rho - r_, q1 = std::abs(x.y()) - h_;
  // ∇²ρ = (I − ŷŷᵀ − uuᵀ)/ρ: the radial direction turns around the axis.
  const Mat3 P_perp = Mat3::Identity() - Vec3::UnitY() * Vec3::UnitY().transpose() - u * u.transpose();
  if (q0 <= 0 && q1 <= 0) {
    if (q0 >= q1) {  // nearest: the side wall
      s.distance = q0;
      s.gradient = u;
      s.has_hessian = rho > 0;
      if (want_hessian && s.has_hessian) s.hessian = P_perp / rho;
    } else {  // nearest: a cap
      s.distance = q1;
      s.gradient = a;
      s.has_hessian = true;
    }
    return s;
  }
  const double r0 = std::max(q0, 0.0), r1 = std::max(q1, 0.0);
  const double d = std::hypot(r0, r1);
  s.distance = d;
  s.gradient = (r0 * u + r1 * a) / d;
  s.has_hessian = true;  // r0 > 0 implies ρ > R > 0
  if (want_hessian) {
    Mat3 D = Mat3::Zero();
    if (r0 > 0) D += u * u.transpose();
    if (r1 > 0) D += Vec3::UnitY() * Vec3::UnitY().transpose();
    s.hessian = (D - s.gradient * s.gradient.transpose()) / d;
    if (r0 > 0) s.hessian += (r0 / d) * P_perp / rho;
  }
  return s;
}

Aabb CylinderSdf::bounds() const { return Aabb(Vec3(-r_, -h_, -r_), Vec3(r_, h_, r_)); }

}  // namespace sflsh::geometry
