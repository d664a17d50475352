#include <algorithm>

#include "sflsh/volume/shape_volume.hpp"

namespace sflsh {

std::vector<BoneCapsule> fit_bone_capsules(const Points& nodes, const Points& node_skeleton, const VecXi& skin_nodes,
                                           const VecXi& node_segment, const std::vector<BoneSegment>& segments,
                                           const std::vector<int>& parents, const Points& joints, double percentile) {
  std::vector<std::vector<double>> thick(segments.size());
  for (int i = 0; i < skin_nodes.size(); ++i) {
    const int n = skin_nodes[i];
    thick[node_segment[n]].push_back((nodes.row(n) - node_skeleton.row(n)).norm());
  }
  std::vector<BoneCapsule> out;
  for (size_t s = 0; s < segments.size(); ++s) {
    auto& t = thick[s];
    Vec3 a, b;
    segment_endpoints(segments[s], parents, joints, a, b);
    if (t.size() < 8 || (b - a).norm() < 0.01) continue;
    // Robust radius: a percentile, not the max, so a few far skin points
    // (e.g. where the segment's flesh meets the trunk) do not inflate it.
    const size_t k = std::min(t.size() - 1, size_t(percentile * (t.size() - 1) + 0.5));
    std::nth_element(t.begin(), t.begin() + k, t.end());
    out.push_back(BoneCapsule{segments[s].joint, a, b, t[k]});
  }
  return out;
}

}  // namespace sflsh
