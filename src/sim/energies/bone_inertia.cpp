#include "sflsh/sim/energies/bone_inertia.hpp"

#include <cmath>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {

const std::vector<double>& smpl_segment_mass_fractions() {
  // Winter (2009) table 4.1, fractions of total body mass:
  //   trunk 0.497 = pelvis 0.142 + abdomen 0.139 + thorax 0.216,
  //   thigh 0.100, leg 0.0465, foot 0.0145, head+neck 0.081,
  //   upper arm 0.028, forearm 0.016, hand 0.006.
  // SMPL split: thorax -> spine2 0.108, spine3 0.088, collars 2 x 0.010;
  // foot -> ankle 0.011 + toes 0.0035; head+neck -> neck 0.020 + head 0.061;
  // hand -> wrist 0.004 + fingers 0.002.
  static const std::vector<double> f = {
      0.142,  // pelvis
      0.100,  0.100,   // hips (thighs)
      0.139,           // spine1 (abdomen)
      0.0465, 0.0465,  // knees (legs)
      0.108,           // spine2
      0.011,  0.011,   // ankles (feet)
      0.088,           // spine3
      0.0035, 0.0035,  // feet (toes)
      0.020,           // neck
      0.010,  0.010,   // collars
      0.061,           // head
      0.028,  0.028,   // shoulders (upper arms)
      0.016,  0.016,   // elbows (forearms)
      0.004,  0.004,   // wrists (hands)
      0.002,  0.002};  // hands (fingers)
  return f;
}

namespace {

/// Thin solid rod from a to b: mass, midpoint and inertia about the midpoint.
struct Rod {
  double mass;
  Vec3 mid;
  Mat3 inertia;
};

Rod make_rod(const Vec3& a, const Vec3& b, double mass) {
  const Vec3 d = b - a;
  const double L = d.norm();
  const double r = 0.05 * L + 0.01;  // m: bones are thin; keeps twist inertia > 0
  const Vec3 u = L > 1e-12 ? Vec3(d / L) : Vec3::UnitY();
  const Mat3 uu = u * u.transpose();
  // Solid cylinder: ½ m r² about its axis, m(3r² + L²)/12 across it.
  return {mass, 0.5 * (a + b), 0.5 * mass * r * r * uu + mass * (3 * r * r + L * L) / 12.0 * (Mat3::Identity() - uu)};
}

}  // namespace

std::vector<BoneBody> bone_bodies(const Avatar& avatar, double total_mass) {
  const int J = int(avatar.parents.size());
  require(J == kSmplJoints && avatar.joints_rest.rows() == J, "bone_bodies: avatar skeleton has ", J,
          " parents and ", avatar.joints_rest.rows(), " rest joints, expected ", kSmplJoints);
  require(total_mass > 0 && std::isfinite(total_mass), "bone_bodies: total mass must be positive, got ", total_mass);
  const std::vector<double>& frac = smpl_segment_mass_fractions();
  std::vector<std::vector<int>> children(J);
  for (int j = 1; j < J; ++j) children[avatar.parents[j]].push_back(j);
  auto joint = [&](int j) { return Vec3(avatar.joints_rest.row(j).transpose()); };

  std::vector<BoneBody> bodies(J);
  for (int j = 0; j < J; ++j) {
    const double m = frac[j] * total_mass;
    std::vector<Rod> rods;
    if (!children[j].empty()) {
      for (int c : children[j]) rods.push_back(make_rod(joint(j), joint(c), m / double(children[j].size())));
    } else {
      const int p = avatar.parents[j];
      require(p >= 0, "bone_bodies: joint ", j, " has neither parent nor children");
      rods.push_back(make_rod(joint(j), joint(j) + 0.5 * (joint(j) - joint(p)), m));
    }
    BoneBody& b = bodies[j];
    b.mass = m;
    for (const Rod& r : rods) b.com_rest += r.mass / m * r.mid;
    for (const Rod& r : rods) {
      const Vec3 s = r.mid - b.com_rest;  // parallel-axis theorem
      b.inertia_rest += r.inertia + r.mass * (s.squaredNorm() * Mat3::Identity() - s * s.transpose());
    }
  }
  return bodies;
}

double total_mass(const std::vector<BoneBody>& bodies) {
  double m = 0;
  for (const BoneBody& b : bodies) m += b.mass;
  return m;
}

BoneInertia::BoneInertia(std::vector<BoneBody> bodies) : bodies_(std::move(bodies)) {
  for (std::size_t i = 0; i < bodies_.size(); ++i)
    require(bodies_[i].mass > 0 && bodies_[i].inertia_rest.allFinite(), "BoneInertia: bone ", i,
            " needs a positive mass, got ", bodies_[i].mass);
}

namespace {

/// Predictions of the current step.
struct BoneInertiaCache : TermCache {
  double h = 0.0;  ///< time step of the prediction (0 = begin_step not called)
  std::vector<Vec3> com_pred;
  std::vector<Mat3> rot_pred;
  std::vector<Mat3> inertia_world;  ///< R*_i I_i,rest R*_iᵀ
};

}  // namespace

std::unique_ptr<TermCache> BoneInertia::make_cache() const { return std::make_unique<BoneInertiaCache>(); }

void BoneInertia::begin_step(const StepContext& ctx) const {
  auto* cache = dynamic_cast<BoneInertiaCache*>(ctx.cache);
  require(cache != nullptr, "BoneInertia::begin_step: the context carries no bone inertia cache (see begin_term_step)");
  const std::size_t n = bodies_.size();
  require(ctx.h > 0, "BoneInertia: time step must be positive, got ", ctx.h);
  require(ctx.q_prev.bones.size() == n, "BoneInertia: q_prev has ", ctx.q_prev.bones.size(), " bones, expected ", n);
  const bool at_rest = ctx.q_prev2.bones.empty();
  require(at_rest || ctx.q_prev2.bones.size() == n, "BoneInertia: q_prev2 has ", ctx.q_prev2.bones.size(),
          " bones, expected ", n, " (or none)");
  cache->h = ctx.h;
  cache->com_pred.resize(n);
  cache->rot_pred.resize(n);
  cache->inertia_world.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Isometry& Gt = ctx.q_prev.bones[i];
    const Isometry& Gp = at_rest ? Gt : ctx.q_prev2.bones[i];
    const Vec3& c = bodies_[i].com_rest;
    cache->com_pred[i] = 2.0 * (Gt * c) - Gp * c;
    cache->rot_pred[i] = Gt.linear() * Gp.linear().transpose() * Gt.linear();
    cache->inertia_world[i] = cache->rot_pred[i] * bodies_[i].inertia_rest * cache->rot_pred[i].transpose();
  }
}

void BoneInertia::residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const {
  const auto* cache = dynamic_cast<const BoneInertiaCache*>(ctx.cache);
  require(cache != nullptr && cache->h > 0, "BoneInertia: evaluate called before begin_step");
  require(q.bones.size() == bodies_.size(), "BoneInertia: configuration has ", q.bones.size(), " bones, expected ",
          bodies_.size());
  const double inv_h2 = 1.0 / (cache->h * cache->h);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    BoneResidual lin;
    const Vec3 c = q.bones[i] * bodies_[i].com_rest;
    lin.r = c - cache->com_pred[i];
    lin.W = bodies_[i].mass * inv_h2 * Mat3::Identity();
    lin.bones[0] = int(i);
    lin.J[0] = point_jacobian(c);
    out.push_back(lin);
    out.push_back(rotation_residual(q, int(i), cache->rot_pred[i].transpose(), -1, inv_h2 * cache->inertia_world[i]));
  }
}

}  // namespace sflsh
