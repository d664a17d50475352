#pragma once
// The terms of a dynamic rigid object: a body of the model without
// an avatar (model.hpp), one 6-DoF "bone" G mapping its frame — centred on its
// centre of mass, along its principal or shape axes — to the world. Its
// inertia is the bone-inertia term for a single rigid body,
//   E = 1/(2h²) [ m |c − c*|² + Δωᵀ I Δω ]   (energies/bone_inertia.hpp),
// and gravity −m g·c (energies/bone_gravity.hpp): the same backward-Euler
// objective as the skeleton's bones, in the same Newton solve as the bodies.
#include "sflsh/sim/model.hpp"

namespace sflsh {

/// Adds inertia (mass `mass` kg > 0, inertia tensor `inertia` kg·m² about the
/// centre of mass in the object's axes, symmetric positive definite) and, when
/// the model's gravity is non-zero and `gravity` is true, gravity for the
/// rigid object `body` (false: a tool whose device carries its weight).
void add_rigid_body_terms(ModelBuilder& builder, int body, double mass, const Mat3& inertia, bool gravity = true);

}  // namespace sflsh
