#pragma once
// Compiling a scene: a SceneDescription (scene_description.hpp) becomes the
// immutable Model — bodies with their soft-tissue and skeleton terms, dynamic
// objects and coupled tools as rigid bodies, and only the contact, anchor and
// coupling terms the scene's pairs need — the State at t = 0, and what a run
// needs to drive it: the bodies' motions and placements, the objects' shapes,
// the tools' shapes, jaws and grasp settings. Nothing here changes after
// compilation; ToolDriver (tool_driver.hpp) drives the tools and SceneSession
// (scene_session.hpp) steps the whole scene.
//
// Each scene section has one builder function in scene_compiler.cpp (bodies,
// objects, body–object contact, tools, body–body contact); a new scene key is
// read by the parser (scene_description.hpp) and used by one of them.
//
// Model order (fixed: the golden scene tests pin it): the bodies with their
// terms, the dynamic objects with theirs, body–object contact, per tool its
// coupled body and coupling then per body its shape, jaw and anchor terms,
// then body–body and self contact.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/motion/motion_clip.hpp"
#include "sflsh/scene/rigid_object.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/sim/energies/virtual_coupling.hpp"
#include "sflsh/sim/grasp_controller.hpp"
#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"

namespace sflsh {

struct SceneCompileOptions {
  /// Print what compiling does (mesh bakes) to stderr.
  bool progress = true;
  /// Root push limit of bodies in body contact, as a fraction of body weight.
  double body_push_limit = 0.25;
};

/// A body of the scene: its avatar, motion and placement, and where it sits in the model.
struct CompiledBody {
  const BodyDescription* desc = nullptr;
  std::shared_ptr<const Avatar> avatar;
  bool has_motion = false;
  MotionClip motion;
  int model_index = 0;
  Isometry placement = Isometry::Identity();  ///< at t = 0: heading about +Y, then offset
  /// The placement applies (scene bodies). false: the body follows its motion
  /// as given (one avatar driven by a motion, compile_avatar_motion).
  bool placed = true;
  /// Start at rest in the motion's first pose instead of moving with it.
  bool start_at_rest = false;
  /// Model term indices of its elastic and damping terms: what a stiffness
  /// scale multiplies (model_with_stiffness).
  std::vector<int> stiffness_terms;

  /// The placement at time t: with a motion it travels at the body's velocity.
  Isometry placement_at(double t) const;
  /// The motion's pose at t (the rest pose without a motion), placed.
  BodyPose target_pose(double t) const;
  /// Where the body starts: the placed motion at t = 0, moving with the motion
  /// (and the body's velocity) over the first step of `h` seconds, or at rest
  /// there (start_at_rest).
  BodyState initial_state(double h) const;
};

/// A rigid object of the scene (static, kinematic or dynamic).
struct CompiledObject {
  const RigidObjectDescription* desc = nullptr;
  RigidObjectModel model;
  int model_index = -1;  ///< dynamic objects: their body in the model
  FrameId frame;         ///< static and kinematic objects: their world frame in the step inputs
};

/// A gripper jaw: a contact shape turning about the tool's hinge with the closure.
struct CompiledJaw {
  std::string name;  ///< "<tool>/jaw<i>": its contact terms' object and world frame
  RigidObjectModel model;
  Isometry offset = Isometry::Identity();  ///< the jaw frame in the tool frame at closure 0
  double side = 1;                         ///< +1 or −1: which way it turns
  /// Its world frame in the step inputs: the jaw's pose (kinematic tool) or
  /// its moving shape's on the coupled body (moving_shape_frame_name).
  FrameId frame;
};

/// A tool of the scene: its shapes, coupling and grasp settings, its inputs'
/// ids and the model terms that act on it.
struct CompiledTool {
  const ToolDescription* desc = nullptr;
  RigidObjectModel shape;                ///< when desc->has_shape
  std::vector<CompiledJaw> jaws;
  int model_index = -1;                  ///< coupled tools: their rigid body in the model
  VirtualCouplingOptions coupling;       ///< coupled tools: the coupling's gains
  GraspOptions grasp;                    ///< tools with sensors: the grasp controller's settings
  /// Its world frame in the step inputs: the tool's pose (kinematic) or its
  /// device's (coupled: device_frame_name).
  FrameId frame;
  std::vector<AnchorSetId> anchor_sets;  ///< tools with sensors, per body: its anchor term's set
  /// Model term indices: its contact terms (shape and jaws, every body) and
  /// anchor terms, whose forces on the bodies the tool feels (ToolDriver::feel).
  std::vector<int> contact_terms, anchor_terms;
  int coupling_term = -1;                ///< coupled tools: the model index of its coupling

  bool coupled() const { return model_index >= 0; }
  /// A jaw's pose in the tool frame at `closure` (rad): turned by side·closure/2 about the hinge.
  Isometry jaw_in_tool(const CompiledJaw& jaw, double closure) const;
};

/// A compiled scene. Its `desc` pointers point into the SceneDescription it
/// was compiled from, which must outlive it.
struct CompiledScene {
  /// What messages call the run: the scene file ("scene" when built in code)
  /// or, for one avatar driven by a motion, the motion's name.
  std::string name;
  /// One avatar driven by a motion (compile_avatar_motion): results name the
  /// motion and list no bodies, as the one-avatar result file has them.
  bool one_avatar = false;
  std::shared_ptr<const Model> model;  ///< every body at stiffness scale 1
  State initial;  ///< t = 0; coupled tools' bodies at rest at the origin until their driver starts them
  double h = 0;        ///< s, the step
  double seconds = 0;  ///< s, solver.seconds or the longest motion
  long steps = 0;      ///< max(1, round(seconds / h))
  std::vector<CompiledBody> bodies;    ///< scene order
  std::vector<CompiledObject> objects; ///< scene order
  std::vector<CompiledTool> tools;     ///< scene order
  /// Model term indices of every contact term, in model order: body–object
  /// pairs, the tools' shapes and jaws, then body–body skin and capsule pairs
  /// and self contact (not the tools' anchors and couplings). What results
  /// record per frame (SimulationResult::contacts).
  std::vector<int> contact_terms;
};

/// Compiles `scene`. Throws sflsh::Error naming the scene file and the body,
/// object or tool on inputs the runtime rejects (no bodies, an unresolved
/// `avatar: default`, a motion that does not load, a dynamic object with the
/// contact patch, colliding bodies without bone capsules, ...).
CompiledScene compile_scene(const SceneDescription& scene, const SceneCompileOptions& options = {});

/// One avatar driven by `motion` (`sflsh simulate --avatar --motion`,
/// run_simulation) as a one-body scene: `scene` holds its one body (name,
/// bones) and solver (dt, seconds); the model is avatar_model(avatar, sim,
/// skeleton when sim.bones_dynamic) and the body follows the motion unplaced,
/// moving with it at t = 0 unless `start_at_rest`. `scene` must outlive the result.
CompiledScene compile_avatar_motion(const SceneDescription& scene, std::shared_ptr<const Avatar> avatar,
                                    const MotionClip& motion, const SimulatorOptions& sim,
                                    const SkeletonTermsOptions& skeleton, bool start_at_rest);

/// `base` with the elastic and damping terms of body i (scene order) scaled by
/// scales[i] (ScaledTerm, sim/energies/scaled_term.hpp); `base` itself when
/// every scale is 1.
std::shared_ptr<const Model> model_with_stiffness(const std::shared_ptr<const Model>& base,
                                                  const std::vector<CompiledBody>& bodies,
                                                  const std::vector<double>& scales);

}  // namespace sflsh
