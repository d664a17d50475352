// Body parameters as users type them: named poses (--pose-preset) and β lists
// (--betas). Angles follow SMPL's frame: Y up, the body faces +Z, its left side
// is +X. A rotation about -X swings a leg forward (flexes the hip); about +X it
// bends the knee backward; about -Z it lowers the left arm, +Z the right;
// about -Y the left elbow flexes (forearm forward), about +Y the right one.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>

#include "sflsh/body/body_model.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

using JointAngles = std::map<std::string, Vec3>;  // SMPL joint name -> axis-angle (radians)

BodyPose from_angles(const JointAngles& angles) {
  BodyPose p;
  for (const auto& [name, aa] : angles) p.axis_angle.row(smpl_joint_index(name)) = aa.transpose();
  return p;
}

// Arms hanging at `down` degrees below the T-pose horizontal.
JointAngles arms_down(double down) {
  return {{"left_shoulder", Vec3(0, 0, -down * kDeg)}, {"right_shoulder", Vec3(0, 0, down * kDeg)}};
}

const std::map<std::string, JointAngles>& presets() {
  static const std::map<std::string, JointAngles> table = [] {
    std::map<std::string, JointAngles> t;
    t["tpose"] = {};
    t["apose"] = arms_down(45);
    // Mid-stride: left leg forward, right leg trailing with a bent knee, arms
    // relaxed at the sides with slightly bent elbows.
    JointAngles walk = arms_down(70);
    walk["left_hip"] = Vec3(-25 * kDeg, 0, 0);
    walk["left_knee"] = Vec3(10 * kDeg, 0, 0);
    walk["right_hip"] = Vec3(15 * kDeg, 0, 0);
    walk["right_knee"] = Vec3(35 * kDeg, 0, 0);
    walk["right_ankle"] = Vec3(-10 * kDeg, 0, 0);
    walk["left_elbow"] = Vec3(0, -15 * kDeg, 0);
    walk["right_elbow"] = Vec3(0, 15 * kDeg, 0);
    t["walk"] = walk;
    // Seated on a chair: thighs horizontal, shanks vertical, hands near the lap.
    JointAngles sit = arms_down(75);
    sit["left_hip"] = Vec3(-90 * kDeg, 0, 0);
    sit["right_hip"] = Vec3(-90 * kDeg, 0, 0);
    sit["left_knee"] = Vec3(90 * kDeg, 0, 0);
    sit["right_knee"] = Vec3(90 * kDeg, 0, 0);
    sit["left_elbow"] = Vec3(0, -45 * kDeg, 0);
    sit["right_elbow"] = Vec3(0, 45 * kDeg, 0);
    t["sit"] = sit;
    return t;
  }();
  return table;
}

}  // namespace

BodyPose pose_preset(const std::string& name) {
  const auto& table = presets();
  auto it = table.find(name);
  if (it == table.end()) {
    std::string known;
    for (const auto& [k, _] : table) known += (known.empty() ? "" : ", ") + k;
    fail("unknown pose preset '", name, "' (known: ", known, ")");
  }
  return from_angles(it->second);
}

VecX parse_betas(const std::string& csv) {
  std::vector<double> values;
  if (csv.find_first_not_of(" \t") == std::string::npos) return VecX();
  size_t start = 0;
  while (true) {
    const size_t end = csv.find(',', start);
    std::string token = csv.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const size_t a = token.find_first_not_of(" \t"), b = token.find_last_not_of(" \t");
    token = a == std::string::npos ? std::string() : token.substr(a, b - a + 1);
    char* stop = nullptr;
    errno = 0;
    const double v = token.empty() ? 0.0 : std::strtod(token.c_str(), &stop);
    if (token.empty() || *stop != '\0' || errno == ERANGE || !std::isfinite(v))
      fail("--betas: token ", values.size() + 1, " '", token, "' of '", csv,
           "' is not a number (expected comma-separated values like 0.5,-1,2)");
    values.push_back(v);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return Eigen::Map<VecX>(values.data(), Eigen::Index(values.size()));
}

}  // namespace sflsh
