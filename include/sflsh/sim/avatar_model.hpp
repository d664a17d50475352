#pragma once
// The model of one avatar alone, as `sflsh simulate` runs it: one body, its
// soft-tissue terms and, with dynamic bones, the skeleton's terms.
#include <memory>

#include "sflsh/sim/model.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"

namespace sflsh {

struct SimulatorOptions {
  /// Time step h (s).
  double h = 1.0 / 60.0;
  /// Bones are DoFs of the optimization (true) or prescribed by the motion
  /// (false: bones := target bones each step, only z is solved; "kinematic mode").
  bool bones_dynamic = false;
  /// Gravity (m/s², world, Y up).
  Vec3 gravity = Vec3(0, -9.81, 0);
  /// Stiffness-proportional damping β (s) of the soft tissue; 0 = none.
  double damping = 0.0;
  /// Mean dilatation per cell in the small-strain elastic energy (SoftTissueOptions).
  bool mean_dilatation = true;
  /// Add the soft-tissue terms (inertia, elastic, gravity if |g| > 0, damping if β > 0).
  bool soft_tissue_terms = true;
  /// Newton iterations, line search, step caps, regularization (newton_step.hpp);
  /// defaults: 1 iteration, no line search, 5 cm / 1 rad caps, no diagonal shift unless H fails to factor.
  NewtonOptions newton;
};

/// One body called `name` with the soft-tissue terms (options.soft_tissue_terms)
/// and, when `skeleton` is given, the skeleton terms (usually with dynamic bones).
std::shared_ptr<const Model> avatar_model(std::shared_ptr<const Avatar> avatar, const SimulatorOptions& options,
                                          const SkeletonTermsOptions* skeleton = nullptr,
                                          const std::string& name = "avatar");

/// ModelOptions (h, gravity, Newton) of SimulatorOptions.
ModelOptions model_options(const SimulatorOptions& options);

}  // namespace sflsh
