#pragma once
// One time step of backward Euler over a Model (Gast et al. 2015; seed §1):
//   q_{t+1} = argmin_q Σ_terms E_term(q),
// with NewtonOptions::iterations Newton iterations (one by default) in the
// tangent space of every body's q = ({G_i}, z) (configuration.hpp).
//
// Frame: the step is solved in a frame centred on the first body's pelvis at
// time t (physics is translation invariant; one Newton step is not, since
// bones turn about points whose distance to the origin enters the
// linearization). Every world-space input — each body's q_t, q_{t−1}, targets
// and every world frame and anchored point — is translated by the same −c
// (anchor terms shift their points themselves), and the result
// translated back, so a world-fixed obstacle or tool frame stays where the
// scene put it. StepReport energies are those of the centred frame (gravity's
// energy differs by the constant M g·c).
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

/// Advances `state` by the model's h. Kinematic bodies end exactly at their
/// target bones. Throws on inputs that do not fit the model.
StepReport step(const Model& model, State& state, const StepInputs& inputs);

/// World point (m) the step's frame is centred on: the first body's pelvis
/// (joint 0) at time t, or its root bone's origin when it has no joints;
/// the origin for a model without bodies.
Vec3 step_frame_origin(const Model& model, const State& state);

}  // namespace sflsh
