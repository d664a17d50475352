#include "sflsh/motion/builtin_motions.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Joint indices (kSmplJointNames).
enum J { kPelvis = 0, kLHip = 1, kRHip = 2, kSpine1 = 3, kLKnee = 4, kRKnee = 5, kSpine2 = 6, kLAnkle = 7,
         kRAnkle = 8, kSpine3 = 9, kNeck = 12, kHead = 15, kLShoulder = 16, kRShoulder = 17, kLElbow = 18,
         kRElbow = 19 };

/// One frame as Euler-angle increments (radians, applied as Rz*Ry*Rx in the
/// joint's local SMPL frame) and root translation (metres).
struct Frame {
  Vec3 euler[kSmplJoints];
  Vec3 trans = Vec3::Zero();
  Frame() {
    for (auto& e : euler) e.setZero();
  }
};

using FrameFn = std::function<void(double t, Frame&)>;

// SMPL axes: Y up, +Z forward, +X to the body's left. Hip flexion (knee
// forward) is a negative X rotation, knee flexion a positive one; the left arm
// lies along +X, so lowering it is a negative Z rotation (positive for the right).
void arms_down(Frame& f, double angle) {
  f.euler[kLShoulder].z() -= angle;
  f.euler[kRShoulder].z() += angle;
}

void idle(double t, Frame& f) {
  const double breath = std::sin(2 * kPi * 0.25 * t), sway = std::sin(2 * kPi * 0.2 * t);
  f.trans.x() = 0.01 * sway;
  f.euler[kPelvis].z() = -0.015 * sway;
  f.euler[kSpine3].x() = -0.02 * breath;  // chest lifts slightly on inhale
  f.euler[kNeck].x() = 0.01 * breath;
  f.euler[kHead].y() = 0.05 * std::sin(2 * kPi * 0.1 * t);
  arms_down(f, 1.2 + 0.03 * breath);
  f.euler[kLElbow].y() = 0.15;
  f.euler[kRElbow].y() = -0.15;
}

void jump(double t, Frame& f) {
  // Phase: c = +1 at landing (lowest point, knees bent), -1 at the apex.
  const double w = 2 * kPi * 2.0;
  const double c = std::cos(w * t);
  const double crouch = 0.5 * (1 + c);  // 1 at landing, 0 at apex
  f.trans.y() = 0.15 * (1 - crouch) - 0.05 * crouch;
  const double hip = -0.6 * crouch, knee = 1.1 * crouch;
  for (int s = 0; s < 2; ++s) {
    f.euler[s ? kRHip : kLHip].x() = hip;
    f.euler[s ? kRKnee : kLKnee].x() = knee;
    f.euler[s ? kRAnkle : kLAnkle].x() = -(hip + knee) * 0.8;  // keep the feet roughly flat
  }
  f.euler[kSpine1].x() = 0.25 * crouch;  // lean forward when crouching
  // Arms swing back at landing and up in flight.
  arms_down(f, 1.1 - 0.7 * (1 - crouch));
  f.euler[kLShoulder].y() = 0.4 * c;
  f.euler[kRShoulder].y() = -0.4 * c;
  f.euler[kLElbow].y() = 0.3;
  f.euler[kRElbow].y() = -0.3;
}

void shake(double t, Frame& f) {
  const double w = 2 * kPi * 5.0;
  const double s = std::sin(w * t), c = std::cos(w * t);
  f.trans.x() = 0.02 * s;
  f.trans.y() = 0.005 * std::sin(2 * w * t);
  f.euler[kPelvis].z() = 0.08 * s;     // hip roll
  f.euler[kPelvis].y() = 0.05 * c;     // hip yaw
  f.euler[kSpine1].y() = -0.08 * c;    // spine twist against the hips
  f.euler[kSpine2].y() = -0.08 * c;
  f.euler[kSpine3].y() = -0.06 * c;
  f.euler[kSpine1].z() = -0.05 * s;
  f.euler[kLHip].z() = -0.08 * s;      // legs keep the feet under the body
  f.euler[kRHip].z() = -0.08 * s;
  f.euler[kLKnee].x() = 0.15;
  f.euler[kRKnee].x() = 0.15;
  f.euler[kLHip].x() = -0.08;
  f.euler[kRHip].x() = -0.08;
  arms_down(f, 1.0 + 0.15 * s);
  f.euler[kLElbow].y() = 0.5;
  f.euler[kRElbow].y() = -0.5;
}

