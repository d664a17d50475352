#include "sflsh/geometry/mass_properties.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh::geometry {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require_density(double density) {
  require(std::isfinite(density) && density > 0, "mass properties: density must be finite and > 0 kg/m^3, got ", density);
}

/// A body symmetric about the origin with principal moments (Ixx, Iyy, Izz).
MassProperties centred(double mass, double ixx, double iyy, double izz) {
  MassProperties p;
  p.mass = mass;
  p.inertia = Vec3(ixx, iyy, izz).asDiagonal();
  return p;
}

}  // namespace

MassProperties MassProperties::with_mass(double total_mass) const {
  require(std::isfinite(total_mass) && total_mass > 0, "mass properties: mass must be finite and > 0 kg, got ", total_mass);
  require(mass > 0, "mass properties: cannot rescale a body of zero mass");
  MassProperties p = *this;
  p.mass = total_mass;
  p.inertia *= total_mass / mass;
  return p;
}

MassProperties mass_properties(const SphereSdf& s, double density) {
  require_density(density);
  const double r = s.radius(), m = density * 4.0 / 3.0 * kPi * r * r * r, i = 0.4 * m * r * r;
  return centred(m, i, i, i);
}

MassProperties mass_properties(const BoxSdf& s, double density) {
  require_density(density);
  const Vec3 b = s.half_extents();
  const double m = density * 8 * b.prod();
  return centred(m, m / 3 * (b.y() * b.y() + b.z() * b.z()), m / 3 * (b.x() * b.x() + b.z() * b.z()),
                 m / 3 * (b.x() * b.x() + b.y() * b.y()));
}

MassProperties mass_properties(const CylinderSdf& s, double density) {
  require_density(density);
  const double r = s.radius(), h = s.half_height(), m = density * kPi * r * r * 2 * h;
  const double transverse = m * (3 * r * r + 4 * h * h) / 12;
  return centred(m, transverse, 0.5 * m * r * r, transverse);
}

MassProperties mass_properties(const CapsuleSdf& s, double density) {
  require_density(density);
  const double r = s.radius(), h = s.half_length();
  const double m_cyl = density * kPi * r * r * 2 * h, m_hemi = density * 2.0 / 3.0 * kPi * r * r * r;
  // A hemisphere's centroid sits 3r/8 from its flat face; about that centroid
  // its transverse moment is (83/320)·m·r², its axial one (2/5)·m·r².
  const double d = h + 3.0 * r / 8.0;
  const double transverse =
      m_cyl * (3 * r * r + 4 * h * h) / 12 + 2 * m_hemi * (83.0 / 320.0 * r * r + d * d);
  const double axial = 0.5 * m_cyl * r * r + 2 * 0.4 * m_hemi * r * r;
  return centred(m_cyl + 2 * m_hemi, transverse, axial, transverse);
}

MassProperties mesh_mass_properties(const Points& V, const Triangles& F, double density) {
  require_density(density);
  double vol = 0;
  Vec3 first = Vec3::Zero();     // ∫ x dV
  Mat3 second = Mat3::Zero();    // ∫ x xᵀ dV
  for (int f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    // Tetrahedron (0, a, b, c): signed volume det/6, ∫x = vol·(a+b+c)/4,
    // ∫x xᵀ = det/120 · (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c.
    const double det = a.dot(b.cross(c));
    const Vec3 s = a + b + c;
    vol += det / 6;
    first += det / 24 * s;
    second += det / 120 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  require(vol > 0, "mass properties: the mesh encloses a volume of ", vol,
          " m^3; expected a closed mesh with faces counter-clockwise seen from outside");
  MassProperties p;
  p.mass = density * vol;
  p.center = first / vol;
  // Second moment about the centre, then I = tr(C)·1 − C.
  const Mat3 C = density * (second - vol * p.center * p.center.transpose());
  p.inertia = C.trace() * Mat3::Identity() - C;
  return p;
}

}  // namespace sflsh::geometry
