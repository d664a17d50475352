#include "sflsh/motion/skeleton_motion.hpp"

namespace sflsh {

int SkeletonMotion::find(const std::string& name) const {
  for (int j = 0; j < num_joints(); ++j)
    if (names[j] == name) return j;
  return -1;
}

void skeleton_world_pose(const SkeletonMotion& m, int frame, std::vector<Eigen::Quaterniond>* rotations,
                         std::vector<Vec3>* positions) {
  const int n = m.num_joints();
  rotations->resize(n);
  positions->resize(n);
  std::vector<double> cum_scale(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Quaterniond& q = frame < 0 ? m.rest_rotations[j] : m.rotations[size_t(frame) * n + j];
    const Vec3& t = frame < 0 ? m.rest_translations[j] : m.translations[size_t(frame) * n + j];
    const int p = m.parents[j];
    if (p < 0) {
      (*rotations)[j] = q;
      (*positions)[j] = t;
      cum_scale[j] = m.scales[j];
    } else {
      (*rotations)[j] = ((*rotations)[p] * q).normalized();
      (*positions)[j] = (*positions)[p] + cum_scale[p] * ((*rotations)[p] * t);
      cum_scale[j] = cum_scale[p] * m.scales[j];
    }
  }
}

SkeletonMotion skeleton_motion_from_bvh(const BvhMotion& bvh) {
  SkeletonMotion m;
  m.source = bvh.path;
  m.fps = 1.0 / bvh.frame_time;
  m.num_frames = bvh.num_frames;
  std::vector<int> end_of;  // BVH joint of each End Site joint
  for (const auto& j : bvh.joints) {
    m.names.push_back(j.name);
    m.parents.push_back(j.parent);
    m.rest_translations.push_back(j.offset);
    m.animated.push_back(!j.channels.empty());
  }
  for (int j = 0; j < int(bvh.joints.size()); ++j)
    if (bvh.joints[j].has_end_site) {
      m.names.push_back(bvh.joints[j].name + "_End");
      m.parents.push_back(j);
      m.rest_translations.push_back(bvh.joints[j].end_site);
      m.animated.push_back(false);
    }
  const int n = m.num_joints(), nb = int(bvh.joints.size());
  m.rest_rotations.assign(n, Eigen::Quaterniond::Identity());
  m.scales.assign(n, 1.0);
  m.rotations.resize(size_t(m.num_frames) * n);
  m.translations.resize(size_t(m.num_frames) * n);
  for (int f = 0; f < m.num_frames; ++f)
    for (int j = 0; j < n; ++j) {
      const size_t k = size_t(f) * n + j;
      m.rotations[k] = j < nb ? bvh.local_rotation(j, f) : Eigen::Quaterniond::Identity();
      m.translations[k] = j < nb ? bvh.local_translation(j, f) : m.rest_translations[j];
    }
  return m;
}

}  // namespace sflsh
