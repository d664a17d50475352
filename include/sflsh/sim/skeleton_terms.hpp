#pragma once
// The skeleton's energy terms (seed §3) with documented defaults: bone
// rigid-body inertia and gravity (the skeleton's own mass), joint
// constraints, joint limits and motion-tracking springs.
#include <vector>

#include "sflsh/sim/energies/bone_inertia.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/model.hpp"

namespace sflsh {

struct SkeletonTermsOptions {
  /// Body mass, kg. ≤ 0: estimate_body_mass(avatar) (skin volume × 1000 kg/m³).
  double body_mass = 0.0;
  /// Share of the body mass in the bones' rigid bodies: the skeleton's own
  /// mass (adult skeleton ≈ 15 %); the rest is soft-tissue mass handled by the
  /// soft inertia term (bone_inertia.hpp explains the budget).
  double skeleton_mass_fraction = 0.15;

  bool bone_inertia = true;      ///< rigid-body inertia of the bones
  bool bone_gravity = true;      ///< gravity on the skeleton's own mass
  bool joint_constraints = true; ///< keep the bones connected
  bool joint_limits = true;      ///< anatomical ranges (joint_limits_table.hpp)
  bool tracking = true;          ///< springs to ctx.target_pose

  /// What the spring stiffnesses below (k_j = I_j (2π f)²) take as I_j:
  ///  - Carried (default): the inertia about joint j of everything its
  ///    rotation moves in the simulation, joint_carried_inertia(): the flesh
  ///    (the avatar's inertia cubature, each sample moved by its skinning
  ///    weights' share in the subtree) plus the skeleton's rigid bodies. Then
  ///    every joint's springs have the frequency they are given. An avatar
  ///    without an inertia cubature falls back to Segments.
  ///  - Segments: Winter's segment masses as thin rods (bone_bodies with the
  ///    whole body mass), the earlier rule. It undercounts the flesh
  ///    on the leaves: on the default body the right hand carries 14.5× and
  ///    the head 54× the rod's inertia, so their 20 Hz tracking springs ran at
  ///    5.2 and 2.7 Hz, and `shake` (5 Hz) drove the right hand into ±0.8 rad
  ///    flapping against the rotation cap (1,666 of 10,000 steps damped).
  enum class SpringInertia { Carried, Segments };
  SpringInertia spring_inertia = SpringInertia::Carried;

  /// Joint constraint stiffness k = ratio · body_mass / h² (N/m): a force
  /// body_mass·a opens a joint by a h²/ratio (0.03 mm for g at h = 1/60 s).
  double joint_stiffness_ratio = 100.0;
  /// Joint limit springs k_j = I_j (2π f)² (I_j: subtree inertia about joint j),
  /// f in Hz; stiffer than tracking so limits win over implausible targets.
  double limit_frequency_hz = 30.0;
  /// Tracking springs: k_j = I_j (2π f)², root position k = body_mass (2π f)²
  /// (f in Hz). A constant target acceleration a is followed with a lag of
  /// a/(2π f)² (0.6 mm at g for 20 Hz). Measured with one Newton step per
  /// 1/60 s step (tests/sim/skeleton_terms_test.cpp), 20 Hz, steps solved in
  /// the pelvis-centred frame with bones turning about their joints
  /// (simulator.hpp, configuration.hpp): 1.5 mm / 0.004 rad max joint error on
  /// a 1 Hz walk, 5.6 mm / 0.016 rad at 2 Hz.
  double tracking_frequency_hz = 20.0;
  /// Track the root (pelvis) position and orientation too (false: only the
  /// joint angles follow the motion; the body moves freely, e.g. a body
  /// without a motion falling onto the floor).
  bool track_root = true;
  /// Largest force (N) the root position spring exerts; 0 = unlimited
  /// (energies/tracking.hpp: a Huber spring). Scenes with body contact set it
  /// so that contact, not the motion, decides where bodies meet.
  double root_force_limit = 0.0;
};

/// Body mass (kg) from the closed skin surface of the avatar (volume by the
/// divergence theorem × 1000 kg/m³). Throws if the surface is missing or not
/// closed and outward oriented (volume ≤ 0).
double estimate_body_mass(const Avatar& avatar);

/// Rotational inertia (kg m²) about each joint of everything it moves (the
/// joint's subtree of `bodies`, parallel-axis theorem about J̄_j): the largest
/// principal moment, #J. Joint 0: the whole body about the root joint.
std::vector<double> joint_subtree_inertia(const Avatar& avatar, const std::vector<BoneBody>& bodies);

/// Rotational inertia (kg m²) about each joint j of everything its rotation
/// moves in the simulator, as the largest principal moment (#J):
///   I_j = Σ_s m_s W_sj² (|d_s|² I − d_s d_sᵀ) + Σ_{i ∈ subtree(j)} (rigid body i about J̄_j),
/// d_s = x̄_s − J̄_j, over the avatar's inertia cubature samples s (mass m_s =
/// density × weight, cubature_masses) with W_sj = Σ_{b ∈ subtree(j)} w_sb the
/// share of the sample's skinning weights that joint j turns (a sample moves
/// W_sj as far as the subtree does: the Gauss–Newton inertia Jᵀ M J the
/// Newton step sees), plus `skeleton` (the bones' own rigid bodies, #J) by the
/// parallel-axis theorem. Unposed rest frame. Throws when the avatar has no
/// inertia cubature or `skeleton` does not have one body per joint.
std::vector<double> joint_carried_inertia(const Avatar& avatar, const std::vector<BoneBody>& skeleton);

/// Appends the enabled skeletal terms to `terms`, in the order inertia,
/// gravity, joint constraints, joint limits, tracking.
void add_skeleton_terms(std::vector<EnergyTermPtr>& terms, const Avatar& avatar, const SkeletonTermsOptions& options);
/// The same terms, bound to `body` of `builder`.
void add_skeleton_terms(ModelBuilder& builder, int body, const SkeletonTermsOptions& options);

}  // namespace sflsh
