#pragma once
// The runtime (MuJoCo's model/data split): an immutable Avatar plus the
// changing state (q_t, q_{t−1}, time), advanced by backward Euler written as an
// optimization (Gast et al. 2015; seed §1; DESIGN.md §4):
//   q_{t+1} = argmin_q  Σ_terms E_term(q)   (inertia + potentials),
// solved with `newton_iters` Newton iterations (one by default) in the tangent
// space of q = ({G_i}, z) (configuration.hpp).
//
// The simulator adds the soft-tissue terms itself (inertia, elasticity,
// gravity, optional damping); skeleton terms (bone inertia, joint constraints,
// limits, tracking) are added by whoever builds the scene with add_term().
#include <memory>
#include <vector>

#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/newton_step.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

struct SimulatorOptions {
  /// Time step h (s).
  double h = 1.0 / 60.0;
  /// Bones are DoFs of the optimization (true) or prescribed by the motion
  /// (false: bones := target bones each step, only z is solved; "kinematic mode").
  /// Default false because the simulator alone carries no skeleton terms: a
  /// scene that adds bone inertia/joint/tracking terms switches it on.
  bool bones_dynamic = false;
  /// Gravity (m/s², world, Y up).
  Vec3 gravity = Vec3(0, -9.81, 0);
  /// Stiffness-proportional damping β (s) of the soft tissue (energies/damping.hpp); 0 = none
  /// (backward Euler's own numerical damping remains).
  double damping = 0.0;
  /// Add the soft-tissue terms (inertia, elastic, gravity if |g| > 0, damping if β > 0).
  bool soft_tissue_terms = true;
  /// Newton iterations, line search, step caps, regularization (newton_step.hpp);
  /// defaults: 1 iteration, no line search, 5 cm / 1 rad caps, no diagonal shift unless H fails to factor.
  NewtonOptions newton;
};

class Simulator {
 public:
  /// Builds the soft-tissue terms for `avatar` (kept alive by the simulator)
  /// and puts the state at rest in the unposed configuration (all G_i = I, z = 0).
  Simulator(std::shared_ptr<const Avatar> avatar, SimulatorOptions options = {});

  /// Adds a term to the objective (e.g. skeleton terms); the simulator owns it.
  void add_term(EnergyTermPtr term);
  const std::vector<EnergyTermPtr>& terms() const { return terms_; }

  /// Resets to `bones` (24 world transforms) with z = 0 and zero velocity, time 0.
  void reset(const std::vector<Isometry>& bones);
  /// Resets to an arbitrary state: q_t = q, q_{t−1} = q_previous (velocity (q − q_previous)/h).
  void reset(const Configuration& q, const Configuration& q_previous, double time = 0.0);

  /// Advances one step h to t + h. `target_bones` (24 world transforms at t + h)
  /// are the prescribed bones in kinematic mode and the tracking targets
  /// otherwise; `target_pose` is passed to the terms (tracking springs).
  /// Each step is solved in a frame centred on the pelvis at time t (physics
  /// is translation invariant), so the result does not depend on how far from
  /// the world origin the body is; StepReport energies are measured in that frame.
  StepReport step(const std::vector<Isometry>& target_bones, const BodyPose& target_pose = {});

  const Configuration& state() const { return q_; }
  const Configuration& previous_state() const { return q_prev_; }
  double time() const { return time_; }
  const SimulatorOptions& options() const { return options_; }
  const Avatar& avatar() const { return *avatar_; }
  DofLayout layout() const;

  /// #V by 3 posed skin surface (m, world), pose blend shapes included.
  Points posed_surface() const;
  /// #V by 3 soft displacement u of the surface vertices (m, unposed space).
  Points soft_displacement() const;
  /// 24 by 3 world joint positions (m).
  Points joints() const;
  /// The elastic term (for diagnostics such as the smallest det F).
  const ElasticTerm& elastic() const { return *elastic_; }

 private:
  StepContext context(const std::vector<Isometry>& target_bones, const BodyPose& target_pose) const;
  /// World point (m) the step's frame is centred on: the pelvis at time t.
  Vec3 frame_origin() const;

  std::shared_ptr<const Avatar> avatar_;
  SimulatorOptions options_;
  std::vector<EnergyTermPtr> terms_;
  const ElasticTerm* elastic_ = nullptr;  // owned by terms_ (or by own_elastic_)
  std::unique_ptr<ElasticTerm> own_elastic_;
  PosedPoints surface_;
  Configuration q_, q_prev_;
  double time_ = 0;
};

/// 24 identity bone transforms (the unposed configuration).
std::vector<Isometry> identity_bones();

}  // namespace sflsh
