#include "sflsh/sim/step_cap.hpp"

#include <algorithm>

#include "sflsh/core/error.hpp"

namespace sflsh {

double handle_step_scale(const VecX& delta, const std::vector<DofLayout>& bodies, double max_z_step) {
  if (max_z_step <= 0) return 1.0;
  double m = 0;
  for (const DofLayout& layout : bodies)
    for (int k = 0; k < layout.num_reduced / 3; ++k) m = std::max(m, delta.segment<3>(layout.z_offset() + 3 * k).norm());
  return m > max_z_step ? max_z_step / m : 1.0;
}

double rotation_step_scale(const VecX& delta, const std::vector<DofLayout>& bodies, double max_rotation) {
  if (max_rotation <= 0) return 1.0;
  double m = 0;
  for (const DofLayout& layout : bodies)
    if (layout.bones_dynamic)
      for (int i = 0; i < layout.num_bones; ++i) m = std::max(m, delta.segment<3>(layout.bone_offset(i)).norm());
  return m > max_rotation ? max_rotation / m : 1.0;
}

bool rotation_cap_per_bone_applies(const VecX& delta, const std::vector<DofLayout>& bodies,
                                   const std::vector<const std::vector<int>*>& parents, double max_rotation) {
  if (max_rotation <= 0) return false;
  require(parents.size() == bodies.size(), "rotation_cap_per_bone_applies: ", parents.size(), " parent tables for ",
          bodies.size(), " bodies");
  for (size_t b = 0; b < bodies.size(); ++b) {
    const DofLayout& layout = bodies[b];
    if (!layout.bones_dynamic) continue;
    for (int i = 0; i < layout.num_bones; ++i) {
      if (!(delta.segment<3>(layout.bone_offset(i)).norm() > max_rotation)) continue;
      if (!parents[b] || int(parents[b]->size()) != layout.num_bones) return false;
      if (std::find(parents[b]->begin(), parents[b]->end(), i) != parents[b]->end()) return false;  // has a child
    }
  }
  return true;
}

int cap_bone_rotations(VecX& delta, const std::vector<Configuration>& q, const std::vector<DofLayout>& bodies,
                       double max_rotation) {
  if (max_rotation <= 0) return 0;
  require(q.size() == bodies.size(), "cap_bone_rotations: ", q.size(), " configurations for ", bodies.size(),
          " bodies");
  int capped = 0;
  for (size_t b = 0; b < bodies.size(); ++b) {
    const DofLayout& layout = bodies[b];
    if (!layout.bones_dynamic) continue;
    require(delta.size() >= layout.end(), "cap_bone_rotations: step has ", delta.size(),
            " entries, expected at least ", layout.end());
    const bool pivots = layout.bone_pivots.rows() > 0;
    for (int i = 0; i < layout.num_bones; ++i) {
      auto w = delta.segment<3>(layout.bone_offset(i));
      const double angle = w.norm();
      if (!(angle > max_rotation)) continue;
      const Vec3 w_full = w;
      w *= max_rotation / angle;
      if (pivots) {
        // retract() moves the pivot p by v + ω × p: keep that displacement.
        const Vec3 p = q[b].bones[i] * Vec3(layout.bone_pivots.row(i).transpose());
        delta.segment<3>(layout.bone_offset(i) + 3) += (w_full - Vec3(w)).cross(p);
      }
      ++capped;
    }
  }
  return capped;
}

}  // namespace sflsh
