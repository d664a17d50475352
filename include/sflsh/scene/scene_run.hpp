#pragma once
// Running a scene file (`sflsh simulate scene.yaml`, issue 10): the
// SceneDescription (scene_description.hpp) becomes a Model — bodies with
// their soft-tissue and skeleton terms, dynamic rigid objects as 6-DoF bodies,
// and only the contact terms the scene's pairs need — and is stepped with
// StepInputs carrying each body's motion targets and the static and kinematic
// objects as named world frames. The result holds every body's skin
// (concatenated, SimulationResult::body_vertex_offsets) and the objects' poses.
//
// Scene conventions (documented for users in scene_description.hpp):
//   * placement P (offset, heading about +Y) is applied to the motion: the
//     body's targets are P·G(t); with a non-zero `velocity` the placement
//     travels, P(t) = T(velocity·t)·P, and the body starts with that velocity;
//   * a body without a motion holds its rest pose with its joint springs but
//     its root is free (it falls, rolls and comes to rest under contact);
//   * bodies that collide with another body track their motion's root with a
//     force limit (body_push_limit × body weight) so that contact, not the
//     motion, decides where they meet;
//   * tools (issue 11) are kinematic frames following keyframes or a pose
//     file: with a shape they touch every body (SdfContactTerm), with sensors
//     they grasp (GraspController, AMBF Alg. 3) through one AnchorTerm per
//     body; the force on the tool is minus what those terms exert;
//   * contact: one SdfContactTerm per colliding body–object pair (skin samples
//     every `sample_spacing`), one CapsuleContactTerm per colliding pair of
//     bodies (skipped when both are kinematic), and one per body with
//     self_contact; object–object contact is not modelled.
#include <functional>
#include <string>
#include <vector>

#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

struct SceneRunOptions {
  bool progress = true;
  /// Folder of baked mesh SDFs ("" = no cache): the CLI passes the default cache.
  std::string cache_dir;
  /// Root push limit of bodies in body contact, as a fraction of body weight.
  double body_push_limit = 0.25;
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
  struct ToolEvent {
    double time = 0;
    std::string tool, body, kind;  ///< kind: "grasp" | "release"
    int points = 0;
  };
  std::vector<ToolEvent> tool_events;
  std::string describe() const;
  /// CSV: time, tool, force (N), anchors, max_stretch (m), one row per tool and step.
  void write_tool_log(const std::string& path) const;
};

/// Simulates `scene` (read and checked by read_scene_description and
/// validate_scene_files) and returns the result with every output frame.
/// Throws naming the body/object on inputs the runtime rejects (e.g. an avatar
/// without capsules in body contact) and when the state becomes non-finite.
SimulationResult run_scene(const SceneDescription& scene, const SceneRunOptions& options = {},
                           SceneContactStats* stats = nullptr);

}  // namespace sflsh
