#include "sflsh/sim/joint_limits_table.hpp"

#include "sflsh/body/smpl_skeleton.hpp"

namespace sflsh {

namespace {

JointRange range(Vec3 lower, Vec3 upper) { return {true, lower, upper}; }

/// Mirror image across the sagittal plane (x = 0): a rotation vector
/// (x, y, z) of the left side becomes (x, −y, −z) on the right.
JointRange mirror(const JointRange& left) {
  JointRange r = left;
  r.lower = Vec3(left.lower.x(), -left.upper.y(), -left.upper.z());
  r.upper = Vec3(left.upper.x(), -left.lower.y(), -left.lower.z());
  return r;
}

std::vector<JointRange> build() {
  std::vector<JointRange> t(kSmplJoints);
  const int L[] = {1, 4, 7, 10, 13, 16, 18, 20, 22};  // left joints; right = left + 1
  t[0] = JointRange{};                                               // pelvis: free (root)
  t[1] = range({-2.3, -0.9, -0.5}, {0.6, 0.9, 1.0});                 // left hip
  t[3] = range({-0.5, -0.6, -0.5}, {0.8, 0.6, 0.5});                 // spine1
  t[4] = range({-0.1, -0.5, -0.2}, {2.6, 0.5, 0.2});                 // left knee
  t[6] = t[3];                                                       // spine2
  t[7] = range({-0.5, -0.6, -0.6}, {1.0, 0.6, 0.6});                 // left ankle
  t[9] = t[3];                                                       // spine3
  t[10] = range({-1.0, -0.3, -0.3}, {0.6, 0.3, 0.3});                // left foot (toes)
  t[12] = range({-0.8, -1.2, -0.7}, {0.9, 1.2, 0.7});                // neck
  t[13] = range({-0.5, -0.6, -0.3}, {0.5, 0.4, 0.7});                // left collar
  t[15] = range({-0.7, -0.9, -0.6}, {0.7, 0.9, 0.6});                // head
  t[16] = range({-1.8, -2.0, -1.8}, {1.8, 1.0, 1.6});                // left shoulder
  t[18] = range({-1.6, -2.6, -0.4}, {1.6, 0.1, 0.4});                // left elbow
  t[20] = range({-0.8, -0.6, -1.3}, {0.8, 0.6, 1.1});                // left wrist
  t[22] = range({-0.4, -0.4, -1.6}, {0.4, 0.4, 0.4});                // left hand (fingers)
  for (int l : L) t[l + 1] = mirror(t[l]);
  return t;
}

}  // namespace

const std::vector<JointRange>& smpl_joint_ranges() {
  static const std::vector<JointRange> table = build();
  return table;
}

}  // namespace sflsh
