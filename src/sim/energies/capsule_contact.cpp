#include "sflsh/sim/energies/capsule_contact.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/geometry/capsule_distance.hpp"

namespace sflsh {
namespace {

struct PairCache : TermCache {
  std::vector<int> near;  // indices into pairs_ within reach at time t
};

geometry::Capsule posed(const BoneCapsule& c, const std::vector<Isometry>& bones) {
  const Isometry& G = bones.at(c.bone);
  return {G * c.p0, G * c.p1, c.radius};
}

/// Edges between joints i and j in the tree `parents`.
int tree_distance(const std::vector<int>& parents, int i, int j) {
  std::vector<int> up_i;
  for (int k = i; k >= 0; k = parents[k]) up_i.push_back(k);
  int steps_j = 0;
  for (int k = j; k >= 0; k = parents[k], ++steps_j) {
    const auto it = std::find(up_i.begin(), up_i.end(), k);
    if (it != up_i.end()) return int(it - up_i.begin()) + steps_j;
  }
  return int(parents.size());
}

/// Bounding-sphere test: can capsules a and b be within `reach` of touching?
bool spheres_near(const geometry::Capsule& a, const geometry::Capsule& b, double reach) {
  const Vec3 ca = 0.5 * (a.p0 + a.p1), cb = 0.5 * (b.p0 + b.p1);
  const double ra = 0.5 * (a.p1 - a.p0).norm() + a.radius, rb = 0.5 * (b.p1 - b.p0).norm() + b.radius;
  return (ca - cb).norm() <= ra + rb + reach;
}

}  // namespace

CapsuleContactTerm::CapsuleContactTerm(const Avatar& a, const Avatar* b, const CapsuleContactOptions& o)
    : caps_a_(a.capsules), caps_b_(b ? b->capsules : a.capsules), self_(b == nullptr), options_(o) {
  require(o.stiffness >= 0 && std::isfinite(o.stiffness), "capsule contact: stiffness ", o.stiffness,
          " N/m, expected >= 0");
  require(!caps_a_.empty() && !caps_b_.empty(), "capsule contact: an avatar has no bone capsules (/skeleton/capsules)");
  require(o.radius_scale > 0 && o.radius_scale <= 1, "capsule contact: radius scale ", o.radius_scale,
          ", expected in (0, 1]");
  for (auto* caps : {&caps_a_, &caps_b_})
    for (BoneCapsule& c : *caps) c.radius *= o.radius_scale;
  for (int i = 0; i < int(caps_a_.size()); ++i)
    for (int j = self_ ? i + 1 : 0; j < int(caps_b_.size()); ++j) {
      if (self_) {
        if (tree_distance(a.parents, caps_a_[i].bone, caps_b_[j].bone) <= o.min_bone_separation) continue;
        const geometry::Capsule ca{caps_a_[i].p0, caps_a_[i].p1, caps_a_[i].radius};
        const geometry::Capsule cb{caps_b_[j].p0, caps_b_[j].p1, caps_b_[j].radius};
        if (geometry::capsule_distance(ca, cb).distance <= 0) continue;  // touching at rest: not contact
      }
      pairs_.emplace_back(i, j);
    }
}

std::unique_ptr<TermCache> CapsuleContactTerm::make_cache() const { return std::make_unique<PairCache>(); }

void CapsuleContactTerm::begin_step(const StepContext& ctx) const {
  auto& c = static_cast<PairCache&>(*ctx.cache);
  c.near.clear();
  require(ctx.bound.size() == (self_ ? 1u : 2u), name(), ": bound to ", ctx.bound.size(), " bodies, expected ",
          self_ ? 1 : 2);
  const BoundBody& A = ctx.bound[0];
  const BoundBody& B = ctx.bound[self_ ? 0 : 1];
  // Reach: twice the farthest any capsule end moved over the last step, plus 2 cm.
  auto motion = [](const BoundBody& b, const std::vector<BoneCapsule>& caps) {
    double m = 0;
    if (b.q_prev2 && b.q_prev2->bones.size() == b.q_prev->bones.size())
      for (const BoneCapsule& cap : caps) {
        const geometry::Capsule now = posed(cap, b.q_prev->bones), before = posed(cap, b.q_prev2->bones);
        m = std::max({m, (now.p0 - before.p0).norm(), (now.p1 - before.p1).norm()});
      }
    return m;
  };
  const double reach = 0.02 + 2 * (motion(A, caps_a_) + (self_ ? 0.0 : motion(B, caps_b_)));
  for (int k = 0; k < int(pairs_.size()); ++k) {
    const auto [i, j] = pairs_[k];
    if (spheres_near(posed(caps_a_[i], A.q_prev->bones), posed(caps_b_[j], B.q_prev->bones), reach))
      c.near.push_back(k);
  }
}

bool CapsuleContactTerm::active(const StepContext& ctx) const {
  return !static_cast<PairCache&>(*ctx.cache).near.empty();
}

double CapsuleContactTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const auto& c = static_cast<PairCache&>(*ctx.cache);
  const BoundBody& A = ctx.bound[0];
  const Configuration& qa = q;
  const Configuration& qb = self_ ? q : *ctx.bound[1].q;
  const DofLayout& La = A.layout;
  const DofLayout& Lb = ctx.bound[self_ ? 0 : 1].layout;
  const double k = options_.stiffness;
  double E = 0;
  for (int idx : c.near) {
    const auto [i, j] = pairs_[idx];
    const geometry::Capsule ca = posed(caps_a_[i], qa.bones), cb = posed(caps_b_[j], qb.bones);
    if (!spheres_near(ca, cb, 0.0)) continue;
    const geometry::CapsuleContact cc = geometry::capsule_distance(ca, cb);
    const double d = cc.distance;
    if (!(d < 0)) continue;
    E += 0.5 * k * d * d;
    const Vec3& n = cc.normal;
    // ∂d/∂ξ for each side's bone (empty when that body's bones are kinematic).
    Eigen::Matrix<double, 6, 1> ga, gb;
    ga << -cc.axes.point_a.cross(n), -n;
    gb << cc.axes.point_b.cross(n), n;
    const int oa = La.bones_dynamic ? La.bone_offset(caps_a_[i].bone) : -1;
    const int ob = Lb.bones_dynamic ? Lb.bone_offset(caps_b_[j].bone) : -1;
    if (grad) {
      if (oa >= 0) grad->segment<6>(oa) += k * d * ga;
      if (ob >= 0) grad->segment<6>(ob) += k * d * gb;
    }
    if (hess) {
      if (oa >= 0) hess->block<6, 6>(oa, oa) += k * ga * ga.transpose();
      if (ob >= 0) hess->block<6, 6>(ob, ob) += k * gb * gb.transpose();
      if (oa >= 0 && ob >= 0) {
        hess->block<6, 6>(oa, ob) += k * ga * gb.transpose();
        hess->block<6, 6>(ob, oa) += k * gb * ga.transpose();
      }
    }
  }
  return E;
}

