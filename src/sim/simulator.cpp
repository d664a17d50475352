#include "sflsh/sim/simulator.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/damping.hpp"
#include "sflsh/sim/energies/gravity.hpp"
#include "sflsh/sim/energies/inertia.hpp"

namespace sflsh {

std::vector<Isometry> identity_bones() { return std::vector<Isometry>(24, Isometry::Identity()); }

Simulator::Simulator(std::shared_ptr<const Avatar> avatar, SimulatorOptions options)
    : avatar_(std::move(avatar)), options_(std::move(options)) {
  require(avatar_ != nullptr, "Simulator: null avatar");
  require(options_.h > 0, "SimulatorOptions::h = ", options_.h, " s, expected > 0");
  require(options_.damping >= 0, "SimulatorOptions::damping = ", options_.damping, " s, expected >= 0");
  const Avatar& a = *avatar_;
  if (options_.soft_tissue_terms) {
    terms_.push_back(std::make_unique<InertiaTerm>(a));
    auto elastic = std::make_unique<ElasticTerm>(a);
    elastic_ = elastic.get();
    terms_.push_back(std::move(elastic));
    if (options_.gravity.squaredNorm() > 0) terms_.push_back(std::make_unique<GravityTerm>(a));
    if (options_.damping > 0) terms_.push_back(std::make_unique<DampingTerm>(a, *elastic_, options_.damping));
  } else {
    own_elastic_ = std::make_unique<ElasticTerm>(a);
    elastic_ = own_elastic_.get();
  }
  surface_ = PosedPoints::at_surface(a);
  reset(identity_bones());
}

void Simulator::add_term(EnergyTermPtr term) {
  require(term != nullptr, "Simulator::add_term: null term");
  terms_.push_back(std::move(term));
}

void Simulator::reset(const std::vector<Isometry>& bones) {
  Configuration q;
  q.bones = bones;
  q.z = VecX::Zero(avatar_->num_reduced());
  reset(q, q, 0.0);
}

void Simulator::reset(const Configuration& q, const Configuration& q_previous, double time) {
  for (const Configuration* c : {&q, &q_previous}) {
    require(c->bones.size() == 24, "Simulator::reset: ", c->bones.size(), " bones, expected 24");
    require(c->z.size() == avatar_->num_reduced(), "Simulator::reset: z has ", c->z.size(), " entries, expected 3K = ",
            avatar_->num_reduced());
  }
  q_ = q;
  q_prev_ = q_previous;
  time_ = time;
}

DofLayout Simulator::layout() const {
  DofLayout l;
  l.num_bones = 24;
  l.bones_dynamic = options_.bones_dynamic;
  l.num_reduced = avatar_->num_reduced();
  // Each bone turns about its own joint: the Newton step's linearization then
  // keeps the stiff joint constraints closed on fast distal motion.
  if (avatar_->joints_rest.rows() == 24) l.bone_pivots = avatar_->joints_rest;
  return l;
}

StepContext Simulator::context(const std::vector<Isometry>& target_bones, const BodyPose& target_pose) const {
  StepContext ctx;
  ctx.avatar = avatar_.get();
  ctx.layout = layout();
  ctx.h = options_.h;
  ctx.gravity = options_.gravity;
  ctx.q_prev = q_;        // q at time t
  ctx.q_prev2 = q_prev_;  // q at time t − h
  ctx.target_pose = target_pose;
  ctx.target_bones = target_bones;
  return ctx;
}

Vec3 Simulator::frame_origin() const {
  // The pelvis (root joint) at time t; the root bone's origin when the avatar has no skeleton.
  const Isometry& G = q_.bones[0];
  return avatar_->joints_rest.rows() > 0 ? Vec3(G * Vec3(avatar_->joints_rest.row(0).transpose()))
                                         : Vec3(G.translation());
}

namespace {

/// Translates every bone of `bones` by `d` (world): G ← T(d) G.
void translate_bones(std::vector<Isometry>& bones, const Vec3& d) {
  for (Isometry& G : bones) G.translation() += d;
}

}  // namespace

StepReport Simulator::step(const std::vector<Isometry>& target_bones, const BodyPose& target_pose) {
  require(target_bones.size() == 24, "Simulator::step: ", target_bones.size(), " target bones, expected 24");
  // Re-centre the world on the pelvis for this step. Tangent steps rotate
  // bones about the world origin (configuration.hpp), so the linearization
  // error of one Newton step grows with the distance from it (a walk 14 m
  // away tracked ~10x worse). The physics is translation invariant: inertia
  // predictions shift with q_t, q_{t−1} (x* = 2x_t − x_{t−1} moves by the
  // same −c), tracking targets shift with the bones, and gravity's energy
  // changes by the constant M g·c, which has no gradient. Reported energies
  // are therefore those of the pelvis-centred frame.
  const Vec3 c = frame_origin();
  std::vector<Isometry> targets = target_bones;
  translate_bones(targets, -c);
  BodyPose pose = target_pose;
  pose.translation -= c;
  translate_bones(q_.bones, -c);
  translate_bones(q_prev_.bones, -c);
  const StepContext ctx = context(targets, pose);
  std::vector<EnergyTerm*> terms;
  for (auto& t : terms_) {
    t->begin_step(ctx);
    terms.push_back(t.get());
  }
  // Start Newton from q_t; in kinematic mode the bones are already final.
  Configuration q = q_;
  if (!options_.bones_dynamic) q.bones = targets;
  StepReport rep = newton_minimize(terms, ctx, q, options_.newton);
  translate_bones(q_.bones, c);
  q_prev_ = std::move(q_);
  translate_bones(q.bones, c);
  // Kinematic mode: the prescribed bones exactly, not shifted there and back.
  if (!options_.bones_dynamic) q.bones = target_bones;
  q_ = std::move(q);
  time_ += options_.h;
  rep.time = time_;
  return rep;
}

Points Simulator::posed_surface() const {
  const Points b = surface_pose_offsets(*avatar_, q_.bones);
  return surface_.world(q_, &b);
}

Points Simulator::soft_displacement() const { return surface_.soft_displacement(q_.z); }

Points Simulator::joints() const { return posed_joints(*avatar_, q_.bones); }

}  // namespace sflsh
