#include "sflsh/teleop/pose_stream_filter.hpp"

#include <cmath>
#include <sstream>

namespace sflsh::teleop {

long PoseStreamCounters::rejected_total() const {
  long n = 0;
  for (long r : rejected) n += r;
  return n;
}

std::string PoseStreamCounters::describe() const {
  std::ostringstream os;
  os << "received " << received << ", accepted " << accepted << ", rejected " << rejected_total();
  std::string sep = " (";
  for (int i = 0; i < kNumRejectReasons; ++i) {
    if (rejected[i] == 0) continue;
    os << sep << to_string(static_cast<RejectReason>(i)) << ' ' << rejected[i];
    sep = ", ";
  }
  if (sep == ", ") os << ')';
  return os.str();
}

PoseStreamFilter::PoseStreamFilter(const PoseStreamCheckOptions& options) : options_(options) {}

std::optional<RejectReason> PoseStreamFilter::check(const PoseMessage& m, std::string* detail) {
  std::ostringstream os;
  os.precision(17);
  auto reject = [&](RejectReason why) {
    if (detail) *detail = os.str();
    return std::optional<RejectReason>(why);
  };
  const PoseSample& s = m.sample;
  const Eigen::Quaterniond& q = s.orientation;
  const double values[] = {s.time, s.position.x(), s.position.y(), s.position.z(),
                           q.w(), q.x(), q.y(), q.z(), s.closure};
  const char* names[] = {"time", "x", "y", "z", "qw", "qx", "qy", "qz", "closure"};
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(values[i])) {
      os << names[i] << " = " << values[i] << ", expected a finite number";
      return reject(RejectReason::kNonFinite);
    }
  }
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > options_.quaternion_tolerance) {
    os << "|q| = " << norm << ", expected 1 within " << options_.quaternion_tolerance;
    return reject(RejectReason::kBadQuaternion);
  }
  if (s.closure < 0.0 || s.closure > kMaxClosure) {
    os << "closure = " << s.closure << " rad, expected in [0, pi]";
    return reject(RejectReason::kBadClosure);
  }
  if (last_) {
    if (m.sequence <= last_->sequence) {
      os << "sequence " << m.sequence << " after accepted sequence " << last_->sequence;
      return reject(RejectReason::kOutOfOrder);
    }
    const double dt = s.time - last_->sample.time;
    if (!(dt > 0.0)) {
      os << "device time " << s.time << " s, not after the last accepted " << last_->sample.time << " s";
      return reject(RejectReason::kTimeNotIncreasing);
    }
    const double dist = (s.position - last_->sample.position).norm();
    if (dist > options_.max_speed * dt) {
      os << "moved " << dist << " m in " << dt << " s (" << dist / dt << " m/s), faster than the maximum "
         << options_.max_speed << " m/s";
      return reject(RejectReason::kJump);
    }
  }
  PoseMessage good = m;
  normalize_unless_unit(good.sample.orientation);
  last_ = good;
  return std::nullopt;
}

}  // namespace sflsh::teleop
