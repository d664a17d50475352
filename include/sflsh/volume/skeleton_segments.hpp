#pragma once
// The skeleton as a set of line segments (the "bones" of seed §2): one
// segment from each joint to each of its children, and for leaf joints (head,
// hands, feet) a segment continuing the parent direction into the body part.
// A point on a segment is a fixed linear combination of joint positions, so
// it follows the joints of any body shape.
#include <vector>

#include "sflsh/body/body_model.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh {

struct BoneSegment {
  int joint = 0;      ///< joint whose transform carries the segment (its start)
  int child = -1;     ///< end joint, or -1 for a leaf extension
  /// Leaf only: end = J[joint] + extension * (J[joint] - J[parent]).
  double extension = 0.0;
};

/// Segments of `model`'s kinematic tree for template vertices `vertices`
/// (#V by 3) and joints `joints` (#J by 3). Leaf segments get a length of
/// 0.7 x the extent (along the parent direction) of the vertices whose
/// dominant skinning joint is the leaf, so they stay inside the body part.
std::vector<BoneSegment> skeleton_segments(const BodyModel& model, const Points& vertices, const Points& joints);

/// End points of `segment` for joints `joints` (#J by 3, metres).
void segment_endpoints(const BoneSegment& segment, const std::vector<int>& parents, const Points& joints, Vec3& a,
                       Vec3& b);

/// Coefficients c (#J) such that c · joints is the point at parameter t in
/// [0,1] of the segment (0 = start, 1 = end); they sum to 1.
VecX segment_point_coefficients(const BoneSegment& segment, const std::vector<int>& parents, int num_joints,
                                double t);

/// Closest point of segment [a,b] to x: returns the parameter t in [0,1].
double closest_segment_parameter(const Vec3& a, const Vec3& b, const Vec3& x);

}  // namespace sflsh
