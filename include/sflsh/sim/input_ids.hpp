#pragma once
// Ids of a model's per-step inputs. The ModelBuilder hands them out
// (ModelBuilder::add_frame, add_anchor_set) and StepInputs holds the inputs
// in vectors indexed by them, so a step never looks an input up by name;
// the names stay with the Model for files and messages.
namespace sflsh {

/// A world frame of the step inputs (an obstacle's, a tool's, a jaw's pose):
/// its index in StepInputs::frames.
struct FrameId {
  int index = -1;
  bool valid() const { return index >= 0; }
  friend bool operator==(FrameId a, FrameId b) { return a.index == b.index; }
  friend bool operator!=(FrameId a, FrameId b) { return a.index != b.index; }
};

/// One anchor term's set of anchored points (a tool's grasp of a body): its
/// index in StepInputs::anchors.
struct AnchorSetId {
  int index = -1;
  bool valid() const { return index >= 0; }
  friend bool operator==(AnchorSetId a, AnchorSetId b) { return a.index == b.index; }
  friend bool operator!=(AnchorSetId a, AnchorSetId b) { return a.index != b.index; }
};

}  // namespace sflsh
