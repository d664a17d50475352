#pragma once
// The world frames of one step's inputs (obstacles, tools, jaws, a coupled
// tool's device), indexed by the FrameId the ModelBuilder handed out
// (ModelBuilder::add_frame; Model::frame_id finds one by name). A frame
// the caller did not set this step is "not given": the terms that need it
// throw naming it, the ones for which it is optional do without.
//
// Programs that build a model without keeping its ids may set frames by name
// instead; the step resolves those names against the model once when it
// starts (a name the model does not know is ignored, as a frame no term
// reads). The scene runtime uses ids only.
#include <map>
#include <string>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/input_ids.hpp"

namespace sflsh {

class WorldFrameInputs {
 public:
  /// Frame `id` (valid), given from now on; a new one starts at the identity, at rest.
  WorldFrame& operator[](FrameId id);
  /// Frame `id`, or null when it is not given (or `id` is not valid).
  const WorldFrame* find(FrameId id) const;
  /// The frame called `name`, given from now on (see header comment).
  WorldFrame& operator[](const std::string& name);
  /// The frames set by name (header comment).
  const std::map<std::string, WorldFrame>& by_name() const { return by_name_; }
  /// One past the largest id given so far.
  int size() const { return int(frames_.size()); }
  /// No frame given.
  void clear();

 private:
  std::vector<WorldFrame> frames_;
  std::vector<char> given_;
  std::map<std::string, WorldFrame> by_name_;
};

}  // namespace sflsh
