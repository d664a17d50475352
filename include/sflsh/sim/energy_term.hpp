#pragma once
// One potential/inertial term of the backward-Euler objective (Gast et al. 2015):
//   q_{t+1} = argmin  E(q) = Σ_terms E_term(q)
// Terms share this interface so the integrator does not know which exist; a
// scene adds only the terms it needs (STYLE.md). Each gives value, gradient and
// a positive semi-definite Hessian (projected, or Gauss–Newton) with respect to
// the tangent step at q (configuration.hpp).
//
// Blocks. A term is bound to one or more bodies (sim/model.hpp) and declares
// which of each body's DoF blocks it touches (blocks(): the bone blocks, the
// soft block, or both). It fills a *local* gradient and Hessian whose ordering
// is the concatenation of those blocks, described by ctx.layout (one body) or
// ctx.bound[i].layout (several bodies, each with its `base` in the local
// system); the assembler (sim/newton_step.hpp) scatters them into the global
// system, or lets the term write in place when its blocks are contiguous there.
//
// State. Terms are immutable once built (they belong to the Model and can be
// shared across threads and runs). Anything a term computes per step (e.g. the
// inertia's explicit prediction x*) lives in its TermCache, which the State
// owns: make_cache() creates it, begin_step() fills it, compute() reads it.
// A cache that also carries state from one step to the next (the contact
// patch's displacement and its history) says so with clone(): a copied State
// carries a copy of it over, also to a model rebuilt with the same terms.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/body_pose.hpp"
#include "sflsh/sim/anchor_point.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// Writable views of a term's local gradient / Hessian (blocks of the global
/// system, or of a scratch buffer).
using VecRef = Eigen::Ref<VecX>;
using MatRef = Eigen::Ref<MatX>;

/// Which of a bound body's DoF blocks a term touches.
enum class BodyBlocks {
  Bones,        ///< the 6-DoF blocks of the body's dynamic bones
  Soft,         ///< the body's reduced soft block z (3K)
  BonesAndSoft  ///< both (terms on embedded points: inertia, gravity, contact)
};

/// A world frame given as a step input (an obstacle's or a tool's pose):
/// pose at t + h and its twist (ω, v), world frame, rad/s and m/s.
struct WorldFrame {
  Isometry pose = Isometry::Identity();
  Vec3 angular_velocity = Vec3::Zero();
  Vec3 linear_velocity = Vec3::Zero();
};

/// Per-step scratch a term owns inside the State (see header comment).
struct TermCache {
  virtual ~TermCache() = default;
  /// A copy when the cache carries state from step to step; null (the
  /// default) when begin_step recomputes everything in it.
  virtual std::unique_ptr<TermCache> clone() const { return nullptr; }
  /// What a checkpoint keeps of the state it carries (state_file.hpp), as
  /// doubles; empty (the default) when it carries nothing or holds nothing now.
  virtual std::vector<double> saved_state() const { return {}; }
  /// Restores saved_state()'s values into a fresh cache; throws naming
  /// `where` when they cannot be such values (length, NaN, indices).
  virtual void restore_state(const std::vector<double>& values, const std::string& where);
};

/// One body as a term sees it (several for terms that couple bodies).
struct BoundBody {
  int body = 0;                         ///< index in the Model
  int slot = 0;                         ///< index of its configuration in the step's system
  const Avatar* avatar = nullptr;
  DofLayout layout;                     ///< where its touched blocks sit in the term's local system
  const Configuration* q = nullptr;     ///< current iterate (set before every evaluation)
  const Configuration* q_prev = nullptr;   ///< q at time t
  const Configuration* q_prev2 = nullptr;  ///< q at time t − h
};

