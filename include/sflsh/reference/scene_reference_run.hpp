#pragma once
// A scene run with the full-FEM reference (reference/full_fem.hpp) in place of the
// reduced soft tissue: `sflsh simulate scene.yaml --solver full`, so that a
// user can check a scene of their own against the ground truth.
//
// What the reference models: one body with its bones prescribed by its motion
// (placed as the scene places it), every node of the tet mesh a DoF; static and
// kinematic rigid objects, and kinematic tools with a contact shape, as
// frictionless obstacles whose contact is a pressure over the skin's faces
// (contact.pressure_stiffness, contact.spacing: the same keys as the reduced
// solver's contact patch). The poses of bones, objects and tools come from the
// scene session, so both solvers see the same inputs. A kinematic tool with a
// grasp grasps the reference's own skin by the reduced run's rule
// (grasp_controller.hpp: the same sensors, closure threshold and tool path;
// anchors start unstretched on the reference's skin) and holds it with the
// same spring–dampers (FullFemAnchor); its force is the anchors' reaction.
// Refused (one line naming the scene and the item): several bodies, dynamic
// objects, tools with a live stream or jaws. Dynamic bones run kinematic, a
// coupled tool moves along its device's path (keyframes or pose file: where
// the coupling pulls it; the reduced run's tool lags by the coupling's
// stretch, force / stiffness), and friction is dropped, each with a warning
// line on stderr.
// Cost: seconds per step on the default body (a sparse Cholesky of ~30k DoFs
// per Newton iteration); progress is shown.
#include <functional>
#include <vector>

#include "sflsh/scene/scene_run.hpp"

namespace sflsh {

class FullFem;
struct FullFemReport;

/// What SceneReferenceOptions::on_step sees after a step.
struct SceneReferenceStep {
  long step = 0;                                    ///< 1-based
  double time = 0;                                  ///< s, at the end of the step
  const FullFem* fem = nullptr;                     ///< the reference (posed_surface(), soft_displacement())
  const FullFemReport* report = nullptr;            ///< contacts: one per obstacle, in the stats' pair order
  const std::vector<Isometry>* obstacle_poses = nullptr;  ///< world, one per obstacle
  /// N, world, one per tool of the scene: what the body exerts on it through
  /// its shape's contact and its anchors.
  const std::vector<Vec3>* tool_forces = nullptr;
  const std::vector<Isometry>* tool_poses = nullptr;  ///< world, one per tool of the scene, at the step's end
  double cpu_ms = 0;                                ///< thread CPU time of the reference's step
};

struct SceneReferenceOptions {
  bool progress = true;
  int max_iterations = 50;     ///< Newton iterations per step at most (FullFemOptions)
  /// Called after every step (e.g. the contact benchmark's per-step figures); may be empty.
  std::function<void(const SceneReferenceStep&)> on_step;
};

/// Throws the one-line refusal (header comment) when the reference cannot run
/// `scene`; nothing otherwise (the warnings come with the run).
void check_scene_reference(const SceneDescription& scene);

/// Runs `scene` with the full-FEM reference; the result has the reduced run's
/// layout (frames of the body's skin, objects' and tools' poses; no reduced
/// coordinates: z is empty) and `stats` gets each obstacle's contact figures.
/// Throws sflsh::Error for the scenes it refuses (header comment).
SimulationResult run_scene_reference(const SceneDescription& scene, const SceneReferenceOptions& options,
                                     SceneContactStats* stats = nullptr);

}  // namespace sflsh
