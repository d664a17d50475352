#pragma once
// Body ↔ body contact through bone capsules (seed §5). Each avatar
// carries capsules on its bones (Avatar::capsules, unposed); posed by their
// bone, two capsules a, b with signed gap d = |p_a − p_b| − r_a − r_b (p_a, p_b
// the closest axis points, geometry/capsule_distance.hpp) get the penalty
//   E = Σ_pairs ½ k min(d, 0)².
// By the envelope theorem ∂d/∂p_a = −n, ∂d/∂p_b = n (n from a to b), and a
// point carried by bone i moves by ω_i × p + v_i, so
//   ∂d/∂ξ_a = −(p_a × n, n),   ∂d/∂ξ_b = (p_b × n, n);
// gradient k d ∂d/∂ξ, Hessian Gauss–Newton k ∂d/∂ξᵀ ∂d/∂ξ (PSD). The forces on
// the two bones are equal and opposite and act along the same line, so linear
// and angular momentum are conserved. It acts on the bones only (kinematic
// bones take no DoFs: a kinematic body pushes, but is not pushed).
//
// Two bodies: every capsule of the first against every capsule of the second.
// One body (self-contact): pairs of capsules whose bones are more than
// `min_bone_separation` joints apart in the skeleton tree and that do not
// already overlap at rest. Broad phase: bounding spheres per capsule at the
// current iterate.
#include <utility>
#include <vector>

#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

struct CapsuleContactOptions {
  double stiffness = 1.0e4;  ///< k, N/m per capsule pair
  /// Self-contact: skip pairs whose bones are at most this many edges apart
  /// in the skeleton tree (2: a bone, its parent, grandparent, siblings).
  int min_bone_separation = 2;
  /// Each capsule's radius is scaled by this (0, 1]: below 1 the capsules are
  /// cores, a backstop under a contact model that lets the flesh give (skin_contact.hpp).
  double radius_scale = 1.0;
};

class CapsuleContactTerm : public EnergyTerm {
 public:
  /// Between the term's two bound bodies (`self` false) or within its one body.
  /// Pairs are fixed here from the avatars' capsules (a: first body's, b: second's).
  CapsuleContactTerm(const Avatar& a, const Avatar* b, const CapsuleContactOptions& options = {});
  std::string name() const override { return self_ ? "self_contact" : "body_contact"; }
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  bool in_nonlinearity_check() const override { return false; }  // a contact term (energy_term.hpp)
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  bool active(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// "force" (3, N: on the first body, world), "overlapping_pairs" (1),
  /// "max_overlap" (1, m) at the final q; while any pair overlaps also
  /// "contact_point" (3, m, world: the midpoints of the pairs' witness points,
  /// weighted by their overlap).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;

  const CapsuleContactOptions& options() const { return options_; }
  /// Candidate pairs (capsule index in a, in b).
  const std::vector<std::pair<int, int>>& pairs() const { return pairs_; }
  /// Largest capsule overlap (m, ≥ 0) of the pairs at bone transforms `bones_a`, `bones_b`.
  double max_overlap(const std::vector<Isometry>& bones_a, const std::vector<Isometry>& bones_b) const;

 private:
  std::vector<BoneCapsule> caps_a_, caps_b_;
  bool self_ = false;
  std::vector<std::pair<int, int>> pairs_;
  CapsuleContactOptions options_;
};

}  // namespace sflsh
