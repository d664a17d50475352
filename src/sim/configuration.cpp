#include "sflsh/sim/configuration.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

Configuration retract(const Configuration& q, const VecX& delta, const DofLayout& layout) {
  require(delta.size() >= layout.end(), "retract: step has ", delta.size(), " entries, expected at least ", layout.end());
  Configuration out = q;
  if (layout.bones_dynamic) {
    const bool pivots = layout.bone_pivots.rows() > 0;
    require(!pivots || layout.bone_pivots.rows() == layout.num_bones, "retract: ", layout.bone_pivots.rows(),
            " bone pivots, expected ", layout.num_bones);
    for (int i = 0; i < layout.num_bones; ++i) {
      const Vec3 w = delta.segment<3>(layout.bone_offset(i));
      const Vec3 v = delta.segment<3>(layout.bone_offset(i) + 3);
      const Mat3 E = rodrigues(w);
      out.bones[i].linear() = E * q.bones[i].linear();
      out.bones[i].translation() = E * q.bones[i].translation() + v;
      if (pivots) {
        // x' = E(x − p) + p + v + ω × p: same tangent, rotation about p (configuration.hpp).
        const Vec3 p = q.bones[i] * Vec3(layout.bone_pivots.row(i).transpose());
        out.bones[i].translation() += p - E * p + w.cross(p);
      }
    }
  }
  out.z = q.z + delta.segment(layout.z_offset(), layout.num_reduced);
  return out;
}

VecX tangent_between(const Configuration& to, const Configuration& from, const DofLayout& layout) {
  require(to.z.size() == layout.num_reduced && from.z.size() == layout.num_reduced, "tangent_between: z has ",
          to.z.size(), " and ", from.z.size(), " entries, expected ", layout.num_reduced);
  VecX delta = VecX::Zero(layout.end());
  if (layout.bones_dynamic) {
    require(int(to.bones.size()) == layout.num_bones && int(from.bones.size()) == layout.num_bones,
            "tangent_between: ", to.bones.size(), " and ", from.bones.size(), " bones, expected ", layout.num_bones);
    const bool pivots = layout.bone_pivots.rows() > 0;
    for (int i = 0; i < layout.num_bones; ++i) {
      const Mat3 E = to.bones[i].linear() * from.bones[i].linear().transpose();
      const Vec3 w = rotation_log(E);
      // retract: t' = E t + v (+ p − E p + ω × p about the pivot p).
      Vec3 v = to.bones[i].translation() - E * from.bones[i].translation();
      if (pivots) {
        const Vec3 p = from.bones[i] * Vec3(layout.bone_pivots.row(i).transpose());
        v -= p - E * p + w.cross(p);
      }
      delta.segment<3>(layout.bone_offset(i)) = w;
      delta.segment<3>(layout.bone_offset(i) + 3) = v;
    }
  }
  delta.segment(layout.z_offset(), layout.num_reduced) = to.z - from.z;
  return delta;
}

}  // namespace sflsh
