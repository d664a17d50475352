#pragma once
// The mutable half of the runtime (MuJoCo's mjData role): per body q_t and
// q_{t−1}, the time, and the per-step caches of the model's terms; plus the
// per-step inputs (motion targets per body, obstacles' and tools' world frames,
// grasps' anchored points; by input id). A step is a function of (Model, State, StepInputs) (step.hpp).
// A State can be copied and saved/restored (state_file.hpp). A copy gets
// fresh caches (begin_step recomputes them), except those that carry state
// from step to step (TermCache::clone): their copies go with it and are taken
// up by the first step on a model whose term of that place has the same name
// and cache type (the same model, or one rebuilt with its terms rescaled).
// A state file holds the bodies and what those caches carry (saved_state).
#include <memory>
#include <string>
#include <vector>

#include "sflsh/sim/anchor_point.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/world_frame_inputs.hpp"

namespace sflsh {

/// One body's state: q at time t and at t − h (velocity (q − q_prev)/h).
struct BodyState {
  Configuration q, q_prev;
};

/// What drives one body in a step: its target bones at t + h (24 world
/// transforms; the prescribed bones when kinematic, tracking targets
/// otherwise) and the target pose (tracking springs).
struct BodyTargets {
  std::vector<Isometry> bones;
  BodyPose pose;
};

/// Inputs of one step.
struct StepInputs {
  std::vector<BodyTargets> bodies;  ///< one per model body
  WorldFrameInputs frames;          ///< world frames at t + h (world, not shifted), by FrameId
  /// Anchored points per anchor set (by AnchorSetId; world, not shifted). A
  /// set not given, or empty, holds nothing this step.
  std::vector<std::vector<AnchorPoint>> anchors;
};

/// Scratch of a step: the terms' caches and contexts (see header comment).
struct StepWorkspace;

class State {
 public:
  double time = 0;                 ///< s
  std::vector<BodyState> bodies;   ///< one per model body

  State();
  ~State();
  State(const State& other);
  State& operator=(const State& other);
  State(State&&) noexcept;
  State& operator=(State&&) noexcept;

  /// The step's scratch, created for `model` on first use (taking up the
  /// caches a copy carried over).
  StepWorkspace& workspace(const Model& model);

  /// Copies of the caches that carry state (TermCache::clone) with their
  /// terms' names, by model term index (null: none).
  std::vector<std::unique_ptr<TermCache>> carried_caches(std::vector<std::string>* names = nullptr) const;
  /// Hands `cache` to term `term` of `model` for the next step, as a copy of
  /// a State carries it (a state file's restored caches).
  void carry_cache(const Model& model, int term, std::unique_ptr<TermCache> cache);

 private:
  /// Copies of the caches that carry state, by model term index (null: none), with the terms' names.
  struct CarriedCaches {
    std::vector<std::unique_ptr<TermCache>> caches;
    std::vector<std::string> names;
  };
  CarriedCaches carried() const;

  std::unique_ptr<StepWorkspace> workspace_;
  CarriedCaches carried_;  ///< not yet taken up by a workspace
};

/// A state at rest for `model`: every bone G_i = I, z = 0, time 0.
State rest_state(const Model& model);

/// Throws unless `state` fits `model` (body count, 24 bones, z sizes, finite).
void validate_state(const Model& model, const State& state);

}  // namespace sflsh
