#pragma once
// What the browser viewer receives once per client, on connect: the skin's
// triangles and rest shape, body names, the objects' and tools' surfaces, the
// box positions are quantized in, and the colour legend's range. Sent as one
// JSON text message (scene_json); the frames that follow (frame_codec.hpp)
// carry only what changes.
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh::viewer {

struct ViewerObject {
  std::string name, shape, kind;  ///< kind: "static" | "kinematic" | "dynamic" | "tool"
  Points vertices;                ///< #N by 3, object frame (m)
  Triangles faces;                ///< #M by 3
};

struct ViewerScene {
  std::string mode = "live";   ///< "live" (a running scene) or "playback" (a result file)
  std::string title;           ///< shown in the page (scene or result file name)
  Triangles faces;             ///< #F by 3, every body's skin
  Points rest;                 ///< #V by 3, the first frame's posed skin (m, world)
  std::vector<std::string> body_names;  ///< one per body ("body" for one unnamed body)
  std::vector<int> body_offsets;        ///< #bodies + 1 vertex offsets
  int num_joints = 24;                  ///< 24 per body
  std::vector<ViewerObject> objects;    ///< in the order of ViewerFrame::object_poses
  std::vector<std::string> tools;       ///< live: the drivable tools; playback: the result's tools (tool index order)
  std::vector<int> tool_objects;        ///< objects index of each tool's surface, -1 if none
  /// The result's contact terms (ViewerFrame::contacts order): term and body, no frames.
  std::vector<ContactTrack> contacts;
  /// Quantization box (m, world): frame positions are sent as 16-bit
  /// fractions of it and clamped to it.
  Vec3 box_min = Vec3::Zero(), box_max = Vec3::Ones();
  double legend_max = 0.02;  ///< m: colour scale top (|u| is sent as 8 bits of [0, legend_max])
  double duration = 0;       ///< s, playback: the last frame's time; live: the scene's duration
  double dt = 0;             ///< s, the solver's step
  bool can_reset = true;     ///< live: the server applies reset messages
  std::vector<ToolEvent> tool_events;  ///< playback: the result's grasps and releases, in time order
};

/// The scene of a result (or of SceneSession::result_header() with at least
/// one recorded frame): skin, bodies, objects as object_display_meshes draws
/// them (names and kinds from the result; `tool_names` mark the objects that
/// are tools, by name, and their jaws "<tool>/jaw<j>"), the result's contact terms and its tool events. The box holds every frame's skin and the objects'
/// positions, padded by `pad` m (live scenes pad more: the body may move).
/// legend_max = the largest |u| over the frames rounded up to 1 mm, at least
/// `min_legend` m. Throws when the result has no frame.
ViewerScene viewer_scene(const SimulationResult& result, const std::vector<std::string>& tool_names, double pad,
                         double min_legend);

/// The scene of a result file played back (`sflsh view`): viewer_scene with the
/// result's tools, mode "playback", titled `title`.
ViewerScene playback_scene(const SimulationResult& result, const std::string& title);

/// The scene as the JSON text sent on connect:
/// {"type":"scene","mode","title","faces":[...flat],"rest":[...flat],"bodies":[{"name","begin","end"}],
///  "joints":J,"objects":[{"name","shape","kind","vertices":[...],"faces":[...]}],"tools":[{"name","object"}],
///  "contacts":[{"term","body"}],
///  "box_min":[3],"box_max":[3],"legend_max_mm":x,"duration":s,"dt":s,"can_reset":b,"protocol":1,
///  "tool_events":[{"time","tool","body","kind","points"}]}
std::string scene_json(const ViewerScene& scene);

}  // namespace sflsh::viewer