/// What a term may read about the step being taken. The single-body fields
/// (avatar, layout, q_prev, q_prev2, targets) describe the term's first bound
/// body; `bound` lists every bound body.
///
/// Frame: every world-space quantity here (q, targets, frames; not anchors) is
/// expressed in the step frame, the world translated by −frame_origin (the integrator
/// centres each step on the first body's pelvis: one Newton step of a
/// translation-invariant problem then does not depend on the distance to the
/// world origin). world = step frame + frame_origin.
struct StepContext {
  const Avatar* avatar = nullptr;
  DofLayout layout;
  double h = 1.0 / 60.0;            ///< time step, s
  Vec3 gravity = Vec3(0, -9.81, 0); ///< m/s^2, world
  Configuration q_prev;             ///< q at time t
  Configuration q_prev2;            ///< q at time t − h (velocity = (q_prev − q_prev2)/h)
  /// Target pose at t + h (motion tracking / prescribed bones); joint
  /// transforms of the target in `target_bones` (24 world transforms).
  BodyPose target_pose;
  std::vector<Isometry> target_bones;
  Vec3 frame_origin = Vec3::Zero();  ///< world position of the step frame's origin (m)
  /// The world frames the term reads (EnergyTerm::input_frames(), in that
  /// order) at t + h, in the step frame; null: not given this step.
  std::vector<const WorldFrame*> frames;
  /// The term's anchored points (EnergyTerm::input_anchor_set()) as the step
  /// inputs give them: positions in the world (the term subtracts
  /// frame_origin); null: none given this step.
  const std::vector<AnchorPoint>* anchors = nullptr;
  std::vector<BoundBody> bound;      ///< every bound body (bound[0] = the fields above)
  TermCache* cache = nullptr;        ///< the term's own cache in the State (null if it has none)

  /// The i-th of the term's input frames, or null when it is not given.
  const WorldFrame* frame(size_t i = 0) const { return i < frames.size() ? frames[i] : nullptr; }
};

/// A typed quantity a term reports after a step (e.g. a reaction force).
struct TermQuantity {
  std::string name;   ///< e.g. "contact_force"
  std::string unit;   ///< e.g. "N"
  /// The value (a vector; a scalar is one entry). A "contact_point" (3, m) is
  /// in the step's centred frame (step.hpp); StepReport holds it in the world.
  VecX value;
};

class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  /// Short name for diagnostics ("inertia", "elastic", ...).
  virtual std::string name() const = 0;
  /// The blocks of each bound body this term touches (default: bones and soft).
  virtual BodyBlocks blocks() const { return BodyBlocks::BonesAndSoft; }
  /// The world frames the term reads each step, by name (default: none). The
  /// ModelBuilder registers them (add_frame) and the step hands the term
  /// their values in this order (StepContext::frames).
  virtual std::vector<std::string> input_frames() const { return {}; }
  /// The set of anchored points the term reads each step, by name ("" = none,
  /// the default); registered like input_frames() (StepContext::anchors).
  virtual std::string input_anchor_set() const { return ""; }
  /// A fresh per-step cache for this term, or null when it needs none.
  virtual std::unique_ptr<TermCache> make_cache() const { return nullptr; }
  /// Called once per time step before the Newton iterations (e.g. to compute
  /// the explicit prediction x* from q_prev, q_prev2 into ctx.cache).
  virtual void begin_step(const StepContext& ctx) const {}
  /// Whether the term takes part in this step (after begin_step; e.g. a contact
  /// term with nothing near, an anchor not grasping). Inactive terms cost nothing.
  virtual bool active(const StepContext& ctx) const { return true; }
  /// Whether the Newton solver's nonlinearity check (NewtonOptions::
  /// nonlinearity_tolerance) measures this term. Contact terms answer false:
  /// a penalty whose samples enter and leave contact within a step departs
  /// from its quadratic model whatever the flesh does, and a second Newton
  /// iteration does not change what it gives (a probe's force, contact figures).
  virtual bool in_nonlinearity_check() const { return true; }
  /// Energy at q (J), q = the first bound body's configuration. If `grad` is
  /// non-null, adds ∂E/∂δ (ctx.layout's local ordering); if `hess` is non-null,
  /// adds a PSD approximation of ∂²E/∂δ² (dense, local, square). Returns
  /// +infinity for inadmissible q (e.g. an inverted element), which the step rejects.
  virtual double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const = 0;
  /// Quantities to report after the step at the final q (default: none).
  virtual std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const { return {}; }

  /// compute() on plain vectors (sized by the caller): for tests and tools.
  double evaluate(const StepContext& ctx, const Configuration& q, VecX* grad, MatX* hess) const;
};

using EnergyTermPtr = std::unique_ptr<EnergyTerm>;

/// Creates the term's cache, points ctx.cache at it and calls begin_step: the
/// one-term version of what the integrator does at the start of a step.
std::unique_ptr<TermCache> begin_term_step(const EnergyTerm& term, StepContext& ctx);

}  // namespace sflsh
