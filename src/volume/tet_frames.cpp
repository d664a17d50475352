#include <cmath>

#include "sflsh/volume/shape_volume.hpp"

namespace sflsh {

MatXr tet_frames(const TetMesh& tet, const Points& node_skeleton, const VecXi& node_segment,
                 const std::vector<BoneSegment>& segments, const std::vector<int>& parents, const Points& joints) {
  std::vector<Vec3> dir(segments.size());
  for (size_t s = 0; s < segments.size(); ++s) {
    Vec3 a, b;
    segment_endpoints(segments[s], parents, joints, a, b);
    dir[s] = (b - a).normalized();
  }
  const int T = tet.num_elements();
  MatXr frames(T, 9);
  for (int t = 0; t < T; ++t) {
    Vec3 along = Vec3::Zero(), c = Vec3::Zero(), s = Vec3::Zero();
    for (int i = 0; i < 4; ++i) {
      const int n = tet.elements(t, i);
      along += dir[node_segment[n]];
      c += tet.nodes.row(n).transpose();
      s += node_skeleton.row(n).transpose();
    }
    along = along.norm() > 1e-9 ? along.normalized() : Vec3::UnitY();
    Vec3 through = (c - s) - (c - s).dot(along) * along;
    if (through.norm() < 1e-9) {  // on the bone axis: any perpendicular
      through = along.cross(std::abs(along.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY());
    }
    through.normalize();
    const Vec3 around = along.cross(through);
    frames.row(t) << along.transpose(), through.transpose(), around.transpose();
  }
  return frames;
}

}  // namespace sflsh
