#pragma once
// Built-in procedural motions, so that everything runs without outside data.
// All are sums of sinusoids under a C1 ease-in envelope: the clip starts at
// SMPL's rest pose (T-pose) with zero velocity and every rotation and the root
// translation are continuously differentiable in time, so the simulator is not
// excited by discontinuities.
#include <string>
#include <vector>

#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

/// Names accepted by builtin_motion ("idle", "jump", "shake", "walk").
std::vector<std::string> builtin_motion_names();

/// The built-in motion `name`, `seconds` long (> 0), sampled at `fps`:
///  - idle:  breathing (0.25 Hz chest) and a slow sway (0.2 Hz, ~1 cm), arms down;
///  - jump:  vertical bouncing at 2 Hz, root up to 15 cm above and 5 cm below
///           rest, knee/hip flexion at landing, arms swinging up in flight;
///  - shake: fast shaking at 5 Hz: root lateral +-2 cm, pelvis roll, spine twist;
///  - walk:  walking in place at 1 step/s (hip/knee swing, arm counter-swing).
/// Throws on an unknown name, listing the known ones.
MotionClip builtin_motion(const std::string& name, double seconds, double fps);

}  // namespace sflsh
