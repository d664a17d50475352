// Mass properties against numerical integration over a fine grid (inside =
// the primitive's SDF is negative), and the mesh formula against a box's
// closed form, moved and rotated.
#include <gtest/gtest.h>

#include "sflsh/geometry/mass_properties.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using geometry::MassProperties;

/// Midpoint-rule mass properties of {φ < 0} over the shape's bounds with n³ cells.
MassProperties integrate(const geometry::Sdf& f, double density, int n) {
  const auto box = f.bounds();
  const Vec3 h = (box.max - box.min) / n;
  const double dv = h.prod();
  double m = 0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 x = box.min + h.cwiseProduct(Vec3(i + 0.5, j + 0.5, k + 0.5));
        if (f.distance(x) >= 0) continue;
        m += density * dv;
        first += density * dv * x;
        second += density * dv * x * x.transpose();
      }
  MassProperties p;
  p.mass = m;
  p.center = first / m;
  const Mat3 C = second - m * p.center * p.center.transpose();
  p.inertia = C.trace() * Mat3::Identity() - C;
  return p;
}

void expect_close(const MassProperties& a, const MassProperties& b, double rel) {
  EXPECT_NEAR(a.mass, b.mass, rel * b.mass);
  const double scale = std::cbrt(b.mass);  // any length-ish scale for the centre
  EXPECT_LT((a.center - b.center).norm(), rel * scale);
  EXPECT_LT((a.inertia - b.inertia).norm(), rel * b.inertia.norm()) << "\n" << a.inertia << "\nvs\n" << b.inertia;
}

TEST(MassProperties, PrimitivesMatchGridIntegration) {
  const double rho = 1000;
  const geometry::SphereSdf sphere(0.1);
  expect_close(mass_properties(sphere, rho), integrate(sphere, rho, 160), 3e-3);
  const geometry::BoxSdf box(Vec3(0.1, 0.05, 0.2));
  expect_close(mass_properties(box, rho), integrate(box, rho, 100), 1e-3);  // midpoint rule: O(h²) in ∫x²
  // Short and fat, so that the caps carry most of the transverse moment.
  const geometry::CapsuleSdf capsule(0.08, 0.05);
  expect_close(mass_properties(capsule, rho), integrate(capsule, rho, 200), 3e-3);
  const geometry::CylinderSdf cylinder(0.08, 0.12);
  expect_close(mass_properties(cylinder, rho), integrate(cylinder, rho, 160), 3e-3);
  // Capsule by hand: volume πr²·2h + 4/3πr³.
  EXPECT_NEAR(mass_properties(capsule, rho).mass, rho * (M_PI * 0.0064 * 0.1 + 4.0 / 3 * M_PI * 0.000512), 1e-12);
}

TEST(MassProperties, MeshOfAMovedRotatedBoxMatchesTheClosedForm) {
  const Vec3 b(0.1, 0.05, 0.2);
  Points V(8, 3);
  for (int i = 0; i < 8; ++i) V.row(i) = Vec3(i & 1 ? b.x() : -b.x(), i & 2 ? b.y() : -b.y(), i & 4 ? b.z() : -b.z());
  Triangles F(12, 3);
  F << 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5;
  const Mat3 R = Eigen::AngleAxisd(0.8, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vec3 t(0.3, -1.0, 2.0);
  Points W = (V * R.transpose()).rowwise() + t.transpose();
  const MassProperties mesh = geometry::mesh_mass_properties(W, F, 500);
  const MassProperties exact = mass_properties(geometry::BoxSdf(b), 500);
  EXPECT_NEAR(mesh.mass, exact.mass, 1e-12);
  EXPECT_LT((mesh.center - t).norm(), 1e-12);
  EXPECT_LT((mesh.inertia - R * exact.inertia * R.transpose()).norm(), 1e-12);
  // Inward-oriented faces enclose a negative volume.
  test::expect_error([&] { geometry::mesh_mass_properties(W, Triangles(F.rowwise().reverse()), 500); }, {"volume"});
  // A given mass rescales the inertia.
  const MassProperties two = exact.with_mass(2 * exact.mass);
  EXPECT_LT((two.inertia - 2 * exact.inertia).norm(), 1e-12);
  test::expect_error([&] { mass_properties(geometry::SphereSdf(1), -3); }, {"density"});
}

}  // namespace
}  // namespace sflsh
