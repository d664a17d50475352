#pragma once
// The offline run loop, as fast as possible: scene files (`sflsh simulate
// scene.yaml`) and one avatar driven by a motion (`sflsh simulate --avatar
// --motion`, run_simulation, a one-body scene) alike. A SceneSession
// (scene_session.hpp: how the scene becomes a model and what its bodies,
// objects and tools do) stepped to its end, every output frame recorded, and
// the contact and tool figures gathered. The result holds every body's skin
// (concatenated, SimulationResult::body_vertex_offsets) and the objects' and
// tools' poses.
#include <functional>
#include <string>
#include <vector>

#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

struct SceneRunOptions {
  bool progress = true;
  /// Root push limit of bodies in body contact, as a fraction of body weight.
  double body_push_limit = 0.25;
  /// Keep every output frame in the result (memory: ~0.5 MB per frame for a
  /// 10k-vertex body). Long runs set false and stream with on_frame.
  bool keep_frames = true;
  /// Called with every output frame as it is made; may be empty.
  std::function<void(const FrameData&)> on_frame;
  /// Called after every step (e.g. the benchmark records u); may be empty.
  std::function<void(const Simulator&, const StepReport&)> on_step;
  /// Continue from this checkpoint (sim/state_file.hpp) instead of the
  /// scene's start: the run goes from the checkpoint's time to the scene's
  /// end, its frames start at the checkpoint's time; tools resume with what
  /// they hold (scene/scene_checkpoint.hpp).
  std::string resume;
  /// Save the final state here (a checkpoint to resume from).
  std::string checkpoint;
  /// TEST ONLY: SceneSessionOptions::inject_nan_at_step.
  long inject_nan_at_step = 0;
};

/// Contact figures of a run (the largest over all steps).
struct SceneContactStats {
  struct Pair {
    std::string term;            ///< e.g. "contact:floor" on body "alice"
    std::string body;
    double max_penetration = 0;  ///< m: skin samples into the object, or capsule overlap
    double max_force = 0;        ///< N
    long active_steps = 0;       ///< steps with any sample/pair in contact
    Vec3 last_force = Vec3::Zero();  ///< N, at the final step (on the body)
  };
  std::vector<Pair> pairs;
  /// Total linear momentum of the model at the first and last step (kg·m/s).
  Vec3 momentum_start = Vec3::Zero(), momentum_end = Vec3::Zero();
  /// Tools, per step: the force on the tool (what its contact and anchors
  /// take from the bodies, N, world), its anchors and their largest stretch (m).
  struct ToolStep {
    double time = 0;
    std::string tool;
    Vec3 force = Vec3::Zero();
    int anchors = 0;
    double max_stretch = 0;
  };
  std::vector<ToolStep> tool_steps;
  /// Grasp and release events.
  using ToolEvent = sflsh::ToolEvent;
  std::vector<ToolEvent> tool_events;
  std::string describe() const;
  /// CSV: time, tool, force (N), anchors, max_stretch (m), one row per tool and step.
  void write_tool_log(const std::string& path) const;
};

/// Simulates `scene` (read by read_scene_description, its mesh shapes and
/// `avatar: default` prepared by prepare_scene_assets) and returns the result with every output frame.
/// Throws naming the body/object on inputs the runtime rejects (e.g. an avatar
/// without capsules in body contact), and SimulationStopped (with the frames
/// made so far, marked incomplete) when the state or an energy becomes
/// non-finite, naming the step, the term and the body.
SimulationResult run_scene(const SceneDescription& scene, const SceneRunOptions& options = {},
                           SceneContactStats* stats = nullptr);

/// The run loop of every offline run (scene files and one avatar driven by a
/// motion, run_simulation): steps `scene` from where it stands (or
/// options.resume) to its end, an output frame at t = 0 and every
/// 1/scene().output.fps s (kept, passed to on_frame), the pelvis figures of
/// the first body, the contact and tool figures into `stats`, and
/// options.checkpoint at the end. Throws SimulationStopped as run_scene.
SimulationResult run_scene(SceneSession& scene, const SceneRunOptions& options = {},
                           SceneContactStats* stats = nullptr);

}  // namespace sflsh
