#pragma once
// The simulation's degrees of freedom q = ({G_i} bone rigid transforms, z)
// (seed §3–4) and how a tangent-space step is laid out and applied.
//
// Bone transform G_i maps unposed (shaped, rest-pose) points to world:
//   x_world = R_i x̄ + t_i   (SMPL's per-joint A matrices / joint_world_transforms).
// Tangent step for bone i: ξ_i = (ω_i, v_i) ∈ R^6, applied on the left, in world
// coordinates: R_i ← exp(ω_i) R_i,  t_i ← exp(ω_i) t_i + v_i.
// So at ξ = 0:  ∂x/∂ω_i = −[x]×,  ∂x/∂v_i = I   for x = G_i x̄.
// Reduced soft DoFs z ∈ R^{3K}: z[3k..3k+2] = displacement of handle k (m, unposed).
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"

namespace sflsh {

using Isometry = Eigen::Isometry3d;

/// A configuration q of the whole avatar.
struct Configuration {
  std::vector<Isometry> bones;  ///< 24 world transforms G_i
  VecX z;                       ///< 3K reduced soft DoFs
};

/// Which DoFs the Newton step solves for, and where they sit in the step vector.
struct DofLayout {
  int num_bones = 24;          ///< bones in the configuration
  bool bones_dynamic = true;   ///< false: bones prescribed (kinematic), only z is solved
  int num_reduced = 0;         ///< 3K
  /// Optional (added by sim2): #num_bones by 3 unposed pivots p̄_i (m), e.g. the
  /// bones' own joints. Empty: every bone retracts about the world origin as
  /// above. Else retract() rotates bone i about p = G_i p̄_i and adds ω × p, so
  /// the tangent (ω, v) and the derivatives ∂x/∂ω = −[x]×, ∂x/∂v = I at ξ = 0 are
  /// unchanged, but the second-order error of a finite step grows with the
  /// distance from the bone's pivot instead of from the world origin (a
  /// swinging hand 0.8 m from the pelvis otherwise opens its stiff joints by cm).
  Points bone_pivots;

  /// Offset of this body's first DoF in the step vector it is part of (0 for
  /// a body alone; the body's place in a scene's or a coupling term's system).
  int base = 0;

  int bone_offset(int i) const { return base + 6 * i; }  ///< valid only if bones_dynamic
  int z_offset() const { return base + (bones_dynamic ? 6 * num_bones : 0); }
  /// DoFs of this body: 6 per dynamic bone plus 3K.
  int size() const { return (bones_dynamic ? 6 * num_bones : 0) + num_reduced; }
  int end() const { return base + size(); }  ///< one past this body's last DoF
};

/// Applies a tangent step to `q`: bones by the exponential map (left, world
/// frame; about layout.bone_pivots when given), z additively. `delta` holds at
/// least layout.end() entries; this body's are [layout.base, layout.end()).
Configuration retract(const Configuration& q, const VecX& delta, const DofLayout& layout);

/// The tangent step that retract() turns `from` into `to` with: retract(from,
/// tangent_between(to, from, layout), layout) = to (each bone's relative
/// rotation below π). Returns layout.end() entries, zero before layout.base.
VecX tangent_between(const Configuration& to, const Configuration& from, const DofLayout& layout);

}  // namespace sflsh
