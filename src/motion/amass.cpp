#include "sflsh/motion/amass.hpp"

#include <cmath>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/motion/clip_ops.hpp"
#include "sflsh/motion/retarget.hpp"

namespace sflsh {
namespace {

// A NaN/Inf in a (T, D) per-frame array: one error naming the key, the frame
// (0-based, and its time at `fps`) and the column.
void require_finite_frames(const io::NpyArray& a, const std::string& path, const std::string& key, double fps) {
  const std::int64_t cols = a.shape.size() == 2 ? a.shape[1] : 1;
  for (size_t i = 0; i < a.data.size(); ++i)
    if (!std::isfinite(a.data[i]))
      fail(path, ": key '", key, "' frame ", std::int64_t(i) / cols, " (t = ", double(std::int64_t(i) / cols) / fps,
           " s), column ", std::int64_t(i) % cols, " is ", a.data[i], "; motions with non-finite frames are rejected");
}

// AMASS world (Z up) -> SMPL/sflsh world (Y up): R_x(-90°).
Eigen::Quaterniond z_up_to_y_up() { return Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitX())); }

Vec3 rest_pelvis(const Points& rest_joints, const std::string& where) {
  const Points rest = rest_joints.rows() ? rest_joints : default_smpl_rest_joints();
  require(rest.rows() == kSmplJoints, where, ": rest joints must be 24 by 3, got ", rest.rows(), " rows");
  return rest.row(0).transpose();
}

}  // namespace

