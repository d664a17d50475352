#pragma once
// The soft-tissue terms of one body (seed §4; DESIGN.md §4): world-space
// inertia integrated with the inertia cubature (couples bones and z),
// orthotropic StVK with Fung saturation and a volume barrier (the exact
// small-strain quadratic plus the sampled remainder), gravity on the flesh,
// and optional stiffness-proportional damping. A scene adds them to a body
// the same way it adds the skeleton's terms (skeleton_terms.hpp).
#include "sflsh/sim/model.hpp"

namespace sflsh {

struct SoftTissueOptions {
  /// Gravity on the soft tissue (the model's gravity vector; skipped when it is 0).
  bool gravity = true;
  /// Stiffness-proportional damping β (s) of the soft tissue (energies/damping.hpp); 0 = none
  /// (backward Euler's own numerical damping remains).
  double damping = 0.0;
  /// Average the volume change of the small-strain energy per cell of tets
  /// (linearized_stiffness.hpp; against the subspace's volumetric locking;
  /// README, "What the gap was"). false: every tet's own volume change.
  /// The default: with the mass-fitted inertia it halves the error on the jumps;
  /// the compression guard (compression_guard.hpp) keeps the torture run bounded.
  bool mean_dilatation = true;
};

/// Adds, in this order, inertia, elastic, gravity (if enabled and the model's
/// gravity is non-zero) and damping (if β > 0) for `body` of `builder`.
void add_soft_tissue_terms(ModelBuilder& builder, int body, const SoftTissueOptions& options = {});

}  // namespace sflsh
