#pragma once
// The simulation result file (HDF5): written frame by frame while a run goes
// (ResultWriter), or at once (write_simulation_result), and read back.
//
// Result file (HDF5, names fixed):
//   /meta/format_version, /meta/units, /meta/avatar, /meta/motion, /meta/dt,
//   /meta/bones ("dynamic" | "kinematic"), /meta/newton_iters
//   /surface/faces        (F,3)        skin triangles
//   /surface/rest         (V,3)        skin, unposed rest shape
//   /frames/time          (Fr,)        s
//   /frames/positions     (Fr,V,3)     posed surface, world, m (float32)
//   /frames/displacement  (Fr,V,3)     soft displacement u, unposed space, m (float32)
//   /frames/joints        (Fr,24,3)    world joint positions, m
//   /frames/reduced       (Fr,r)       reduced DoFs z
//   /frames/step_ms       (Fr,)        mean wall time of the steps since the previous frame
//   /frames/target_pelvis (Fr,3)       world position of the motion's pelvis (SMPL joint 0 of
//                                      the target pose on the avatar's skeleton) at the frame's
//                                      time, m; the simulated pelvis is /frames/joints[:, 0, :].
//                                      Absent in files written before it existed.
//   /steps/{time, energy, grad_norm, newton_decrement, outcome, ms}   (S,) per step
//     outcome: 0 accepted, 1 damped, 2 rejected
#include <memory>
#include <string>

#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

inline constexpr int kResultFormatVersion = 1;

/// Streams a result file: frames are appended as they come, per-step
/// diagnostics and the meta data are written by finish(), which commits the
/// file (nothing is left at `path` if finish() is never called).
class ResultWriter {
 public:
  /// `target_pelvis`: store FrameData::target_pelvis (/frames/target_pelvis).
  ResultWriter(const std::string& path, const Triangles& faces, const Points& surface_rest, int num_reduced,
               bool target_pelvis = true);
  ~ResultWriter();
  void add_frame(const FrameData& frame);
  void finish(const SimulationResult& result);
  int num_frames() const { return frames_; }

 private:
  std::unique_ptr<io::Hdf5File> file_;
  int frames_ = 0;
  bool target_pelvis_ = true;
};

/// Writes a whole result; /frames/target_pelvis only when the result has it.
void write_simulation_result(const SimulationResult& result, const std::string& path);
/// Reads a result file; recomputes the pelvis error from /frames/joints and
/// /frames/target_pelvis when the file has the latter.
SimulationResult read_simulation_result(const std::string& path);

}  // namespace sflsh
