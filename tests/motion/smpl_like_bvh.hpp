#pragma once
// Test helper: a BVH whose skeleton is SMPL's (CMU joint names, rest offsets
// equal to SMPL's default rest bones in centimetres), so that retargeting
// needs no rest alignment and SMPL local rotations equal the BVH's (the CMU
// map drives joints 0..21; the hand joints 22, 23 are present but unmapped).
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/motion/retarget.hpp"

namespace sflsh::test {

/// Channel values of one frame: 6 for the root (X/Y/Z position in cm, then
/// Z, Y, X rotation in degrees), then 3 per joint (Z, Y, X rotation), in SMPL
/// joint order.
using FrameValues = std::function<std::vector<double>(int frame)>;

inline std::vector<double> rest_frame_values() {
  const Points J = default_smpl_rest_joints();
  std::vector<double> v(6 + 3 * 23, 0.0);
  for (int c = 0; c < 3; ++c) v[c] = 100 * J(0, c);
  return v;
}

inline std::string smpl_like_bvh(int frames, const FrameValues& values, const std::string& eol = "\n") {
  const Points J = default_smpl_rest_joints();
  const JointMap map = builtin_joint_map("cmu");
  std::vector<std::string> name(kSmplJoints);
  for (const auto& [src, j] : map.entries) name[j] = src;
  name[22] = "LeftFingerBase";  // not in the CMU map: SMPL's hands stay at rest
  name[23] = "RightFingerBase";
  std::ostringstream os;
  os.precision(17);
  os << "HIERARCHY" << eol;
  // Depth-first over SMPL's tree.
  std::function<void(int, int)> emit = [&](int j, int depth) {
    const std::string ind(depth, '\t');
    os << ind << (j == 0 ? "ROOT " : "JOINT ") << name[j] << eol << ind << "{" << eol;
    const Vec3 off = j == 0 ? Vec3::Zero() : Vec3(100 * (J.row(j) - J.row(kSmplParents[j])).transpose());
    os << ind << "\tOFFSET " << off.x() << " " << off.y() << " " << off.z() << eol;
    os << ind << "\tCHANNELS " << (j == 0 ? "6 Xposition Yposition Zposition " : "3 ") << "Zrotation Yrotation Xrotation"
       << eol;
    bool leaf = true;
    for (int c = 0; c < kSmplJoints; ++c)
      if (kSmplParents[c] == j) {
        leaf = false;
        emit(c, depth + 1);
      }
    if (leaf) os << ind << "\tEnd Site" << eol << ind << "\t{" << eol << ind << "\t\tOFFSET 0 5 0" << eol << ind << "\t}" << eol;
    os << ind << "}" << eol;
  };
  emit(0, 0);
  os << "MOTION" << eol << "Frames: " << frames << eol << "Frame Time: 0.01" << eol;
  // Values follow the order joints appear in the file (depth-first), so
  // reorder from SMPL order.
  std::vector<int> file_order;
  std::function<void(int)> order = [&](int j) {
    file_order.push_back(j);
    for (int c = 0; c < kSmplJoints; ++c)
      if (kSmplParents[c] == j) order(c);
  };
  order(0);
  for (int f = 0; f < frames; ++f) {
    const std::vector<double> v = values(f);
    for (int j : file_order) {
      const int b = j == 0 ? 0 : 6 + 3 * (j - 1);
      for (int c = 0; c < (j == 0 ? 6 : 3); ++c) os << v[b + c] << " ";
    }
    os << eol;
  }
  return os.str();
}

}  // namespace sflsh::test
