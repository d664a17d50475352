#pragma once
// One entry point for every motion source: "builtin:NAME", AMASS .npz, BVH,
// and FBX/DAE/glTF (assimp), with trimming, speed change and resampling.
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

struct MotionOptions {
  /// Output rate (frames/s); 0 keeps the source's rate. Rotations are slerped.
  double fps = 0;
  /// Part of the source to use, seconds of source time; end < 0 means the end.
  double start = 0;
  double end = -1;
  /// Playback speed factor (> 0): 2 plays twice as fast.
  double speed = 1;
  /// Length unit of BVH/assimp files: auto, m, cm, mm, inch or cmu.
  std::string units = "auto";
  /// Joint map file ("source_joint smpl_joint" lines); empty: the built-in map
  /// (cmu or mixamo) matching the file's joint names best.
  std::string joint_map;
  /// 24 by 3 rest joints of the avatar (metres) for retargeting, scaling and
  /// the AMASS axis change; empty: default_smpl_rest_joints().
  Points rest_joints;
  /// Root translation relative to the first frame (see RetargetOptions).
  bool root_from_start = true;
  /// Length and rate of built-in motions ("builtin:NAME"), before trimming.
  double builtin_seconds = 5;
  double builtin_fps = 60;
  /// Read BVH through assimp instead of the own parser (a cross-check).
  bool bvh_via_assimp = false;
  /// BVH/assimp files: drop the file's first frame when the body jumps from
  /// it into the motion (first_frame_jump(), clip_ops.hpp: the T-pose some
  /// converters add as frame 1). A simulation cannot follow such a jump: with
  /// the CMU files' T-pose the pelvis lagged the motion by up to 0.24 m.
  /// Applied before start/end, which count from the first kept frame.
  bool drop_first_frame_jump = true;
};

/// What a load did, for `sflsh motion info` and simulation logs.
struct MotionReport {
  std::string source;        ///< the spec as given
  std::string format;        ///< "builtin", "amass", "bvh", "assimp"
  int source_frames = 0;
  double source_fps = 0;
  int frames = 0;            ///< of the returned clip
  double fps = 0;
  double duration = 0;       ///< seconds, of the returned clip
  std::vector<std::string> source_joints;  ///< the file's joints (BVH/assimp)
  std::string joint_map;     ///< map used (BVH/assimp)
  std::vector<std::string> mapped;   ///< "source -> smpl"
  std::vector<std::string> ignored;  ///< animated source joints not used
  std::vector<std::string> undriven; ///< SMPL joints left at rest
  std::string units;         ///< resolved length unit (BVH/assimp)
  double metres_per_unit = 1;
  double avatar_scale = 1;
  /// The file's first frame was dropped (MotionOptions::drop_first_frame_jump):
  /// its largest joint rotation to the next frame (rad, joint name) and the
  /// largest one between later frames.
  bool dropped_first_frame = false;
  double first_frame_jump = 0, later_max_jump = 0;
  std::string first_frame_jump_joint;
  VecX betas;                ///< AMASS file's shape, if any
  std::string gender;        ///< AMASS file's gender, if any

  /// Multi-line human-readable summary.
  std::string describe() const;
  /// The same as a JSON object.
  std::string to_json() const;
};

/// Loads `spec` ("builtin:NAME", *.npz, *.bvh, or an assimp format by
/// extension), retargets to SMPL, trims to [start, end], applies the speed
/// factor, then resamples to `fps`. Throws sflsh::Error naming the file and
/// what was wrong.
MotionClip load_motion(const std::string& spec, const MotionOptions& options = {}, MotionReport* report = nullptr);

}  // namespace sflsh
