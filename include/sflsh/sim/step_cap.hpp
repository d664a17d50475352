#pragma once
// Caps on one Newton step (sim/newton_step.hpp), applied to the solved
// tangent step δ before the retraction (sim/configuration.hpp).
//
// Handle cap: the largest handle displacement change |δz_k| bounds the whole
// step (one scale for every DoF; the soft DoFs are coupled through the mesh).
//
// Rotation cap, whole step: the largest |ω_i| bounds the whole step.
//
// Rotation cap, per bone: a bone whose rotation increment |ω_i| exceeds the cap
// gets ω_i ← ω_i · cap/|ω_i| (same axis, the cap's angle), and its linear part
// is changed so that its pivot p_i (DofLayout::bone_pivots: the bone's own
// joint, else the step frame's origin) moves exactly as in the uncapped step:
//   v_i ← v_i + (ω_i − ω_i') × p_i,
// since retract() moves the pivot by v + ω × p. Every other bone, and z, keep
// their full step. newton_minimize caps per bone only when every bone over
// the cap is a leaf (a foot, a hand, the head): capping an inner bone alone
// would pull its children's joints apart (measured: builtin:torture then
// inverts elements and rejects 4,169 of 10⁴ steps). Otherwise, or when the
// per-bone step is not admissible, it scales the whole step to the caps.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// Largest scale ≤ 1 such that scale · |δz_k| ≤ `max_z_step` (m) for every
/// handle k of every body (δ laid out by `bodies`, which sit at their `base`
/// in δ). 1 when `max_z_step` ≤ 0 (no cap) or no handle exceeds it.
double handle_step_scale(const VecX& delta, const std::vector<DofLayout>& bodies, double max_z_step);

/// Largest scale ≤ 1 such that scale · |ω_i| ≤ `max_rotation` (rad) for every
/// dynamic bone i of every body: the whole-step form of the rotation cap. 1
/// when `max_rotation` ≤ 0 or no bone exceeds it.
double rotation_step_scale(const VecX& delta, const std::vector<DofLayout>& bodies, double max_rotation);

/// Whether the rotation cap can be applied per bone: every dynamic bone over
/// `max_rotation` (rad) is a leaf of its body's skeleton (no bone has it as
/// parent), so capping it alone moves no other bone's joint. `parents[b]` is
/// body b's parent table (#bones, −1 for the root) or null (an unknown
/// skeleton: false as soon as a bone is over the cap).
bool rotation_cap_per_bone_applies(const VecX& delta, const std::vector<DofLayout>& bodies,
                                   const std::vector<const std::vector<int>*>& parents, double max_rotation);

/// Caps each dynamic bone's rotation increment at `max_rotation` (rad) in
/// place, keeping that bone's pivot displacement (header comment). `q` holds
/// one configuration per body (the iterate the step starts from, step frame),
/// `bodies` their layouts; δ's entries for bones within the cap, for z and for
/// kinematic bodies are left bit-identical. Returns how many bones were
/// capped. `max_rotation` ≤ 0 disables the cap (returns 0).
int cap_bone_rotations(VecX& delta, const std::vector<Configuration>& q, const std::vector<DofLayout>& bodies,
                       double max_rotation);

}  // namespace sflsh
