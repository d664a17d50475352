// A grasping tool's anchors held by the patch (contact_patch.hpp,
// PatchAnchors): the step's anchored skin vertices seed the patch, and their
// springs and dampers join Φ at the vertices' patched positions.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/point_hessian.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::add_offset_rotation_gradient;
using contact_patch_detail::local_layout;
using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;
using contact_patch_detail::patched_vertex;
using contact_patch_detail::PatchedVertex;

void ContactPatchTerm::collect_anchors(const StepContext& ctx, TermCache& cache, std::vector<int>& seeds,
                                       std::vector<double>& seed_phi) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  c.anchor_vertices.clear(), c.anchor_target.clear(), c.anchor_a_t.clear(), c.anchor_x_t.clear();
  if (!ctx.anchors) return;
  const Avatar& a = *avatar_;
  const Configuration& qt = ctx.bound.empty() ? ctx.q_prev : *ctx.bound[0].q_prev;
  if (dynamic_)
    require(ctx.bound.size() == 2 && ctx.bound[1].q_prev != nullptr, name(),
            ": a dynamic tool's anchors are bound to the body and the tool");
  // By increasing vertex, one anchor per vertex (the last given), as AnchorTerm.
  const std::vector<AnchorPoint>& given = *ctx.anchors;
  std::vector<int> order(given.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return given[size_t(i)].point < given[size_t(j)].point; });
  for (size_t k = 0; k < order.size(); ++k) {
    const AnchorPoint& ap = given[size_t(order[k])];
    if (k + 1 < order.size() && given[size_t(order[k + 1])].point == ap.point) continue;
    const int v = ap.point;
    require(v >= 0 && v < vertices_.size(), name(), ": anchored point ", v, " out of range (", vertices_.size(),
            " skin vertices)");
    require(ap.position.allFinite() && ap.velocity.allFinite(), name(), ": anchored point ", v, " is not finite");
    // Kinematic tool: its point at t + h; dynamic: at t, kept as the offset in the tool's body frame.
    const Vec3 position = ap.position - ctx.frame_origin;  // the step frame
    const Vec3 target = dynamic_ ? Vec3(ctx.bound[1].q_prev->bones[0].inverse() * position) : position;
    // The vertex at t with the patch's world offset at t (its tet's nodes' d_t).
    Vec3 x = vertices_.world_point(v, qt);
    const int t = a.surface_tet[v];
    for (int n = 0; n < 4; ++n) {
      const auto h = c.history.find(a.tet.elements(t, n));
      if (h != c.history.end()) x += a.surface_bary(v, n) * h->second.d_t;
    }
    c.anchor_vertices.push_back(v);
    c.anchor_target.push_back(target);
    c.anchor_a_t.push_back(dynamic_ ? position : Vec3(position - ctx.h * ap.velocity));
    c.anchor_x_t.push_back(x);
    seeds.push_back(v);
    seed_phi.push_back(-std::max((x - c.anchor_a_t.back()).norm(), 1e-9));
  }
}

double ContactPatchTerm::add_patch_anchors(const StepContext& ctx, const Configuration& q, const VecX& du,
                                           const EvaluationMode& mode, Evaluation& out) const {
  const PatchCache& c = patch_cache(ctx, name());
  const size_t n = c.anchor_vertices.size();
  if (n == 0) return 0.0;
  const bool q_derivatives = mode.q_derivatives, p_derivatives = mode.p_derivatives || mode.q_derivatives;
  const bool q_hessian = q_derivatives && mode.q_hessian;
  const Avatar& a = *avatar_;
  const DofLayout& L = local_layout(ctx);
  const double k = anchors_->options.hardness, kd = anchors_->options.damping / ctx.h, kappa = k + kd;
  const int ob = object_offset(ctx);  // a dynamic tool's 6 DoFs in the term's system, or −1
  out.anchor_forces = VecX::Zero(3 * long(n));
  MatRef Hqq(out.Hqq);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  double E = 0;
  for (size_t i = 0; i < n; ++i) {
    const int v = c.anchor_vertices[i];
    const PatchedVertex pv = patched_vertex(a, vertices_, c, v, q, du);
    const Vec3 tool = ob >= 0 ? Vec3(ctx.bound[1].q->bones[0] * c.anchor_target[i]) : c.anchor_target[i];
    const Vec3 r = pv.x - tool;
    const Vec3 d = (pv.x - c.anchor_x_t[i]) - (tool - c.anchor_a_t[i]);
    E += 0.5 * k * r.squaredNorm() + 0.5 * kd * d.squaredNorm();
    const Vec3 g = k * r + kd * d;  // ∂E/∂x
    out.anchor_forces.segment<3>(3 * long(i)) = -g;
    out.force -= g;
    out.max_stretch = std::max(out.max_stretch, r.norm());
    if (!p_derivatives) continue;
    // Patch DoFs: ∂x/∂δu_c = b_c A (exact: the springs are quadratic in δu).
    for (const auto& [pi, bi] : pv.couple) {
      if (pi < 0 || bi == 0.0) continue;
      out.gp.segment<3>(3 * pi) += bi * pv.A.transpose() * g;
      if (out.has_Hpp)
        for (const auto& [pj, bj] : pv.couple)
          if (pj >= 0 && bj != 0.0) out.Hpp.block<3, 3>(3 * pi, 3 * pj) += kappa * bi * bj * pv.A.transpose() * pv.A;
    }
    if (!q_derivatives) continue;
    add_offset_rotation_gradient(a.surface_weights.row(v), q.bones, pv.offset, g, L, out.gq);
    vertices_.local_jacobian(v, q, L, J, cols);
    const VecX gq = J.transpose() * g;
    for (size_t e = 0; e < cols.size(); ++e) out.gq[cols[e]] += gq[long(e)];
    // A dynamic tool: ∂a/∂(ω, v) = [−[a]×, I] = J_a, its rows get −J_aᵀ g (equal and opposite).
    Eigen::Matrix<double, 3, 6> Ja;
    if (ob >= 0) {
      Ja << -hat(tool), Mat3::Identity();
      out.gq.segment<6>(ob) -= Ja.transpose() * g;
    }
    if (!q_hessian) continue;
    add_point_hessian(vertices_, v, q, L, kappa, Hqq);
    const Eigen::Matrix<double, Eigen::Dynamic, 3> JA = kappa * (J.transpose() * pv.A);
    for (const auto& [pj, bj] : pv.couple) {
      if (pj < 0 || bj == 0.0) continue;
      for (size_t e = 0; e < cols.size(); ++e) out.Hqp.block<1, 3>(cols[e], 3 * pj) += bj * JA.row(long(e));
      if (ob >= 0) out.Hqp.block<6, 3>(ob, 3 * pj) -= kappa * bj * (Ja.transpose() * pv.A);
    }
    if (ob < 0) continue;
    out.Hqq.block<6, 6>(ob, ob) += kappa * Ja.transpose() * Ja;
    const Eigen::Matrix<double, 6, Eigen::Dynamic> Hob = -kappa * (Ja.transpose() * J);
    for (size_t e = 0; e < cols.size(); ++e) {
      out.Hqq.block<6, 1>(ob, cols[e]) += Hob.col(long(e));
      out.Hqq.block<1, 6>(cols[e], ob) += Hob.col(long(e)).transpose();
    }
  }
  return E;
}

}  // namespace sflsh
