#pragma once
// SceneSession's state, shared by the files that implement it: scene_run.cpp
// (building, stepping, stiffness, resuming), scene_frames.cpp (the result's
// header and frames, the bodies' surfaces) and tool_driver.cpp (its tools).
#include <memory>
#include <vector>

#include "sflsh/scene/scene_compiler.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/scene/tool_driver.hpp"

namespace sflsh {

struct SceneSession::Impl {
  SceneDescription sc;
  SceneSessionOptions opt;
  CompiledScene compiled;         ///< refers to `sc`
  std::vector<ToolDriver> tools;  ///< one per compiled tool (refers to `compiled`)
  std::unique_ptr<Simulator> sim;
  StepInputs in;
  StepReport report;
  std::vector<SceneToolEvent> events;
  State initial;               ///< the state at t = 0 with the tools started (reset)
  std::vector<double> stiffness;  ///< per body (scene order): its stiffness scale
  long k = 0;                  ///< steps done
  long first_k = 0;            ///< steps done when the run started (0, or a checkpoint's)

  /// Starts the compiled scene: its tools' drivers, the simulator at the initial state.
  void start();

  /// The result's object poses at time t (world): the objects, the tools with
  /// a shape, then every tool's jaws (SceneSession::result_header's order).
  std::vector<Isometry> object_poses(double t) const;

  /// Every tool's pose as drawn at time t, closure, force and torque.
  std::vector<ToolFrame> tool_frames(double t) const;
  /// Every contact term's (compiled.contact_terms) force, point, depth and
  /// active samples from the last step's report; `poses`: object_poses at
  /// the frame's time (where terms without a contact point act).
  std::vector<ContactFrame> contact_frames(const std::vector<Isometry>& poses) const;
  /// Where a contact term that reports no contact point is drawn: the
  /// object's position for "contact:<object>", else its body's pelvis.
  Vec3 fallback_contact_point(const Model::BoundTerm& term, const std::vector<Isometry>& poses) const;

  /// An object's pose at time t: its description's, or its rigid body's (dynamic).
  Isometry object_pose(const CompiledObject& o, double t) const {
    if (o.model_index < 0) return object_pose_at(*o.desc, t);
    return Isometry(sim->state(o.model_index).bones[0] * o.model.shape_in_body);
  }
};

}  // namespace sflsh
