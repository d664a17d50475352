#pragma once
// A tool trajectory sampled at any time from its pose samples (a pose file,
// keyframes, or a recorded stream).
#include <string>
#include <vector>

#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh::teleop {

enum class PoseInterpolation {
  /// Position and closure linear, orientation slerp (shortest arc) between the
  /// two samples around t. For pose files and keyframes.
  kLinear,
  /// The last sample at or before t (zero-order hold): what a live simulation
  /// used at t. Replaying a PoseRecorder file with kHold gives the simulator
  /// exactly the poses of the recorded session.
  kHold,
};

class PoseTrack {
 public:
  /// `samples`: at least one, times strictly increasing (throws naming `name`
  /// and the offending index otherwise). Quaternions are normalized.
  explicit PoseTrack(std::vector<PoseSample> samples, const std::string& name = "pose track");

  /// The pose at time `t` (s). Before the first sample the first is held,
  /// after the last the last is held; the result's time is `t`.
  PoseSample at(double t, PoseInterpolation mode = PoseInterpolation::kLinear) const;

  double start_time() const { return samples_.front().time; }  ///< s
  double end_time() const { return samples_.back().time; }      ///< s
  const std::vector<PoseSample>& samples() const { return samples_; }

 private:
  std::vector<PoseSample> samples_;
};

}  // namespace sflsh::teleop
