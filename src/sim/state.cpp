#include "sflsh/sim/state.hpp"

#include <cmath>
#include <typeinfo>

#include "sflsh/core/error.hpp"
#include "sim/step_workspace.hpp"

namespace sflsh {

State::State() = default;
State::~State() = default;
State::State(const State& other) : time(other.time), bodies(other.bodies), carried_(other.carried()) {}
State& State::operator=(const State& other) {
  if (this == &other) return *this;
  time = other.time;
  bodies = other.bodies;
  carried_ = other.carried();
  workspace_.reset();
  return *this;
}
State::State(State&&) noexcept = default;
State& State::operator=(State&&) noexcept = default;

State::CarriedCaches State::carried() const {
  CarriedCaches out;
  if (workspace_) {
    out.names = workspace_->term_names;
    out.caches.resize(out.names.size());
    for (size_t g = 0; g < workspace_->groups.size(); ++g)
      for (size_t k = 0; k < workspace_->groups[g].caches.size(); ++k)
        if (const TermCache* c = workspace_->groups[g].caches[k].get())
          out.caches[size_t(workspace_->term_index[g][k])] = c->clone();
  } else {
    out.names = carried_.names;
    for (const std::unique_ptr<TermCache>& c : carried_.caches) out.caches.push_back(c ? c->clone() : nullptr);
  }
  return out;
}

std::vector<std::unique_ptr<TermCache>> State::carried_caches(std::vector<std::string>* names) const {
  CarriedCaches c = carried();
  if (names) *names = std::move(c.names);
  return std::move(c.caches);
}

void State::carry_cache(const Model& model, int term, std::unique_ptr<TermCache> cache) {
  require(term >= 0 && term < int(model.terms().size()), "State::carry_cache: term ", term, " is not one of the model's ",
          model.terms().size());
  if (workspace_) carried_ = carried(), workspace_.reset();
  if (carried_.names.size() != model.terms().size()) {
    carried_ = CarriedCaches();
    for (const Model::BoundTerm& t : model.terms()) carried_.names.push_back(t.term->name());
    carried_.caches.resize(carried_.names.size());
  }
  carried_.caches[size_t(term)] = std::move(cache);
}

StepWorkspace& State::workspace(const Model& model) {
  if (workspace_ && workspace_->model == &model) return *workspace_;
  CarriedCaches take = workspace_ ? carried() : std::move(carried_);
  carried_ = CarriedCaches();
  workspace_ = std::make_unique<StepWorkspace>(model);
  // A carried cache is taken up by the term of its place when the model has
  // as many terms and that term has the same name and cache type.
  if (take.names.size() == model.terms().size())
    for (size_t g = 0; g < workspace_->groups.size(); ++g)
      for (size_t k = 0; k < workspace_->groups[g].caches.size(); ++k) {
        const size_t i = size_t(workspace_->term_index[g][k]);
        std::unique_ptr<TermCache>& fresh = workspace_->groups[g].caches[k];
        std::unique_ptr<TermCache>& kept = take.caches[i];
        if (kept && fresh && take.names[i] == workspace_->term_names[i] && typeid(*kept) == typeid(*fresh))
          fresh = std::move(kept);
      }
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
