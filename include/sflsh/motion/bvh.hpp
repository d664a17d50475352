#pragma once
// BVH (Biovision Hierarchy) motion files: a HIERARCHY of joints (ROOT/JOINT
// with OFFSET, CHANNELS and End Site) followed by a MOTION block ("Frames: N",
// "Frame Time: dt", then one line of channel values per frame). Rotation
// channels are degrees and are applied in the order listed (the local
// rotation is R = R_c1 * R_c2 * R_c3, intrinsic axes); positions are in the
// file's length units. LF and CRLF line endings, tabs and spaces are accepted.
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"

namespace sflsh {

enum class BvhChannel { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

struct BvhJoint {
  std::string name;
  int parent = -1;              ///< index into BvhMotion::joints, -1 for the root
  Vec3 offset = Vec3::Zero();   ///< rest translation from the parent (file units)
  std::vector<BvhChannel> channels;
  int first_channel = 0;        ///< column of channels[0] in a frame's values
  bool has_end_site = false;
  Vec3 end_site = Vec3::Zero(); ///< End Site offset (file units), if any
};

struct BvhMotion {
  std::string path;             ///< for messages
  std::vector<BvhJoint> joints; ///< in file order (parents before children)
  int num_channels = 0;         ///< values per frame
  int num_frames = 0;
  double frame_time = 0;        ///< seconds per frame
  std::vector<double> values;   ///< #frames by num_channels, row-major

  double value(int frame, int channel) const { return values[size_t(frame) * num_channels + channel]; }
  /// Local rotation of joint j at `frame` from its rotation channels.
  Eigen::Quaterniond local_rotation(int joint, int frame) const;
  /// Local translation of joint j at `frame`: offset + position channels.
  Vec3 local_translation(int joint, int frame) const;
};

/// Reads and parses a BVH file. Throws sflsh::Error "<path>:<line>: ..."
/// naming what was expected on malformed input.
BvhMotion read_bvh(const std::string& path);

/// Parses BVH text held in memory; `name` is used in messages.
BvhMotion parse_bvh(std::string_view text, const std::string& name);

}  // namespace sflsh
