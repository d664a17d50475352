#include "sflsh/scene/torture_motion.hpp"

#include <cmath>
#include <random>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/motion/clip_ops.hpp"

namespace sflsh {
namespace {

/// Uniform in [0, 1) from the top 53 bits: the same on every platform.
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

}  // namespace

MotionClip torture_motion(const std::vector<JointRange>& ranges, const TortureOptions& o) {
  require(int(ranges.size()) == kSmplJoints, "torture_motion: ", ranges.size(), " joint ranges, expected ", kSmplJoints);
  require(o.seconds > 0 && std::isfinite(o.seconds), "builtin:torture: duration must be positive, got ", o.seconds);
  require(o.fps > 0 && std::isfinite(o.fps), "builtin:torture: frame rate must be positive, got ", o.fps);
  require(o.period * o.fps >= 1 && std::isfinite(o.period), "builtin:torture: period ", o.period,
          " s must hold at least one frame at ", o.fps, " fps");
  require(o.range_fraction > 0 && o.range_fraction <= 1, "builtin:torture: range fraction must be in (0, 1], got ",
          o.range_fraction);
  const int frames = int(std::floor(o.seconds * o.fps + 1e-6)) + 1;
  require(frames <= 10'000'000, "builtin:torture: ", frames, " frames is too many");
  std::mt19937_64 rng(o.seed);
  MotionClip clip;
  clip.name = "builtin:torture";
  clip.fps = o.fps;
  clip.rotations.reserve(frames);
  clip.translations.assign(frames, Vec3::Zero());
  std::vector<Eigen::Quaterniond> pose(kSmplJoints, Eigen::Quaterniond::Identity());
  int pose_index = 0;
  for (int i = 0; i < frames; ++i) {
    const int k = int(std::floor(double(i) / o.fps / o.period + 1e-9));
    while (pose_index < k) {  // next pose (a frame rate below 1/period skips none: every pose is drawn)
      ++pose_index;
      for (int j = 0; j < kSmplJoints; ++j) {
        const JointRange& r = ranges[j];
        if (!r.limited) continue;
        const Vec3 mid = 0.5 * (r.lower + r.upper), half = 0.5 * o.range_fraction * (r.upper - r.lower);
        Vec3 theta;
        do {
          for (int c = 0; c < 3; ++c) theta[c] = mid[c] + (2 * uniform01(rng) - 1) * half[c];
        } while (theta.norm() > 3.0);
        const double angle = theta.norm();
        pose[j] = angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, theta / angle)) : Eigen::Quaterniond::Identity();
      }
    }
    clip.rotations.push_back(pose);
  }
  return clip;
}

MotionClip load_stress_motion(const std::string& spec, const MotionOptions& mo, MotionReport* report) {
  if (spec != "builtin:torture") return load_motion(spec, mo, report);
  TortureOptions t;
  t.seconds = mo.builtin_seconds;
  t.fps = mo.builtin_fps;
  MotionClip clip = torture_motion(smpl_joint_ranges(), t);
  if (mo.start > 0 || mo.end >= 0) clip = trim(clip, mo.start, mo.end);
  if (mo.speed != 1) clip = change_speed(clip, mo.speed);
  if (mo.fps > 0) clip = resample(clip, mo.fps);
  if (report) {
    report->source = spec;
    report->format = "builtin";
    report->frames = report->source_frames = clip.num_frames();
    report->fps = report->source_fps = clip.fps;
    report->duration = clip.duration();
  }
  return clip;
}

}  // namespace sflsh
