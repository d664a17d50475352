#include "sflsh/sim/world_frame_inputs.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

WorldFrame& WorldFrameInputs::operator[](FrameId id) {
  require(id.valid(), "step inputs: world frame id ", id.index, " is not valid");
  if (id.index >= int(frames_.size())) {
    frames_.resize(size_t(id.index) + 1);
    given_.resize(size_t(id.index) + 1, 0);
  }
  given_[size_t(id.index)] = 1;
  return frames_[size_t(id.index)];
}

const WorldFrame* WorldFrameInputs::find(FrameId id) const {
  if (!id.valid() || id.index >= int(frames_.size()) || !given_[size_t(id.index)]) return nullptr;
  return &frames_[size_t(id.index)];
}

WorldFrame& WorldFrameInputs::operator[](const std::string& name) { return by_name_[name]; }

void WorldFrameInputs::clear() {
  frames_.clear();
  given_.clear();
  by_name_.clear();
}

}  // namespace sflsh
