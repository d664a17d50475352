#pragma once
// Linear momentum of a scene in the integrator's own discrete sense
// (backward Euler with velocity (x_t − x_{t−1})/h): the sum over every
// body's inertia terms — soft tissue (energies/inertia.hpp: cubature samples)
// and rigid bodies (energies/bone_inertia.hpp: bones, rigid objects) — of
// m (x(q_t) − x(q_{t−1}))/h. With only internal forces (no gravity, no
// tracking springs, no world-fixed objects) and Newton iterated to
// convergence, a step conserves it exactly; contact between bodies must too.
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"

namespace sflsh {

/// Σ m v over the model's inertia terms (kg·m/s, world) for `state`.
Vec3 linear_momentum(const Model& model, const State& state);

/// Σ m over the same terms (kg).
double inertial_mass(const Model& model);

}  // namespace sflsh
