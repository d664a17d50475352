// The full-FEM reference's anchors (full_fem.hpp, FullFemAnchor): skin points
// tied to tool points by spring–dampers, as the reduced model's anchor term.
#include <cmath>
#include <string>

#include "reference/full_fem_cholmod.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/reference/full_fem.hpp"

namespace sflsh {

void FullFem::set_anchors(std::vector<FullFemAnchor> anchors) {
  const int V = int(avatar_->surface_rest.rows());
  for (size_t i = 0; i < anchors.size(); ++i) {
    const FullFemAnchor& p = anchors[i];
    const std::string what = "FullFem anchor " + std::to_string(i);
    require(p.vertex >= 0 && p.vertex < V, what, ": skin vertex ", p.vertex, " out of range [0, ", V, ")");
    require(p.target.allFinite() && p.target_prev.allFinite(), what, ": target not finite");
    require(std::isfinite(p.hardness) && p.hardness > 0, what, ": hardness ", p.hardness, " N/m, expected > 0");
    require(std::isfinite(p.damping) && p.damping >= 0, what, ": damping ", p.damping, " N·s/m, expected >= 0");
  }
  anchors_ = std::move(anchors);
}

double FullFem::evaluate_anchors(const Points& u, VecX* grad, bool hessian, std::vector<Vec3>* forces) const {
  if (forces) forces->clear();
  if (anchors_.empty()) return 0;
  require(anchor_start_.size() == anchors_.size(), "FullFem: anchors set after the step started");
  const Avatar& a = *avatar_;
  const double c_h = 1.0 / options_.h;
  double* values = chol_->H.valuePtr();
  double E = 0;
  for (size_t i = 0; i < anchors_.size(); ++i) {
    const FullFemAnchor& p = anchors_[i];
    const Vec3 x = skin_point(p.vertex, u);
    const Vec3 stretch = x - p.target;
    const Vec3 slip = (x - anchor_start_[i]) - (p.target - p.target_prev);
    E += 0.5 * p.hardness * stretch.squaredNorm() + 0.5 * p.damping * c_h * slip.squaredNorm();
    const Vec3 fx = p.hardness * stretch + p.damping * c_h * slip;  // ∂E/∂x
    if (forces) forces->push_back(-fx);
    if (!grad && !hessian) continue;
    // ∂x/∂u_{n_c} = b_c A_v over the nodes of the vertex's tet.
    const int t = a.surface_tet[p.vertex];
    const Mat3& A = skin_A_[size_t(p.vertex)];
    if (grad)
      for (int c = 0; c < 4; ++c) {
        const int f = node_free_[a.tet.elements(t, c)];
        if (f >= 0) grad->segment<3>(3 * f) += a.surface_bary(p.vertex, c) * (A.transpose() * fx);
      }
    if (!hessian) continue;
    const Mat3 AtA = (p.hardness + p.damping * c_h) * A.transpose() * A;
    const int* slots = &tet_slot_[size_t(t) * 144];
    for (int c = 0; c < 4; ++c)
      for (int d = 0; d < 4; ++d) {
        const double bb = a.surface_bary(p.vertex, c) * a.surface_bary(p.vertex, d);
        if (bb == 0.0) continue;
        for (int i = 0; i < 3; ++i)
          for (int k = 0; k < 3; ++k) {
            const int s = slots[12 * (3 * c + i) + 3 * d + k];
            if (s >= 0) values[s] += bb * AtA(i, k);
          }
      }
  }
  return E;
}

}  // namespace sflsh
