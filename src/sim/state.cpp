#include "sflsh/sim/state.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sim/step_workspace.hpp"

namespace sflsh {

State::State() = default;
State::~State() = default;
State::State(const State& other) : time(other.time), bodies(other.bodies) {}
State& State::operator=(const State& other) {
  time = other.time;
  bodies = other.bodies;
  workspace_.reset();
  return *this;
}
State::State(State&&) noexcept = default;
State& State::operator=(State&&) noexcept = default;

StepWorkspace& State::workspace(const Model& model) {
  if (!workspace_ || workspace_->model != &model) workspace_ = std::make_unique<StepWorkspace>(model);
  return *workspace_;
}

State rest_state(const Model& model) {
  State s;
  for (const Model::Body& b : model.bodies()) {
    Configuration q;
    q.bones.assign(b.num_bones(), Isometry::Identity());
    q.z = VecX::Zero(b.layout.num_reduced);
    s.bodies.push_back({q, q});
  }
  return s;
}

void validate_state(const Model& model, const State& s) {
  require(s.bodies.size() == model.bodies().size(), "state has ", s.bodies.size(), " bodies, the model ",
          model.bodies().size());
  require(std::isfinite(s.time), "state time is not finite");
  for (size_t b = 0; b < s.bodies.size(); ++b) {
    const std::string& name = model.bodies()[b].name;
    for (const Configuration* c : {&s.bodies[b].q, &s.bodies[b].q_prev}) {
      const int bones = model.bodies()[b].num_bones(), K3 = model.bodies()[b].layout.num_reduced;
      require(int(c->bones.size()) == bones, "state of body '", name, "': ", c->bones.size(), " bones, expected ",
              bones);
      require(c->z.size() == K3, "state of body '", name, "': z has ", c->z.size(), " entries, expected 3K = ", K3);
      require(c->z.allFinite(), "state of body '", name, "': z is not finite");
      for (const Isometry& G : c->bones)
        require(G.matrix().allFinite(), "state of body '", name, "': a bone transform is not finite");
    }
  }
}

}  // namespace sflsh
