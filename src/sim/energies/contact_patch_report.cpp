// What the patch term reports after a step, and the skin displacement its
// patches add (contact_patch.hpp).
#include <algorithm>

#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;
using contact_patch_detail::PatchHistory;

std::vector<TermQuantity> ContactPatchTerm::report(const StepContext& ctx, const Configuration& q) const {
  PatchCache& c = patch_cache(ctx, name());
  const VecX du = step_patch(ctx, q);
  // The accepted trial's evaluation when the report is at it (as after a
  // step: q and δu are the last trial's), else one of its own.
  const bool at_trial = c.has_trial && c.trial_du.size() == du.size() && c.trial_du == du &&
                        at_configuration(ctx, q, c.trial_q, c.trial_object);
  Evaluation own;
  if (!at_trial) {
    EvaluationMode mode;
    mode.p_derivatives = false;
    evaluate_patch(ctx, q, du, mode, own);
  }
  const Evaluation& ev = at_trial ? c.trial : own;
  double max_du = 0;
  VecX packed(4 * c.nodes.size());
  for (size_t i = 0; i < c.nodes.size(); ++i) {
    const int n = c.nodes[i];
    PatchHistory& h = c.history[n];
    h.du_next = du.segment<3>(3 * i);
    h.d_next = skinning_rotation_blend(avatar_->node_weights.row(n), q.bones) * h.du_next;
    max_du = std::max(max_du, h.du_next.norm());
    packed.segment<4>(4 * i) << double(n), h.du_next;
  }
  // What the next step's start takes back of its extrapolation (PatchHistory::du_back).
  if (c.linearized && !c.releasing && c.Hpp_llt.rows() == du.size()) {
    const Configuration& q_t = ctx.bound.empty() ? ctx.q_prev : *ctx.bound[0].q_prev;
    const BoundBody* o = dynamic_ ? &ctx.bound[1] : nullptr;
    const VecX back = c.linear_response(move_between(ctx, q, q_t, o ? o->q : nullptr, o ? o->q_prev : nullptr));
    for (size_t i = 0; i < c.nodes.size(); ++i) c.history[c.nodes[i]].du_back_next = back.segment<3>(3 * long(i));
  }
  std::vector<TermQuantity> out = {{"force", "N", ev.force},
          {"friction_force", "N", ev.friction_force},
          {"active_samples", "", VecX::Constant(1, ev.active)},
          {"max_penetration", "m", VecX::Constant(1, ev.depth)},
          {"contact_area", "m^2", VecX::Constant(1, ev.area)},
          {"patch_nodes", "", VecX::Constant(1, double(c.nodes.size()))},
          {"patch_radius", "m", VecX::Constant(1, c.radius)},
          {"max_patch_displacement", "m", VecX::Constant(1, max_du)},
          {"patch_displacement", "m", packed},
          {"patch_iterations", "", VecX::Constant(1, c.inner_iterations)},
          {"patch_minimizations", "", VecX::Constant(1, c.minimizations)}};
  // Where the force acts: the touching samples' mean weighted by their force.
  if (ev.point_weight > 0) out.push_back({"contact_point", "m", ev.point_sum / ev.point_weight});
  if (anchors_) {
    VecX points(long(c.anchor_vertices.size()));
    for (size_t i = 0; i < c.anchor_vertices.size(); ++i) points[long(i)] = c.anchor_vertices[i];
    out.push_back({"anchor_forces", "N", ev.anchor_forces});
    out.push_back({"anchor_points", "", points});
    out.push_back({"max_stretch", "m", VecX::Constant(1, ev.max_stretch)});
  }
  return out;
}

Points patch_surface_displacement(const Avatar& a, const StepReport& report, int body) {
  // δu per tet node (zero where no patch is; empty: no patch at all).
  std::vector<Vec3> du;
  for (const TermQuantityReport& q : report.quantities) {
    if (q.body != body || q.name != "patch_displacement") continue;
    require(q.value.size() % 4 == 0, "patch_surface_displacement: '", q.term, "' reports ", q.value.size(),
            " values, expected 4 per patch node");
    if (du.empty()) du.assign(size_t(a.tet.num_nodes()), Vec3::Zero());
    for (size_t i = 0; i < q.value.size(); i += 4) {
      const int n = int(q.value[i]);
      require(n >= 0 && n < a.tet.num_nodes(), "patch_surface_displacement: node ", n, " out of [0, ",
              a.tet.num_nodes(), ")");
      du[size_t(n)] += Vec3(q.value[i + 1], q.value[i + 2], q.value[i + 3]);
    }
  }
  Points u = Points::Zero(a.surface_rest.rows(), 3);
  if (du.empty()) return u;
  for (int v = 0; v < u.rows(); ++v)
    for (int c = 0; c < 4; ++c) u.row(v) += a.surface_bary(v, c) * du[size_t(a.tet.elements(a.surface_tet[v], c))].transpose();
  return u;
}

}  // namespace sflsh
