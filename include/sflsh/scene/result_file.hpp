#pragma once
// The simulation result file (HDF5): written frame by frame while a run goes
// (ResultWriter), or at once (write_simulation_result), and read back.
//
// Result file (HDF5, names fixed). Format version 2 (scenes with
// several bodies and rigid objects); version-1 files (one body, no objects)
// still read. B = number of bodies (1 without /bodies), O = number of objects.
//   /meta/format_version, /meta/units, /meta/avatar, /meta/motion, /meta/dt,
//   /meta/bones ("dynamic" | "kinematic"), /meta/newton_iters
//   /meta/incomplete      int 0 | 1: 1 = the run stopped early (a non-finite value, see
//                         sim/finite_guard.hpp); the frames are those made before the stop.
//                         Absent in files written before it existed (= 0).
//   /meta/stop_reason     string, why the run stopped; only when /meta/incomplete is 1
//   /surface/faces        (F,3)        skin triangles (every body's, concatenated)
//   /surface/rest         (V,3)        skin, unposed rest shape
//   /bodies/names         (B,)         strings; only in files of scenes with bodies named
//   /bodies/vertex_offsets (B+1,)      int: body b's skin vertices are rows
//                                      [offsets[b], offsets[b+1]) of /surface/rest and of
//                                      every frame's positions; offsets[0] = 0,
//                                      offsets[B] = V, non-decreasing. With /bodies/names only.
//   /frames/time          (Fr,)        s
//   /frames/positions     (Fr,V,3)     posed surface, world, m (float32)
//   /frames/displacement  (Fr,V,3)     soft displacement u, unposed space, m (float32)
//   /frames/joints        (Fr,24·B,3)  world joint positions, m; rows 24b..24b+23 are body b's
//   /frames/reduced       (Fr,r)       reduced DoFs z (every body's, concatenated)
//   /frames/step_ms       (Fr,)        mean wall time of the steps since the previous frame
//   /frames/target_pelvis (Fr,3)       world position of the motion's pelvis (SMPL joint 0 of
//                                      the target pose on the avatar's skeleton) at the frame's
//                                      time, m; the simulated pelvis is /frames/joints[:, 0, :].
//                                      Absent in files written before it existed.
//   /frames/object_poses  (Fr,O,7)     rigid object o's pose (object frame -> world) per frame:
//                                      position x y z (m), then the unit quaternion w x y z of
//                                      its rotation. Only when O > 0.
//   /objects/<o>/name, shape, kind     strings, o = 0..O-1 (ObjectTrack; shape is plane, sphere,
//                                      box, capsule, cylinder or mesh; kind static, kinematic
//                                      or dynamic)
//   /objects/<o>/vertices (N,3), faces (M,3)   the object's surface in its own frame (m);
//                                      a plane's is any flat patch of it (geometry::
//                                      plane_patch_mesh), outward along the plane's normal;
//                                      exports redraw it sized to the bodies
//                                      (result_export.hpp)
//   /tools/<t>/name       string, t = 0..T-1: the scene's tools (ToolTrack). Only when T > 0.
//   /frames/tool_poses    (Fr,T,7)     tool t's pose (tool frame -> world) per frame, as
//                                      /frames/object_poses
//   /frames/tool_closure  (Fr,T)       its device's jaw opening, rad (0 = shut)
//   /frames/tool_force    (Fr,T,3)     force the bodies exert on it (contact and anchors), N, world
//   /frames/tool_torque   (Fr,T,3)     torque about its frame's origin, N·m, world
//   /tool_events/{time (E,) s, tool (E,), body (E,), kind (E,) "grasp" | "release",
//                points (E,) int}      grasps and releases; only when there were any
//   (the /tools, /frames/tool_* and /tool_events datasets are absent in files
//   written before they existed, and in results without tools)
//   /contacts/<c>/{term, body, force (Fr,3), point (Fr,3), max_penetration (Fr,),
//                active_samples (Fr,)}   c = 0..C-1: every contact term's force on its body
//                                      (N, world), where it acts (m), its deepest sample (m)
//                                      and samples in contact, per frame (result_contacts.hpp).
//                                      Only when C > 0; absent in older files (= no contacts).
//   /steps/{time, energy, grad_norm, newton_decrement, outcome, ms}   (S,) per step
//     outcome: 0 accepted, 1 damped, 2 rejected
//   /steps/bones          (S,24·B,7)   every body's bones at the end of each step, as
//                                      /frames/object_poses (position, then unit quaternion
//                                      w x y z); rows 24b..24b+23 are body b's
//   /meta/start_bones     (2,24·B,7)   the same at t − h and t of the run's start
//   (both absent in files written before they existed and in live runs; `sflsh fit`
//   prescribes them to reproduce a run with dynamic bones)
#include <memory>
#include <string>

