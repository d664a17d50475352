#include "sflsh/body/smpl_skeleton.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

int smpl_joint_index(std::string_view name) {
  for (int j = 0; j < kSmplJoints; ++j)
    if (kSmplJointNames[j] == name) return j;
  fail("unknown SMPL joint name '", std::string(name), "' (expected one of pelvis, left_hip, ..., right_hand)");
}

}  // namespace sflsh