double CapsuleContactTerm::max_overlap(const std::vector<Isometry>& bones_a,
                                       const std::vector<Isometry>& bones_b) const {
  double worst = 0;
  for (const auto& [i, j] : pairs_)
    worst = std::max(worst, -geometry::capsule_distance(posed(caps_a_[i], bones_a), posed(caps_b_[j], bones_b)).distance);
  return worst;
}

std::vector<TermQuantity> CapsuleContactTerm::report(const StepContext& ctx, const Configuration& q) const {
  const auto& c = static_cast<PairCache&>(*ctx.cache);
  const Configuration& qb = self_ ? q : *ctx.bound[1].q;
  Vec3 force = Vec3::Zero();
  int overlapping = 0;
  double worst = 0, weight = 0;
  Vec3 point = Vec3::Zero();
  for (int idx : c.near) {
    const auto [i, j] = pairs_[idx];
    const geometry::CapsuleContact cc = geometry::capsule_distance(posed(caps_a_[i], q.bones), posed(caps_b_[j], qb.bones));
    if (!(cc.distance < 0)) continue;
    force += options_.stiffness * cc.distance * cc.normal;  // −k d (−n): pushes a away from b
    ++overlapping;
    worst = std::max(worst, -cc.distance);
    // Between the two witness points, weighted by the pair's force k|d|.
    point += -cc.distance * 0.5 * (cc.witness_a + cc.witness_b);
    weight += -cc.distance;
  }
  std::vector<TermQuantity> out = {{"force", "N", force},
                                   {"overlapping_pairs", "", VecX::Constant(1, overlapping)},
                                   {"max_overlap", "m", VecX::Constant(1, worst)}};
  if (weight > 0) out.push_back({"contact_point", "m", point / weight});
  return out;
}

}  // namespace sflsh