#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

inline constexpr int kResultFormatVersion = 2;

/// What a result holds besides one body's skin: the bodies of a scene and its
/// rigid objects (their surfaces; poses come with each frame).
struct ResultScene {
  std::vector<std::string> body_names;  ///< empty = one body
  std::vector<int> body_vertex_offsets; ///< #bodies + 1 entries, or empty with body_names
  std::vector<ObjectTrack> objects;     ///< name, shape, kind, vertices, faces (poses unused)
  std::vector<std::string> tool_names;  ///< the tools (frames come with each frame)
  std::vector<ContactTrack> contacts;   ///< term and body of each contact (frames come with each frame)
};

/// The bodies, objects, tools and contacts of `result` (objects and contacts copied without their frames).
ResultScene result_scene(const SimulationResult& result);

/// Number of bodies of a result: body_names.size(), or 1 when that is empty.
int num_bodies(const SimulationResult& result);

/// Lines for SimulationResult::describe(): "bodies: a (N skin vertices), b
/// (...)" when the bodies are named, "objects: ball (sphere, dynamic), floor
/// (plane, static)" when there are objects; empty otherwise. Each line ends
/// in a newline.
std::string describe_scene_parts(const SimulationResult& result);

/// Streams a result file: frames are appended as they come, per-step
/// diagnostics and the meta data are written by finish(), which commits the
/// file (nothing is left at `path` if finish() is never called).
class ResultWriter {
 public:
  /// `faces` (#F by 3) and `surface_rest` (#V by 3): every body's skin;
  /// `num_reduced`: length of FrameData::reduced; `target_pelvis`: store
  /// FrameData::target_pelvis (/frames/target_pelvis); `scene`: the bodies
  /// and rigid objects (default: one body, no objects). Throws naming `path`
  /// when the scene does not fit the skin (offsets, face indices, names).
  ResultWriter(const std::string& path, const Triangles& faces, const Points& surface_rest, int num_reduced,
               bool target_pelvis = true, const ResultScene& scene = {});
  ~ResultWriter();
  /// Appends a frame: positions and displacement #V by 3, joints 24·B by 3,
  /// reduced of num_reduced, one finite rigid pose per object, one finite
  /// ToolFrame per tool, one finite ContactFrame per contact. Throws naming
  /// the path and the field on a size mismatch or a non-finite/non-rigid pose.
  void add_frame(const FrameData& frame);
  void finish(const SimulationResult& result);
  int num_frames() const { return frames_; }

 private:
  /// Appends one frame of every tool (/frames/tool_*); `at` starts messages.
  void append_tool_frames(const std::vector<ToolFrame>& tools, const std::string& at);
  /// /tool_events (nothing when there are none).
  void write_tool_events(const std::vector<ToolEvent>& events);
  /// /steps/bones and /meta/start_bones (nothing when the result has none).
  void write_bones(const SimulationResult& result);

  std::unique_ptr<io::Hdf5File> file_;
  int frames_ = 0;
  bool target_pelvis_ = true;
  Eigen::Index num_vertices_ = 0, num_joints_ = 24, num_reduced_ = 0;
  std::vector<std::string> object_names_;
  std::vector<std::string> tool_names_;
  std::vector<ContactTrack> contacts_;  ///< term and body of each contact (no frames)
};

/// Dataset `name` of `f` (the file at `path`) holding poses as the result file
/// stores them (position, then unit quaternion w x y z), shape (entries,
/// bones, 7): entries × bones transforms. Throws one line naming the file,
/// the dataset and the entry and bone of a pose that is not finite or rigid.
std::vector<std::vector<Isometry>> read_result_poses(const io::Hdf5File& f, const std::string& path,
                                                     const std::string& name, std::int64_t entries,
                                                     std::int64_t bones);

/// Writes a whole result; /frames/target_pelvis only when the result has it,
/// the bodies and objects when it has them (every object a pose per frame).
void write_simulation_result(const SimulationResult& result, const std::string& path);
/// Reads a result file (format version 1 or 2); recomputes the pelvis error
/// from /frames/joints and /frames/target_pelvis when the file has the
/// latter. Throws one error naming the path and dataset on a malformed file
/// (shapes, face indices, body offsets, names count, non-unit quaternions).
SimulationResult read_simulation_result(const std::string& path);

}  // namespace sflsh
