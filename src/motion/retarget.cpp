#include "sflsh/motion/retarget.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/input_file.hpp"

namespace sflsh {
namespace {

using Quat = Eigen::Quaterniond;

struct NamedMap {
  const char* name;
  std::vector<std::pair<std::string, std::string>> pairs;  // source -> SMPL name
};

const std::vector<NamedMap>& builtin_maps() {
  static const std::vector<NamedMap> maps = {
      {"cmu",
       {{"Hips", "pelvis"},          {"LeftUpLeg", "left_hip"},       {"RightUpLeg", "right_hip"},
        {"LowerBack", "spine1"},     {"LeftLeg", "left_knee"},        {"RightLeg", "right_knee"},
        {"Spine", "spine2"},         {"LeftFoot", "left_ankle"},      {"RightFoot", "right_ankle"},
        {"Spine1", "spine3"},        {"LeftToeBase", "left_foot"},    {"RightToeBase", "right_foot"},
        {"Neck", "neck"},            {"LeftShoulder", "left_collar"}, {"RightShoulder", "right_collar"},
        {"Head", "head"},            {"LeftArm", "left_shoulder"},    {"RightArm", "right_shoulder"},
        {"LeftForeArm", "left_elbow"}, {"RightForeArm", "right_elbow"}, {"LeftHand", "left_wrist"},
        {"RightHand", "right_wrist"}}},  // finger joints are noisy in CMU (up to 170°): hands stay at rest
      {"mixamo",
       {{"Hips", "pelvis"},          {"LeftUpLeg", "left_hip"},       {"RightUpLeg", "right_hip"},
        {"Spine", "spine1"},         {"LeftLeg", "left_knee"},        {"RightLeg", "right_knee"},
        {"Spine1", "spine2"},        {"LeftFoot", "left_ankle"},      {"RightFoot", "right_ankle"},
        {"Spine2", "spine3"},        {"LeftToeBase", "left_foot"},    {"RightToeBase", "right_foot"},
        {"Neck", "neck"},            {"LeftShoulder", "left_collar"}, {"RightShoulder", "right_collar"},
        {"Head", "head"},            {"LeftArm", "left_shoulder"},    {"RightArm", "right_shoulder"},
        {"LeftForeArm", "left_elbow"}, {"RightForeArm", "right_elbow"}, {"LeftHand", "left_wrist"},
        {"RightHand", "right_wrist"}, {"LeftHandMiddle1", "left_hand"}, {"RightHandMiddle1", "right_hand"}}},
  };
  return maps;
}

// Name without a namespace prefix ("mixamorig:Hips" -> "Hips").
std::string_view bare(std::string_view s) {
  const size_t p = s.rfind(':');
  return p == std::string_view::npos ? s : s.substr(p + 1);
}

// Index of the source joint called `name` (exact, else without prefixes).
int find_joint(const SkeletonMotion& m, const std::string& name) {
  if (const int j = m.find(name); j >= 0) return j;
  for (int j = 0; j < m.num_joints(); ++j)
    if (bare(m.names[j]) == bare(name)) return j;
  return -1;
}

// The child whose bone direction C_j aligns, for the limb joints only (hips,
// knees, collars, shoulders, elbows, wrists); -1 elsewhere (see the header).
int aligned_child(int j) {
  switch (j) {
    case 1: case 2: return j + 3;            // hip -> knee
    case 4: case 5: return j + 3;            // knee -> ankle
    case 13: case 14: return j + 3;          // collar -> shoulder
    case 16: case 17: return j + 2;          // shoulder -> elbow
    case 18: case 19: return j + 2;          // elbow -> wrist
    case 20: case 21: return j + 2;          // wrist -> hand
    default: return -1;
  }
}

bool is_ancestor(const SkeletonMotion& m, int a, int b) {  // a is a strict ancestor of b
  for (int p = m.parents[b]; p >= 0; p = m.parents[p])
    if (p == a) return true;
  return false;
}

// Sum over both legs of hip-knee-ankle bone lengths, or 0 when not all mapped.
double leg_length(const std::vector<Vec3>& pos, const std::vector<int>& joint_of) {
  double L = 0;
  for (const auto& [hip, knee, ankle] : {std::array<int, 3>{1, 4, 7}, std::array<int, 3>{2, 5, 8}}) {
    if (joint_of[hip] < 0 || joint_of[knee] < 0 || joint_of[ankle] < 0) return 0;
    L += (pos[joint_of[knee]] - pos[joint_of[hip]]).norm() + (pos[joint_of[ankle]] - pos[joint_of[knee]]).norm();
  }
  return L;
}

double height_span(const std::vector<Vec3>& pos) {
  double lo = 1e300, hi = -1e300;
  for (const auto& p : pos) {
    lo = std::min(lo, p.y());
    hi = std::max(hi, p.y());
  }
  return pos.empty() ? 0 : hi - lo;
}

}  // namespace

std::vector<std::string> builtin_joint_map_names() {
  std::vector<std::string> n;
  for (const auto& m : builtin_maps()) n.push_back(m.name);
  return n;
}

JointMap builtin_joint_map(const std::string& name) {
  std::string known;
  for (const auto& m : builtin_maps()) {
    if (m.name == name) {
      JointMap map{name, {}};
      for (const auto& [src, smpl] : m.pairs) map.entries.emplace_back(src, smpl_joint_index(smpl));
      return map;
    }
    known += (known.empty() ? "" : ", ") + std::string(m.name);
  }
  fail("unknown built-in joint map '", name, "' (known: ", known, ")");
}

JointMap read_joint_map(const std::string& path) {
  io::require_input_file(path, "joint map");
  std::ifstream in(path);
  require(bool(in), path, ": cannot open joint map file");
  JointMap map{path, {}};
  std::set<std::string> sources;
  std::set<int> targets;
  std::string line;
  for (int ln = 1; std::getline(in, line); ++ln) {
    if (const size_t h = line.find('#'); h != std::string::npos) line.resize(h);
    std::istringstream ls(line);
    std::string src, smpl, extra;
    if (!(ls >> src)) continue;
    require(bool(ls >> smpl), path, ":", ln, ": expected 'source_joint smpl_joint', found only '", src, "'");
    require(!(ls >> extra), path, ":", ln, ": expected two names, found a third ('", extra, "')");
    int j = -1;
    for (int k = 0; k < kSmplJoints; ++k)
      if (kSmplJointNames[k] == smpl) j = k;
    if (j < 0) {
      std::string all;
      for (auto n : kSmplJointNames) all += (all.empty() ? "" : " ") + std::string(n);
      fail(path, ":", ln, ": unknown SMPL joint '", smpl, "' (expected one of: ", all, ")");
    }
    require(sources.insert(src).second, path, ":", ln, ": source joint '", src, "' is mapped twice");
    require(targets.insert(j).second, path, ":", ln, ": SMPL joint '", smpl, "' is the target of two joints");
    map.entries.emplace_back(src, j);
  }
  require(!map.entries.empty(), path, ": joint map holds no 'source_joint smpl_joint' lines");
  return map;
}

JointMap best_builtin_joint_map(const std::vector<std::string>& joint_names) {
  std::string best;
  int best_hits = -1;
  for (const auto& m : builtin_maps()) {
    int hits = 0;
    for (const auto& [src, smpl] : m.pairs)
      for (const auto& n : joint_names)
        if (bare(n) == src) {
          ++hits;
          break;
        }
    if (hits > best_hits) {
      best_hits = hits;
      best = m.name;
    }
  }
  return builtin_joint_map(best);
}

Points default_smpl_rest_joints() {
  // SMPL neutral model, zero betas (J_regressor · v_template), rounded to 0.1 mm.
  static const double J[24][3] = {
      {-0.0018, -0.2233, 0.0282},  {0.0695, -0.3141, 0.0239},  {-0.0677, -0.3147, 0.0219},
      {-0.0025, -0.1102, 0.0015},  {0.1043, -0.6757, 0.0166},  {-0.1056, -0.6798, 0.0134},
      {0.0054, 0.0197, 0.0013},    {0.0880, -1.0824, -0.0270}, {-0.0920, -1.0874, -0.0282},
      {0.0017, 0.0736, 0.0283},    {0.1180, -1.1473, 0.0928},  {-0.1157, -1.1432, 0.0968},
      {-0.0068, 0.2868, -0.0159},  {0.0823, 0.1928, -0.0095},  {-0.0842, 0.1887, -0.0104},
      {0.0116, 0.3549, 0.0453},    {0.1651, 0.2352, -0.0146},  {-0.1554, 0.2340, -0.0185},
      {0.4185, 0.2233, -0.0389},   {-0.4232, 0.2199, -0.0388}, {0.6620, 0.2276, -0.0402},
      {-0.6576, 0.2261, -0.0451},  {0.7509, 0.2222, -0.0462},  {-0.7470, 0.2212, -0.0524}};
  Points p(24, 3);
  for (int j = 0; j < 24; ++j) p.row(j) << J[j][0], J[j][1], J[j][2];
  return p;
}

double metres_per_unit(const std::string& units) {
  if (units == "m") return 1.0;
  if (units == "cm") return 0.01;
  if (units == "mm") return 0.001;
  if (units == "inch") return 0.0254;
  if (units == "cmu") return 0.0254 / 0.45;
  fail("unknown length unit '", units, "' (expected auto, m, cm, mm, inch or cmu)");
}

namespace {

/// SMPL joint -> source joint of `m` (−1: unmapped) by the joint map; the
/// pelvis must be mapped.
std::vector<int> source_joints(const SkeletonMotion& m, const JointMap& map) {
  const int nj = m.num_joints();
  std::vector<int> joint_of(kSmplJoints, -1);
  for (const auto& [name, j] : map.entries) {
    const int b = find_joint(m, name);
    if (b >= 0 && joint_of[j] < 0) joint_of[j] = b;
  }
  if (joint_of[0] < 0) {
    std::string names, expected;
    for (int j = 0; j < std::min(nj, 40); ++j) names += (names.empty() ? "" : ", ") + m.names[j];
    for (const auto& [name, j] : map.entries)
      if (j == 0) expected = name;
    fail(m.source, ": unmapped skeleton: no joint maps to SMPL 'pelvis' (joint map '", map.name, "' expects '",
         expected, "'); the file's joints are: ", names, nj > 40 ? ", ..." : "",
         ". Pass a joint map (--joint-map FILE with 'file_joint smpl_joint' lines)");
  }
  return joint_of;
}

/// Nearest mapped SMPL ancestor of each joint (its source joint must be an
/// ancestor of ours, else the map contradicts the file's tree).
std::vector<int> mapped_parents(const SkeletonMotion& m, const JointMap& map, const std::vector<int>& joint_of) {
  std::vector<int> mapped_parent(kSmplJoints, -1);
  for (int j = 1; j < kSmplJoints; ++j) {
    int a = kSmplParents[j];
    while (a > 0 && joint_of[a] < 0) a = kSmplParents[a];
    mapped_parent[j] = a;
    if (joint_of[j] >= 0)
      require(is_ancestor(m, joint_of[a], joint_of[j]), m.source, ": joint map '", map.name, "': '",
              m.names[joint_of[j]], "' (SMPL ", kSmplJointNames[j], ") is not below '", m.names[joint_of[a]],
              "' (SMPL ", kSmplJointNames[a], ") in the file's hierarchy");
  }
  return mapped_parent;
}

/// The length unit of the source: `requested`, or with "auto" the one that makes
/// its size (file units) closest to the avatar's (m).
std::string source_units(const std::string& requested, double size_src, double size_smpl) {
  std::string units = requested;
  if (units == "auto") {
    double best = 1e300;
    for (const char* u : {"m", "cm", "mm", "inch", "cmu"}) {
      const double err = std::abs(std::log(size_src * metres_per_unit(u) / size_smpl));
      if (err < best) {
        best = err;
        units = u;
      }
    }
  }
  return units;
}

/// Rest alignment C_j (see header): per SMPL joint, the rotation of its rest
/// bone onto the source's (through zero-length source bones), else its mapped parent's.
std::vector<Quat> rest_alignment(const SkeletonMotion& m, const std::vector<int>& joint_of,
                                 const std::vector<int>& mapped_parent, const std::vector<Vec3>& rest_pos,
                                 const std::vector<Vec3>& smpl_rest, double size_src) {
  const int nj = m.num_joints();
  std::vector<std::vector<int>> children(nj);
  for (int j = 0; j < nj; ++j)
    if (m.parents[j] >= 0) children[m.parents[j]].push_back(j);
  const double eps = 1e-6 * size_src;
  std::vector<Quat> C(kSmplJoints, Quat::Identity());
  for (int j = 1; j < kSmplJoints; ++j) {
    C[j] = C[mapped_parent[j]];
    const int c = aligned_child(j);
    if (joint_of[j] < 0 || c < 0 || joint_of[c] < 0) continue;
    const int b = joint_of[j];
    int d_joint = joint_of[c];
    // Zero-length bones (CMU's hand -> finger base): follow first children.
    for (int guard = 0; (rest_pos[d_joint] - rest_pos[b]).norm() <= eps && !children[d_joint].empty() && guard < nj;
         ++guard)
      d_joint = children[d_joint].front();
    const Vec3 d = rest_pos[d_joint] - rest_pos[b];
    const Vec3 e = smpl_rest[c] - smpl_rest[j];
    if (d.norm() <= eps || e.norm() <= 1e-9) continue;
    C[j] = Quat::FromTwoVectors(e, d);
  }
  return C;
}

/// What the retargeting mapped, ignored and left undriven, and its units and scale.
void report_retarget(const SkeletonMotion& m, const JointMap& map, const std::vector<int>& joint_of,
                     const std::string& units, double unit, double avatar_scale, RetargetReport* report) {
  const int nj = m.num_joints();
  report->map_name = map.name;
  report->mapped.clear();
  report->ignored.clear();
  report->undriven.clear();
  std::vector<bool> used(nj, false);
  for (int j = 0; j < kSmplJoints; ++j) {
    if (joint_of[j] >= 0) {
      used[joint_of[j]] = true;
      report->mapped.push_back(m.names[joint_of[j]] + " -> " + std::string(kSmplJointNames[j]));
    } else {
      report->undriven.emplace_back(kSmplJointNames[j]);
    }
  }
  for (int b = 0; b < nj; ++b)
    if (!used[b] && m.animated[b]) report->ignored.push_back(m.names[b]);
  report->units = units;
  report->metres_per_unit = unit;
  report->avatar_scale = avatar_scale;
}

}  // namespace

MotionClip retarget_to_smpl(const SkeletonMotion& m, const JointMap& map, const RetargetOptions& options,
                            RetargetReport* report) {
  const int nj = m.num_joints();
  require(nj > 0 && m.num_frames > 0, m.source, ": the file holds no animated skeleton");
  require(m.fps > 0 && std::isfinite(m.fps), m.source, ": frame rate must be positive, got ", m.fps);
  const Points rest = options.rest_joints.rows() ? options.rest_joints : default_smpl_rest_joints();
  require(rest.rows() == kSmplJoints && rest.allFinite(), "retargeting: rest joints must be a finite 24 by 3 array, got ",
          rest.rows(), " rows");

  // SMPL joint -> source joint; the nearest mapped SMPL ancestor of each joint.
  const std::vector<int> joint_of = source_joints(m, map);
  const std::vector<int> mapped_parent = mapped_parents(m, map, joint_of);

  std::vector<Quat> rest_rot, rot;
  std::vector<Vec3> rest_pos, pos;
  skeleton_world_pose(m, -1, &rest_rot, &rest_pos);
  std::vector<Vec3> smpl_rest(kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j) smpl_rest[j] = rest.row(j).transpose();

  // Size of the source (file units) and of the avatar (metres): leg lengths,
  // or heights when the legs are not mapped.
  std::vector<int> identity(kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j) identity[j] = j;
  double size_src = leg_length(rest_pos, joint_of), size_smpl = leg_length(smpl_rest, identity);
  if (size_src <= 0) {
    size_src = height_span(rest_pos);
    size_smpl = height_span(smpl_rest);
  }
  require(size_src > 0 && std::isfinite(size_src), m.source, ": the rest skeleton has zero size");
  const std::string units = source_units(options.units, size_src, size_smpl);
  const double unit = metres_per_unit(units);
  const double avatar_scale = size_smpl / (size_src * unit);
  const double k = unit * avatar_scale;

  // Rest alignment C_j (see header).
  const std::vector<Quat> C = rest_alignment(m, joint_of, mapped_parent, rest_pos, smpl_rest, size_src);

  MotionClip clip;
  clip.name = m.source;
  clip.fps = m.fps;
  clip.rotations.resize(m.num_frames);
  clip.translations.resize(m.num_frames);
  for (int j = 0; j < kSmplJoints; ++j) clip.joint_driven[j] = joint_of[j] >= 0;
  std::vector<Quat> S(kSmplJoints);
  for (int f = 0; f < m.num_frames; ++f) {
    skeleton_world_pose(m, f, &rot, &pos);
    auto& L = clip.rotations[f];
    L.resize(kSmplJoints);
    for (int j = 0; j < kSmplJoints; ++j) {
      const int b = joint_of[j];
      if (b >= 0)
        S[j] = (rot[b] * rest_rot[b].conjugate() * C[j]).normalized();
      else
        S[j] = S[kSmplParents[j]];  // unmapped: identity local rotation
      L[j] = j == 0 ? S[0] : (S[kSmplParents[j]].conjugate() * S[j]).normalized();
    }
    // SMPL: posed pelvis = J_pelvis + trans.
    clip.translations[f] = k * pos[joint_of[0]] - smpl_rest[0];
  }
  if (options.root_from_start) {
    const Vec3 t0 = clip.translations[0];
    for (auto& t : clip.translations) t -= t0;
  }

  if (report) report_retarget(m, map, joint_of, units, unit, avatar_scale, report);
  return clip;
}

}  // namespace sflsh
