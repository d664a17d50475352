#pragma once
// One anchored flesh point as a step input: which flesh point an anchor term
// ties for this step and where its tool point is. A tool's grasp of a body is
// the list of these for one anchor term (StepInputs::anchors, indexed by the
// term's AnchorSetId; energies/anchor.hpp says how the term reads them).
#include "sflsh/core/types.hpp"

namespace sflsh {

struct AnchorPoint {
  int point = 0;                      ///< row of the anchor term's flesh points
  Vec3 position = Vec3::Zero();       ///< m, world: the tool point (at t + h kinematic, at t dynamic)
  Vec3 velocity = Vec3::Zero();       ///< m/s, world: the tool point's velocity (kinematic tool; else unused)
};

}  // namespace sflsh
