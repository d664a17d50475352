#include "sflsh/teleop/pose_track.hpp"

#include <algorithm>

#include "sflsh/core/error.hpp"

namespace sflsh::teleop {

PoseTrack::PoseTrack(std::vector<PoseSample> samples, const std::string& name) : samples_(std::move(samples)) {
  require(!samples_.empty(), name, ": no pose samples, expected at least one");
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    if (i > 0)
      require(samples_[i].time > samples_[i - 1].time, name, ": sample ", i, " at time ", samples_[i].time,
              " s is not after sample ", i - 1, " at ", samples_[i - 1].time, " s (times must be strictly increasing)");
    require(samples_[i].orientation.norm() > 0.5, name, ": sample ", i, " has a quaternion of norm ",
            samples_[i].orientation.norm(), ", expected a unit quaternion");
    normalize_unless_unit(samples_[i].orientation);
  }
}

PoseSample PoseTrack::at(double t, PoseInterpolation mode) const {
  // First sample strictly after t.
  const auto after = std::upper_bound(samples_.begin(), samples_.end(), t,
                                      [](double time, const PoseSample& s) { return time < s.time; });
  PoseSample out;
  if (after == samples_.begin()) {
    out = samples_.front();
  } else if (after == samples_.end() || mode == PoseInterpolation::kHold) {
    out = *(after - 1);
  } else {
    const PoseSample& a = *(after - 1);
    const PoseSample& b = *after;
    const double u = (t - a.time) / (b.time - a.time);
    out.position = (1.0 - u) * a.position + u * b.position;
    out.orientation = a.orientation.slerp(u, b.orientation);  // Eigen takes the shorter arc
    out.closure = (1.0 - u) * a.closure + u * b.closure;
  }
  out.time = t;
  return out;
}

}  // namespace sflsh::teleop