void walk(double t, Frame& f) {
  const double w = 2 * kPi * 0.5;  // one stride (two steps) per 2 s
  const double s = std::sin(w * t);
  const double ls = std::max(0.0, std::sin(w * t + kPi / 2)), rs = std::max(0.0, -std::sin(w * t + kPi / 2));
  f.euler[kLHip].x() = -0.4 * s;
  f.euler[kRHip].x() = 0.4 * s;
  // Knees bend during swing (smooth: squared positive part is C1).
  f.euler[kLKnee].x() = 0.1 + 0.7 * ls * ls;
  f.euler[kRKnee].x() = 0.1 + 0.7 * rs * rs;
  f.euler[kPelvis].y() = 0.08 * s;
  f.euler[kSpine3].y() = -0.12 * s;
  f.trans.y() = 0.01 * std::cos(2 * w * t);
  arms_down(f, 1.25);
  f.euler[kLShoulder].y() = 0.35 * s;
  f.euler[kRShoulder].y() = 0.35 * s;
  f.euler[kLElbow].y() = 0.25;
  f.euler[kRElbow].y() = -0.25;
}

const std::vector<std::pair<std::string, FrameFn>>& table() {
  static const std::vector<std::pair<std::string, FrameFn>> t = {
      {"idle", idle}, {"jump", jump}, {"shake", shake}, {"walk", walk}};
  return t;
}

// C1 ease-in over the first `ramp` seconds: 3u^2 - 2u^3 has zero slope at both
// ends, so the clip leaves the rest pose with zero velocity.
double ease_in(double t, double ramp) {
  const double u = std::clamp(t / ramp, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

}  // namespace

std::vector<std::string> builtin_motion_names() {
  std::vector<std::string> names;
  for (const auto& [n, fn] : table()) names.push_back(n);
  return names;
}

MotionClip builtin_motion(const std::string& name, double seconds, double fps) {
  const FrameFn* fn = nullptr;
  std::string known;
  for (const auto& [n, f] : table()) {
    if (n == name) fn = &f;
    known += (known.empty() ? "" : ", ") + n;
  }
  require(fn != nullptr, "unknown built-in motion '", name, "' (known: ", known, ")");
  require(seconds > 0 && std::isfinite(seconds), "builtin:", name, ": duration must be positive, got ", seconds);
  require(fps > 0 && std::isfinite(fps), "builtin:", name, ": frame rate must be positive, got ", fps);
  const int frames = int(std::floor(seconds * fps + 1e-6)) + 1;
  require(frames <= 10'000'000, "builtin:", name, ": ", frames, " frames is too many");
  MotionClip clip;
  clip.name = "builtin:" + name;
  clip.fps = fps;
  clip.rotations.resize(frames);
  clip.translations.resize(frames);
  const double ramp = 0.5;
  for (int i = 0; i < frames; ++i) {
    const double t = i / fps;
    Frame f;
    (*fn)(t, f);
    const double e = ease_in(t, ramp);
    clip.translations[i] = e * f.trans;
    clip.rotations[i].resize(kSmplJoints);
    for (int j = 0; j < kSmplJoints; ++j) {
      const Vec3 a = e * f.euler[j];
      clip.rotations[i][j] = Eigen::AngleAxisd(a.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(a.y(), Vec3::UnitY()) *
                             Eigen::AngleAxisd(a.x(), Vec3::UnitX());
    }
  }
  return clip;
}

}  // namespace sflsh
