#pragma once
// Finite-difference checks of an Sdf, shared by the geometry tests.
#include <gtest/gtest.h>

#include "sflsh/geometry/sdf.hpp"

namespace sflsh::test {

/// Central-difference gradient of φ at x (step eps, m).
inline Vec3 fd_gradient(const geometry::Sdf& f, const Vec3& x, double eps = 1e-6) {
  Vec3 g;
  for (int a = 0; a < 3; ++a) {
    Vec3 d = Vec3::Zero();
    d[a] = eps;
    g[a] = (f.distance(x + d) - f.distance(x - d)) / (2 * eps);
  }
  return g;
}

/// Central-difference Jacobian of the analytic gradient at x (column a = ∂∇φ/∂x_a).
inline Mat3 fd_hessian(const geometry::Sdf& f, const Vec3& x, double eps = 1e-6) {
  Mat3 H;
  for (int a = 0; a < 3; ++a) {
    Vec3 d = Vec3::Zero();
    d[a] = eps;
    H.col(a) = (f.evaluate(x + d).gradient - f.evaluate(x - d).gradient) / (2 * eps);
  }
  return H;
}

/// Whether the analytic gradient jumps within `eps` of x (x sits on a medial
/// surface, where central differences straddle two branches).
inline bool near_gradient_jump(const geometry::Sdf& f, const Vec3& x, double eps) {
  for (int a = 0; a < 3; ++a) {
    const Vec3 d = eps * Vec3::Unit(a);
    if ((f.evaluate(x + d).gradient - f.evaluate(x - d).gradient).norm() > 0.1) return true;
  }
  return false;
}

/// Expects evaluate(x) to match distance(x), the FD gradient (abs. tol
/// `grad_tol`) and, when has_hessian, the FD Hessian (abs. tol `hess_tol`·(1 + |H|)),
/// with central differences of step `eps` (m).
inline void expect_derivatives_match_fd(const geometry::Sdf& f, const Vec3& x, double grad_tol, double hess_tol,
                                        double eps = 1e-6) {
  const geometry::SdfSample s = f.evaluate(x, true);
  EXPECT_DOUBLE_EQ(s.distance, f.distance(x)) << "x = " << x.transpose();
  EXPECT_LT((s.gradient - fd_gradient(f, x, eps)).norm(), grad_tol)
      << "x = " << x.transpose() << " analytic " << s.gradient.transpose() << " fd " << fd_gradient(f, x, eps).transpose();
  if (s.has_hessian) {
    const Mat3 H_fd = fd_hessian(f, x, eps);
    EXPECT_LT((s.hessian - H_fd).norm(), hess_tol * (1 + H_fd.norm()))
        << "x = " << x.transpose() << "\nanalytic\n" << s.hessian << "\nfd\n" << H_fd;
  }
}

}  // namespace sflsh::test
