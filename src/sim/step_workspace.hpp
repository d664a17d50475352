#pragma once
// Internal: the scratch a State keeps for stepping one Model (per group: term
// caches, per-term contexts, shifted inputs, the Newton system). Recreated
// when the model changes. Groups have disjoint scratch, so they can be
// stepped concurrently.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/sim/model.hpp"
#include "sflsh/sim/newton_step.hpp"
#include "sflsh/sim/state.hpp"

namespace sflsh {

struct GroupWorkspace {
  std::vector<std::unique_ptr<TermCache>> caches;  ///< one per group term (null: none)
  std::vector<StepContext> contexts;               ///< one per group term, rebuilt each step
  std::vector<BodyTargets> targets;                ///< per group body, in the step frame
  std::vector<WorldFrame> frames;                   ///< by FrameId, in the step frame
  std::vector<char> frame_given;                   ///< by FrameId: given this step
  StepSystem system;
};

struct StepWorkspace {
  explicit StepWorkspace(const Model& m) : model(&m), groups(m.groups().size()) {
    for (const Model::BoundTerm& t : m.terms()) term_names.push_back(t.term->name());
    for (size_t g = 0; g < m.groups().size(); ++g) {
      term_index.push_back(m.groups()[g].terms);
      for (int i : m.groups()[g].terms) groups[g].caches.push_back(m.terms()[i].term->make_cache());
      groups[g].contexts.resize(m.groups()[g].terms.size());
    }
  }
  const Model* model;  ///< compared, never read once the workspace is made (the model may be gone)
  std::vector<GroupWorkspace> groups;
  std::vector<std::vector<int>> term_index;  ///< per group, the model index of each of its terms
  std::vector<std::string> term_names;       ///< by model index
};

}  // namespace sflsh
