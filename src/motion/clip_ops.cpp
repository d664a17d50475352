#include "sflsh/motion/clip_ops.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {

Eigen::Quaterniond quaternion_from_axis_angle(const Vec3& aa) {
  const double angle = aa.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * aa.x(), 0.5 * aa.y(), 0.5 * aa.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, aa / angle));
}

Vec3 axis_angle_from_quaternion(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // same rotation, angle in [0, pi]
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();      // first-order: angle*axis = 2 sin(a/2) axis
  const double angle = 2.0 * std::atan2(s, q.w());
  return q.vec() * (angle / s);
}

FirstFrameJump first_frame_jump(const MotionClip& clip) {
  FirstFrameJump out;
  // Largest local rotation (rad) of any joint between frames f and f + 1.
  auto largest_turn = [&](int f, int* joint) {
    double best = -1;
    for (int j = 0; j < int(clip.rotations[f].size()) && j < int(clip.rotations[f + 1].size()); ++j) {
      const double a = clip.rotations[f][j].angularDistance(clip.rotations[f + 1][j]);
      if (a > best) best = a, *joint = j;
    }
    return std::max(best, 0.0);
  };
  if (clip.num_frames() < 2) return out;
  out.angle = largest_turn(0, &out.joint);
  int unused = -1;
  for (int f = 1; f + 1 < clip.num_frames(); ++f) out.later_max = std::max(out.later_max, largest_turn(f, &unused));
  out.discontinuous = clip.num_frames() >= 3 && out.angle > 0.5 && out.angle > 2.5 * out.later_max;
  return out;
}

void validate_clip(const MotionClip& clip) {
  require(clip.fps > 0 && std::isfinite(clip.fps), clip.name, ": frame rate must be positive, got ", clip.fps);
  require(clip.num_frames() > 0, clip.name, ": motion has no frames");
  require(clip.translations.size() == clip.rotations.size(), clip.name, ": ", clip.rotations.size(),
          " rotation frames but ", clip.translations.size(), " translations");
  require(clip.joint_driven.size() == size_t(kSmplJoints), clip.name, ": joint_driven has ",
          clip.joint_driven.size(), " entries, expected 24");
  for (int f = 0; f < clip.num_frames(); ++f) {
    require(clip.rotations[f].size() == size_t(kSmplJoints), clip.name, ": frame ", f, " has ",
            clip.rotations[f].size(), " rotations, expected 24");
    for (int j = 0; j < kSmplJoints; ++j) {
      const auto& q = clip.rotations[f][j];
      require(q.coeffs().allFinite() && std::abs(q.norm() - 1.0) < 1e-6, clip.name, ": frame ", f, " joint ",
              kSmplJointNames[j], ": rotation is not a finite unit quaternion");
    }
    require(clip.translations[f].allFinite(), clip.name, ": frame ", f, ": root translation is not finite");
  }
}

void interpolate_frame(const MotionClip& clip, double t, std::vector<Eigen::Quaterniond>* rotations,
                       Vec3* translation) {
  const int n = clip.num_frames();
  require(n > 0, clip.name, ": cannot sample a motion without frames");
  require(clip.fps > 0, clip.name, ": frame rate must be positive, got ", clip.fps);
  require(std::isfinite(t), clip.name, ": sample time is not finite");
  const double f = std::clamp(t * clip.fps, 0.0, double(n - 1));
  const int i0 = std::min(int(std::floor(f)), n - 1);
  const int i1 = std::min(i0 + 1, n - 1);
  const double a = f - i0;
  rotations->resize(kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j)
    (*rotations)[j] = clip.rotations[i0][j].slerp(a, clip.rotations[i1][j]).normalized();
  if (translation) {
    const bool has_trans = clip.translations.size() == size_t(n);
    *translation = has_trans ? Vec3((1 - a) * clip.translations[i0] + a * clip.translations[i1]) : Vec3::Zero();
  }
}

namespace {
// Samples `clip` at times t0 + i / fps for i = 0..count-1 (the shared core of
// resample and trim).
MotionClip sample_times(const MotionClip& clip, double t0, double fps, int count) {
  MotionClip out;
  out.name = clip.name;
  out.fps = fps;
  out.joint_driven = clip.joint_driven;
  out.rotations.resize(count);
  out.translations.resize(count);
  for (int i = 0; i < count; ++i) interpolate_frame(clip, t0 + i / fps, &out.rotations[i], &out.translations[i]);
  return out;
}
}  // namespace

MotionClip resample(const MotionClip& clip, double fps) {
  require(fps > 0 && std::isfinite(fps), clip.name, ": resampling rate must be positive, got ", fps);
  require(clip.num_frames() > 0, clip.name, ": cannot resample a motion without frames");
  const int count = int(std::floor(clip.duration() * fps + 1e-6)) + 1;
  return sample_times(clip, 0.0, fps, count);
}

MotionClip trim(const MotionClip& clip, double start_s, double end_s) {
  const double duration = clip.duration();
  if (end_s < 0) end_s = duration;
  require(start_s >= 0 && start_s <= duration + 1e-9, clip.name, ": start ", start_s,
          " s is outside the motion (duration ", duration, " s)");
  end_s = std::min(end_s, duration);
  require(end_s >= start_s, clip.name, ": end ", end_s, " s is before start ", start_s, " s");
  const int count = int(std::floor((end_s - start_s) * clip.fps + 1e-6)) + 1;
  return sample_times(clip, start_s, clip.fps, count);
}

MotionClip change_speed(const MotionClip& clip, double speed) {
  require(speed > 0 && std::isfinite(speed), clip.name, ": speed factor must be positive, got ", speed);
  MotionClip out = clip;
  out.fps = clip.fps * speed;
  return out;
}

void clip_to_smpl_params(const MotionClip& clip, MatXr* poses, MatXr* trans) {
  const int n = clip.num_frames();
  poses->resize(n, 3 * kSmplJoints);
  trans->resize(n, 3);
  for (int f = 0; f < n; ++f) {
    // Element-wise copies: GCC 12 misreads 1x3 block assignments under AVX-512.
    for (int j = 0; j < kSmplJoints; ++j) {
      const Vec3 aa = axis_angle_from_quaternion(clip.rotations[f][j]);
      for (int c = 0; c < 3; ++c) (*poses)(f, 3 * j + c) = aa[c];
    }
    const Vec3 t = f < int(clip.translations.size()) ? clip.translations[f] : Vec3(Vec3::Zero());
    for (int c = 0; c < 3; ++c) (*trans)(f, c) = t[c];
  }
}

}  // namespace sflsh
