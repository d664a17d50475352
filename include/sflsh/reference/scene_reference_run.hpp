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
// scene session, so both solvers see the same inputs.
// Refused (one line naming the scene and the item): several bodies, dynamic
// objects, tools with a coupling, a live stream, jaws or a grasp. Dynamic bones
// run kinematic and friction is dropped, each with a warning line on stderr.
// Cost: seconds per step on the default body (a sparse Cholesky of ~30k DoFs
// per Newton iteration); progress is shown.
#include "sflsh/scene/scene_run.hpp"

namespace sflsh {

struct SceneReferenceOptions {
  bool progress = true;
  int max_iterations = 50;     ///< Newton iterations per step at most (FullFemOptions)
};

/// Runs `scene` with the full-FEM reference; the result has the reduced run's
/// layout (frames of the body's skin, objects' and tools' poses; no reduced
/// coordinates: z is empty) and `stats` gets each obstacle's contact figures.
/// Throws sflsh::Error for the scenes it refuses (header comment).
SimulationResult run_scene_reference(const SceneDescription& scene, const SceneReferenceOptions& options,
                                     SceneContactStats* stats = nullptr);

}  // namespace sflsh
