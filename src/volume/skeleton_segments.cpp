#include "sflsh/volume/skeleton_segments.hpp"

#include <algorithm>

#include "sflsh/core/error.hpp"

namespace sflsh {

std::vector<BoneSegment> skeleton_segments(const BodyModel& model, const Points& vertices, const Points& joints) {
  const int J = model.num_joints();
  require(joints.rows() == J, "skeleton_segments: ", joints.rows(), " joints given, model has ", J);
  require(model.weights.rows() == vertices.rows(), "skeleton_segments: ", vertices.rows(),
          " vertices but weights has ", model.weights.rows(), " rows");
  std::vector<int> num_children(J, 0);
  std::vector<BoneSegment> segments;
  for (int c = 0; c < J; ++c) {
    const int p = model.parents[c];
    if (p < 0) continue;
    ++num_children[p];
    BoneSegment s;
    s.joint = p;
    s.child = c;
    segments.push_back(s);
  }
  // Dominant joint of each vertex, for the leaf extents.
  std::vector<int> dominant(vertices.rows());
  for (int v = 0; v < vertices.rows(); ++v) model.weights.row(v).maxCoeff(&dominant[v]);
  for (int j = 0; j < J; ++j) {
    const int p = model.parents[j];
    if (num_children[j] > 0 || p < 0) continue;
    const Vec3 dir_full = joints.row(j) - joints.row(p);
    const double len = dir_full.norm();
    if (len <= 0) continue;
    const Vec3 dir = dir_full / len;
    double extent = 0.0;
    for (int v = 0; v < vertices.rows(); ++v)
      if (dominant[v] == j) extent = std::max(extent, (vertices.row(v) - joints.row(j)).dot(dir));
    const double leaf_len = extent > 0 ? 0.7 * extent : 0.5 * len;
    BoneSegment s;
    s.joint = j;
    s.child = -1;
    s.extension = leaf_len / len;
    segments.push_back(s);
  }
  return segments;
}

void segment_endpoints(const BoneSegment& s, const std::vector<int>& parents, const Points& joints, Vec3& a,
                       Vec3& b) {
  a = joints.row(s.joint).transpose();
  if (s.child >= 0) {
    b = joints.row(s.child).transpose();
  } else {
    b = a + s.extension * (a - joints.row(parents[s.joint]).transpose());
  }
}

VecX segment_point_coefficients(const BoneSegment& s, const std::vector<int>& parents, int num_joints, double t) {
  VecX c = VecX::Zero(num_joints);
  c[s.joint] += 1.0 - t;
  if (s.child >= 0) {
    c[s.child] += t;
  } else {  // b = (1 + e) J_joint - e J_parent
    c[s.joint] += t * (1.0 + s.extension);
    c[parents[s.joint]] -= t * s.extension;
  }
  return c;
}

double closest_segment_parameter(const Vec3& a, const Vec3& b, const Vec3& x) {
  const Vec3 ab = b - a;
  const double l2 = ab.squaredNorm();
  if (l2 <= 0) return 0.0;
  return std::clamp((x - a).dot(ab) / l2, 0.0, 1.0);
}

}  // namespace sflsh
