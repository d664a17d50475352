#pragma once
// The built-in procedural body ("procedural"): sflsh's embedded default,
// generated at run time by its own code. An SMPL-format model (24 SMPL joints,
// names and tree) of a plausible adult in T-pose, Y up, metres, with a linear
// shape space whose directions are documented in BodyModel::shape_meanings.
#include "sflsh/body/body_model.hpp"

namespace sflsh {

struct ProceduralBodyOptions {
  /// Target surface resolution: approximate vertex count (5k..15k sensible).
  int target_vertices = 9000;
  /// Number of shape directions (>= 8).
  int num_betas = 10;
};

/// Generates the built-in body. Deterministic: the same options give the same
/// arrays bit for bit. Takes well under a second.
BodyModel make_procedural_body(const ProceduralBodyOptions& options = {});

/// The joint positions (24 by 3, metres, SMPL order) that the procedural body
/// is built around for shape coefficients `betas` (its parametric skeleton,
/// before the shape space is linearized; missing entries are 0, at most 10).
/// J_regressor · shape_vertices(model, betas) approximates them; exactly at β = 0.
Points procedural_body_joints(const VecX& betas);

}  // namespace sflsh
