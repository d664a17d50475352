#include "sflsh/motion/load_motion.hpp"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/motion/amass.hpp"
#include "sflsh/motion/assimp_motion.hpp"
#include "sflsh/motion/builtin_motions.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/motion/clip_ops.hpp"
#include "sflsh/motion/retarget.hpp"

namespace sflsh {
namespace {

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s.empty() ? std::string("(none)") : s;
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (static_cast<unsigned char>(c) < 32) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else o += c;
  }
  return o + "\"";
}

std::string json_list(const std::vector<std::string>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_string(v[i]);
  return s + "]";
}

MotionClip retarget_file(const SkeletonMotion& sk, const MotionOptions& o, MotionReport& r) {
  const JointMap map = o.joint_map.empty() ? best_builtin_joint_map(sk.names) : read_joint_map(o.joint_map);
  RetargetOptions ro;
  ro.units = o.units;
  ro.rest_joints = o.rest_joints;
  ro.root_from_start = o.root_from_start;
  RetargetReport rr;
  MotionClip clip = retarget_to_smpl(sk, map, ro, &rr);
  r.source_joints = sk.names;
  r.joint_map = rr.map_name;
  r.mapped = rr.mapped;
  r.ignored = rr.ignored;
  r.undriven = rr.undriven;
  r.units = rr.units;
  r.metres_per_unit = rr.metres_per_unit;
  r.avatar_scale = rr.avatar_scale;
  return clip;
}

// Every format: a frame holding a NaN/Inf rotation or translation is one
// error naming the frame and the joint (a NaN frame must not reach a run).
void require_finite_frames(const MotionClip& clip) {
  for (int f = 0; f < clip.num_frames(); ++f) {
    const double t = f / clip.fps;
    require(clip.translations[f].allFinite(), clip.name, ": frame ", f, " (t = ", t,
            " s): the root translation is not finite; motions with non-finite frames are rejected");
    for (size_t j = 0; j < clip.rotations[f].size(); ++j)
      require(clip.rotations[f][j].coeffs().allFinite(), clip.name, ": frame ", f, " (t = ", t, " s): joint ",
              j < kSmplJointNames.size() ? std::string(kSmplJointNames[j]) : std::to_string(j),
              " rotation is not finite; motions with non-finite frames are rejected");
  }
}

}  // namespace

MotionClip load_motion(const std::string& spec, const MotionOptions& o, MotionReport* report) {
  MotionReport local;
  MotionReport& r = report ? *report : local;
  r = MotionReport{};
  r.source = spec;
  require(o.speed > 0 && std::isfinite(o.speed), spec, ": --speed must be positive, got ", o.speed);
  require(o.fps >= 0 && std::isfinite(o.fps), spec, ": --fps must be positive (or 0 to keep the file's), got ", o.fps);
  require(o.start >= 0 && std::isfinite(o.start), spec, ": --start must be a time >= 0 s, got ", o.start);
  require(o.end < 0 || (std::isfinite(o.end) && o.end > o.start), spec,
          ": --end must be a time after --start (s; default: the end), got ", o.end);
  MotionClip clip;
  const std::string ext = io::lower_extension(spec);
  if (spec.rfind("builtin:", 0) == 0) {
    r.format = "builtin";
    clip = builtin_motion(spec.substr(8), o.builtin_seconds, o.builtin_fps);
    for (int j = 0; j < kSmplJoints; ++j) r.mapped.emplace_back(kSmplJointNames[j]);
  } else {
    require(std::filesystem::exists(spec), spec, ": motion file not found (expected builtin:NAME, .npz, .bvh, .fbx, .dae, .gltf/.glb)");
    if (ext == ".npz") {
      r.format = "amass";
      AmassInfo info;
      clip = read_amass(spec, o.rest_joints, &info);
      r.betas = info.betas;
      r.gender = info.gender;
      for (int j = 0; j < kSmplJoints; ++j)
        (clip.joint_driven[j] ? r.mapped : r.undriven).emplace_back(kSmplJointNames[j]);
      if (info.pose_columns > 72) r.ignored.push_back("hand/face joints (" + std::to_string(info.pose_columns / 3 - 22) + ")");
    } else if (ext == ".bvh" && !o.bvh_via_assimp) {
      r.format = "bvh";
      clip = retarget_file(skeleton_motion_from_bvh(read_bvh(spec)), o, r);
    } else {
      r.format = "assimp";
      clip = retarget_file(read_assimp_motion(spec), o, r);
    }
  }
  clip.name = spec;
  require_finite_frames(clip);
  r.source_frames = clip.num_frames();
  r.source_fps = clip.fps;
  if (o.drop_first_frame_jump && (r.format == "bvh" || r.format == "assimp")) {
    const FirstFrameJump jump = first_frame_jump(clip);
    if (jump.discontinuous) {
      clip.rotations.erase(clip.rotations.begin());
      clip.translations.erase(clip.translations.begin());
      if (o.root_from_start) {  // still relative to the (new) first frame
        const Vec3 t0 = clip.translations[0];
        for (auto& t : clip.translations) t -= t0;
      }
      r.dropped_first_frame = true;
      r.first_frame_jump = jump.angle;
      r.later_max_jump = jump.later_max;
      r.first_frame_jump_joint = kSmplJointNames[jump.joint];
    }
  }
  if (o.start > 0 || o.end >= 0) clip = trim(clip, o.start, o.end);
  if (o.speed != 1) clip = change_speed(clip, o.speed);
  if (o.fps > 0 && std::abs(o.fps - clip.fps) > 1e-9 * o.fps) clip = resample(clip, o.fps);
  validate_clip(clip);
  r.frames = clip.num_frames();
  r.fps = clip.fps;
  r.duration = clip.duration();
  return clip;
}

