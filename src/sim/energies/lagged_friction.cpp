#include "sim/energies/lagged_friction.hpp"

namespace sflsh::contact_friction {

void mollifier(double z, double eps, double& f0, double& f1, double& df1) {
  if (z >= eps) {
    f0 = z, f1 = 1, df1 = 0;
  } else {
    f0 = z * z / eps - z * z * z / (3 * eps * eps) + eps / 3;
    f1 = 2 * z / eps - z * z / (eps * eps);
    df1 = 2 / eps - 2 * z / (eps * eps);
  }
}

PointFriction point_friction(const Vec3& x, const Vec3& y, const Vec3& n, double c, double eps, bool derivatives) {
  const Mat3 P = Mat3::Identity() - n * n.transpose();
  const Vec3 s = P * (x - y);
  const double z = s.norm();
  double f0, f1, df1;
  mollifier(z, eps, f0, f1, df1);
  PointFriction out;
  out.energy = c * f0;
  if (!derivatives) return out;
  // ∂D/∂s and ∂²D/∂s², pulled back through P.
  if (z > 0) out.gradient = c * f1 / z * s;
  Mat3 Hs = (2 / eps) * Mat3::Identity();
  if (z > 0) Hs = (f1 / z) * Mat3::Identity() + (df1 - f1 / z) / (z * z) * s * s.transpose();
  Hs *= c;
  out.hessian = P * Hs * P;
  return out;
}

}  // namespace sflsh::contact_friction
