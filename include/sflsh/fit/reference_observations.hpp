#pragma once
// Observations from the full-FEM reference (reference/full_fem.hpp: every tet,
// Newton to convergence) instead of the reduced model: the realistic case for
// `sflsh fit`, where the model that is fitted is not the one that made the data.
#include <memory>
#include <string>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

/// Runs the full-FEM reference on `avatar` (its materials) with the bones of
/// `motion` prescribed, from rest in its first pose, for `seconds` with step h
/// (s), and writes the skin every 1/fps s in the result-file layout
/// (/frames/time, /frames/positions, /meta/motion = `motion_spec`, /meta/dt,
/// /meta/bones = "kinematic"), as path.partial renamed at the end. Fit it with
/// `sflsh fit --start-at-rest`.
void write_reference_observations(std::shared_ptr<const Avatar> avatar, const MotionClip& motion,
                                  const std::string& motion_spec, double seconds, double h, double fps,
                                  const std::string& path);

}  // namespace sflsh