std::string MotionReport::describe() const {
  std::ostringstream os;
  os << std::setprecision(6);
  os << "motion: " << source << " (" << format << ")\n";
  os << "  source: " << source_frames << " frames at " << source_fps << " fps\n";
  if (dropped_first_frame)
    os << std::setprecision(3) << "  dropped the file's first frame: the body jumps " << first_frame_jump << " rad ("
       << first_frame_jump_joint << ") from it into the next frame, later frames change by at most " << later_max_jump
       << " rad (an added T-pose?)\n"
       << std::setprecision(6);
  os << "  clip:   " << frames << " frames at " << fps << " fps, " << duration << " s\n";
  if (!source_joints.empty()) {
    os << "  file joints (" << source_joints.size() << "): " << join(source_joints) << "\n";
    os << "  joint map: " << joint_map << "; units: " << units << " (" << metres_per_unit
       << " m per unit), avatar scale " << avatar_scale << "\n";
  }
  os << "  mapped (" << mapped.size() << "): " << join(mapped) << "\n";
  os << "  not mapped (" << ignored.size() << "; rotations fold into the next mapped joint): " << join(ignored) << "\n";
  os << "  SMPL joints at rest (" << undriven.size() << "): " << join(undriven) << "\n";
  if (betas.size()) {
    os << "  betas (" << betas.size() << "):";
    for (Eigen::Index i = 0; i < betas.size(); ++i) os << " " << betas[i];
    os << "\n";
  }
  if (!gender.empty()) os << "  gender: " << gender << "\n";
  return os.str();
}

std::string MotionReport::to_json() const {
  std::ostringstream os;
  os << std::setprecision(10);
  os << "{\"source\": " << json_string(source) << ", \"format\": " << json_string(format)
     << ", \"source_frames\": " << source_frames << ", \"source_fps\": " << source_fps << ", \"frames\": " << frames
     << ", \"fps\": " << fps << ", \"duration\": " << duration << ", \"source_joints\": " << json_list(source_joints)
     << ", \"joint_map\": " << json_string(joint_map) << ", \"units\": " << json_string(units)
     << ", \"metres_per_unit\": " << metres_per_unit << ", \"avatar_scale\": " << avatar_scale
     << ", \"mapped\": " << json_list(mapped) << ", \"ignored\": " << json_list(ignored)
     << ", \"undriven\": " << json_list(undriven)
     << ", \"dropped_first_frame\": " << (dropped_first_frame ? "true" : "false") << ", \"betas\": [";
  for (Eigen::Index i = 0; i < betas.size(); ++i) os << (i ? ", " : "") << betas[i];
  os << "], \"gender\": " << json_string(gender) << "}";
  return os.str();
}

}  // namespace sflsh
