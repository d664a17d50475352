#include "sflsh/core/rotation.hpp"

#include <cmath>

namespace sflsh {

Mat3 hat(const Vec3& w) {
  Mat3 W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

Mat3 rodrigues(const Vec3& aa) {
  const double t2 = aa.squaredNorm();
  const Mat3 K = hat(aa);
  double a, b;  // R = I + a K + b K^2, a = sin t / t, b = (1 - cos t) / t^2
  if (t2 < 1e-16) {
    a = 1.0 - t2 / 6.0;
    b = 0.5 - t2 / 24.0;
  } else {
    const double t = std::sqrt(t2);
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t2;
  }
  return Mat3::Identity() + a * K + b * K * K;
}

Vec3 rotation_log(const Mat3& R) {
  Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace sflsh
