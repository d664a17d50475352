#include "sflsh/viewer/result_player.hpp"

#include <algorithm>

#include "sflsh/core/error.hpp"

namespace sflsh::viewer {

int frame_at(const std::vector<double>& times, double t) {
  require(!times.empty(), "viewer: the result has no frames");
  const auto it = std::upper_bound(times.begin(), times.end(), t + 1e-9);
  return it == times.begin() ? 0 : int(it - times.begin()) - 1;
}

ViewerFrame result_frame(const SimulationResult& r, int f) {
  require(f >= 0 && f < int(r.frame_positions.size()), "viewer: frame ", f, " of ", r.frame_positions.size());
  ViewerFrame v;
  v.time = r.frame_time[f];
  v.positions = r.frame_positions[f];
  v.displacement = r.frame_displacement[f].rowwise().norm();
  if (f < int(r.frame_joints.size())) v.joints = r.frame_joints[f];
  for (const ObjectTrack& o : r.objects) v.object_poses.push_back(o.poses.at(f));
  for (const ToolTrack& t : r.tools) v.tools.push_back(t.frames.at(f));
  for (const ContactTrack& c : r.contacts) v.contacts.push_back(c.frames.at(f));
  v.stats.frame_index = f;
  v.stats.max_displacement = v.displacement.size() ? v.displacement.maxCoeff() : 0.0;
  if (f < int(r.frame_step_ms.size())) v.stats.step_ms = r.frame_step_ms[f];
  return v;
}

ResultPlayer::ResultPlayer(const SimulationResult& result) : result_(result) {
  require(!result.frame_time.empty(), "viewer: the result has no frames to play");
  time_ = result.frame_time.front();
}

bool ResultPlayer::apply(const ControlMessage& m) {
  const double first = result_.frame_time.front(), last = result_.frame_time.back();
  switch (m.type) {
    case ControlType::kPause:
      if (!m.paused && time_ >= last) time_ = first;
      paused_ = m.paused;
      return true;
    case ControlType::kSeek:
      time_ = std::clamp(m.value, first, last);
      return true;
    case ControlType::kSpeed:
      speed_ = m.value;
      return true;
    case ControlType::kStep: {
      paused_ = true;
      const int f = std::min(frame() + 1, int(result_.frame_time.size()) - 1);
      time_ = result_.frame_time[f];
      return true;
    }
    case ControlType::kReset:
      paused_ = true;
      time_ = first;
      return true;
    case ControlType::kTool:
    case ControlType::kStiffness:
      return false;
  }
  return false;
}

void ResultPlayer::advance(double wall_seconds) {
  if (paused_) return;
  time_ += wall_seconds * speed_;
  if (time_ >= result_.frame_time.back()) {
    time_ = result_.frame_time.back();
    paused_ = true;
  }
}

ViewerFrame ResultPlayer::current() const {
  ViewerFrame v = result_frame(result_, frame());
  v.time = time_;
  v.stats.paused = paused_;
  v.stats.speed = speed_;
  return v;
}

}  // namespace sflsh::viewer
