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

}  // namespace sflsh
