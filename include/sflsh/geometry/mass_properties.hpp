#pragma once
// Mass, centre of mass and inertia of a uniform-density rigid body (dynamic
// rigid objects: mass and inertia from shape and density), for
// the primitive shapes (closed forms, local frame of primitive_sdfs.hpp) and
// for a closed triangle mesh (divergence theorem over the tetrahedra spanned
// by the origin and each face; Eberly, "Polyhedral mass properties").
#include "sflsh/core/types.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"

namespace sflsh::geometry {

struct MassProperties {
  double mass = 0;                 ///< kg
  Vec3 center = Vec3::Zero();      ///< centre of mass, local frame (m)
  Mat3 inertia = Mat3::Zero();     ///< inertia tensor about `center`, local axes (kg·m²)
  /// The same body scaled to `total_mass` kg (> 0): inertia scales with it
  /// (for objects given by mass instead of density).
  MassProperties with_mass(double total_mass) const;
};

/// Uniform solids of `density` kg/m³ (> 0), in the shapes' local frames (centre
/// of mass at the origin). Throws if density is not finite and > 0.
MassProperties mass_properties(const SphereSdf& shape, double density);
MassProperties mass_properties(const BoxSdf& shape, double density);
/// Cylinder of radius r and length 2h plus two hemispherical caps.
MassProperties mass_properties(const CapsuleSdf& shape, double density);
MassProperties mass_properties(const CylinderSdf& shape, double density);

/// The solid bounded by the closed, outward-oriented (counter-clockwise from
/// outside) triangle mesh V (#V by 3, m), F (#F by 3). Throws if the enclosed
/// volume is not positive (open or inward-oriented meshes) or density <= 0.
MassProperties mesh_mass_properties(const Points& V, const Triangles& F, double density);

}  // namespace sflsh::geometry