MotionClip read_amass(const std::string& path, const Points& rest_joints, AmassInfo* info) {
  std::map<std::string, std::vector<std::string>> strings;
  const auto arrays = io::read_npz(path, &strings);
  auto keys = [&] {
    std::string k;
    for (const auto& [name, a] : arrays) k += (k.empty() ? "" : ", ") + name;
    return k.empty() ? std::string("none") : k;
  };
  auto get = [&](const std::string& key) -> const io::NpyArray* {
    const auto it = arrays.find(key);
    return it == arrays.end() ? nullptr : &it->second;
  };
  AmassInfo local;
  AmassInfo& out = info ? *info : local;

  // Frame rate, under either spelling.
  const io::NpyArray* rate = nullptr;
  for (const char* k : {"mocap_framerate", "mocap_frame_rate"})
    if (!rate && (rate = get(k))) out.rate_key = k;
  require(rate != nullptr, path, ": missing key 'mocap_framerate' (or 'mocap_frame_rate'): the frame rate, a scalar; keys present: ",
          keys());
  require(rate->size() == 1, path, ": key '", out.rate_key, "' must be a scalar, has ", rate->size(), " values");
  const double fps = rate->data[0];
  require(std::isfinite(fps) && fps > 0, path, ": key '", out.rate_key, "' must be a positive frame rate, got ", fps);

  // Body rotations: T by 3K axis-angle, first 22 (or 24) joints.
  std::vector<double> aa;  // T by 3*joints
  int joints = 22;
  long long T = 0;
  if (const io::NpyArray* poses = get("poses")) {
    poses->require_shape({-1, -1}, path, "poses");
    const auto D = poses->shape[1];
    require(D % 3 == 0 && D >= 66, path, ": key 'poses' has shape (", poses->shape[0], ", ", D,
            "), expected (T, 156) (SMPL+H), (T, 72) (SMPL) or (T, 3K) with K >= 22 joints");
    require_finite_frames(*poses, path, "poses", fps);
    T = poses->shape[0];
    joints = D == 72 ? 24 : 22;
    out.layout = "poses";
    out.pose_columns = int(D);
    aa.resize(size_t(T) * 3 * joints);
    for (long long t = 0; t < T; ++t)
      for (int c = 0; c < 3 * joints; ++c) aa[size_t(t) * 3 * joints + c] = poses->data[size_t(t) * D + c];
  } else {
    const io::NpyArray* root = get("root_orient");
    const io::NpyArray* body = get("pose_body");
    require(root && body, path, ": missing key '", root ? "pose_body" : "root_orient",
            "': expected 'poses' (T, 156) or 'root_orient' (T, 3) with 'pose_body' (T, 63); keys present: ", keys());
    root->require_shape({-1, 3}, path, "root_orient");
    T = root->shape[0];
    body->require_shape({T, 63}, path, "pose_body");
    require_finite_frames(*root, path, "root_orient", fps);
    require_finite_frames(*body, path, "pose_body", fps);
    out.layout = "root_orient+pose_body";
    out.pose_columns = 66;
    aa.resize(size_t(T) * 66);
    for (long long t = 0; t < T; ++t) {
      for (int c = 0; c < 3; ++c) aa[size_t(t) * 66 + c] = root->data[size_t(t) * 3 + c];
      for (int c = 0; c < 63; ++c) aa[size_t(t) * 66 + 3 + c] = body->data[size_t(t) * 63 + c];
    }
  }
  require(T > 0, path, ": the motion has no frames (pose arrays have 0 rows)");
  const io::NpyArray* trans = get("trans");
  require(trans != nullptr, path, ": missing key 'trans': expected shape (", T, ", 3); keys present: ", keys());
  trans->require_shape({T, 3}, path, "trans");
  require_finite_frames(*trans, path, "trans", fps);

  if (const io::NpyArray* betas = get("betas")) {
    betas->require_finite(path, "betas");
    out.betas = Eigen::Map<const VecX>(betas->data.data(), Eigen::Index(betas->data.size()));
  }
  if (const auto it = strings.find("gender"); it != strings.end() && !it->second.empty()) out.gender = it->second[0];

  const Vec3 J0 = rest_pelvis(rest_joints, path);
  const Eigen::Quaterniond P = z_up_to_y_up();  // see the header

  MotionClip clip;
  clip.name = path;
  clip.fps = fps;
  clip.rotations.resize(T);
  clip.translations.resize(T);
  for (int j = joints; j < kSmplJoints; ++j) clip.joint_driven[j] = false;
  for (long long t = 0; t < T; ++t) {
    auto& q = clip.rotations[t];
    q.assign(kSmplJoints, Eigen::Quaterniond::Identity());
    for (int j = 0; j < joints; ++j)
      q[j] = quaternion_from_axis_angle(Eigen::Map<const Vec3>(&aa[size_t(t) * 3 * joints + 3 * j]));
    q[0] = (P * q[0]).normalized();
    const Vec3 tr(trans->data[size_t(t) * 3], trans->data[size_t(t) * 3 + 1], trans->data[size_t(t) * 3 + 2]);
    clip.translations[t] = P * (tr + J0) - J0;
  }
  return clip;
}

void write_amass(const std::string& path, const MotionClip& clip, const Points& rest_joints) {
  validate_clip(clip);
  const Vec3 J0 = rest_pelvis(rest_joints, path);
  const Eigen::Quaterniond Pinv = z_up_to_y_up().conjugate();
  MotionClip z_up = clip;
  for (int f = 0; f < clip.num_frames(); ++f) {
    z_up.rotations[f][0] = (Pinv * clip.rotations[f][0]).normalized();
    z_up.translations[f] = Pinv * (clip.translations[f] + J0) - J0;
  }
  MatXr poses, trans;
  clip_to_smpl_params(z_up, &poses, &trans);
  std::map<std::string, io::NpyArray> arrays;
  auto put = [&](const std::string& key, std::vector<std::int64_t> shape, const double* data, size_t n) {
    io::NpyArray& a = arrays[key];
    a.shape = std::move(shape);
    a.dtype = "<f8";
    a.data.assign(data, data + n);
  };
  put("poses", {poses.rows(), poses.cols()}, poses.data(), size_t(poses.size()));
  put("trans", {trans.rows(), 3}, trans.data(), size_t(trans.size()));
  put("mocap_framerate", {}, &clip.fps, 1);
  io::write_npz(path, arrays);
}

}  // namespace sflsh
