#include "sflsh/sim/simulator.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

std::vector<Isometry> identity_bones() { return std::vector<Isometry>(24, Isometry::Identity()); }

Simulator::Simulator(std::shared_ptr<const Model> model) : model_(std::move(model)) {
  require(model_ != nullptr, "Simulator: null model");
  for (const Model::Body& b : model_->bodies())
    surfaces_.push_back(b.rigid() ? PosedPoints() : PosedPoints::at_surface(*b.avatar));
  state_ = rest_state(*model_);
}

StepReport Simulator::step(const StepInputs& inputs) { return sflsh::step(*model_, state_, inputs); }

StepReport Simulator::step(const std::vector<Isometry>& target_bones, const BodyPose& target_pose) {
  require(model_->bodies().size() == 1, "Simulator::step(target_bones): the model has ", model_->bodies().size(),
          " bodies; give StepInputs for each");
  require(target_bones.size() == 24, "Simulator::step: ", target_bones.size(), " target bones, expected 24");
  StepInputs in;
  in.bodies.push_back({target_bones, target_pose});
  return step(in);
}

void Simulator::reset(const std::vector<Isometry>& bones) {
  Configuration q;
  q.bones = bones;
  q.z = VecX::Zero(avatar().num_reduced());
  reset(q, q, 0.0);
}

void Simulator::reset(const Configuration& q, const Configuration& q_previous, double time) {
  require(!state_.bodies.empty(), "Simulator::reset: the model has no body");
  State s = state_;
  s.bodies[0] = {q, q_previous};
  s.time = time;
  set_state(s);
}

void Simulator::set_state(const State& state) {
  validate_state(*model_, state);
  state_ = state;
}

const Avatar& Simulator::avatar(int body) const {
  const Model::Body& b = model_->bodies().at(body);
  require(!b.rigid(), "body '", b.name, "' is a rigid object, not an avatar");
  return *b.avatar;
}

Points Simulator::posed_surface(int body) const {
  const Configuration& q = state(body);
  const Points b = surface_pose_offsets(avatar(body), q.bones);
  return surfaces_.at(body).world(q, &b);
}

Points Simulator::soft_displacement(int body) const {
  avatar(body);  // throws for a rigid object
  return surfaces_.at(body).soft_displacement(state(body).z); }

Points Simulator::joints(int body) const { return posed_joints(avatar(body), state(body).bones); }

}  // namespace sflsh
