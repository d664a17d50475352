#pragma once
// A scene's checkpoint: the simulator's State (sim/state_file.hpp) and what
// its tools hold, so that a run with grasping tools stops and resumes
// bit-identically. Groups added to the state file:
//   /tools/names              (T,)   the scene's tools, in scene order
//   /tools/<i>/bodies         scalar the bodies tool i grasps on (0: no sensors)
//   /tools/<i>/<b>/points     (n,)   skin vertices of body b it holds (only bodies it holds)
//   /tools/<i>/<b>/offsets    (n, 3) each one's offset in the tool's frame (m)
// A tool's pose source needs no state: keyframes and pose files are read at
// the checkpoint's time, a coupled tool's body is in the State, a live device
// takes over again as at the start.
#include <string>
#include <vector>

#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"

namespace sflsh {

/// One tool's part of a checkpoint.
struct ToolCheckpoint {
  std::string name;
  std::vector<std::vector<Anchor>> grasps;  ///< per body it grasps on: the anchors held
};

/// Writes `state` and the tools' part to `path` (atomically).
void write_scene_checkpoint(const std::string& path, const Model& model, const State& state,
                            const std::vector<ToolCheckpoint>& tools);

/// Reads a checkpoint of a scene whose tools are `tools` (names, and per tool
/// the number of bodies it grasps on, as the scene compiles them): fills each
/// one's grasps. A file whose tools differ in name, number or bodies, or
/// that holds none while the scene has tools, or whose anchors name no skin
/// vertex of the body (`skin_vertices` per body) is refused naming the file
/// and the field.
State read_scene_checkpoint(const std::string& path, const Model& model, std::vector<ToolCheckpoint>& tools,
                            const std::vector<int>& skin_vertices);

}  // namespace sflsh
