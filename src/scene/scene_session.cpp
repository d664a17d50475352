#include "sflsh/scene/scene_session.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/material_file.hpp"
#include "sflsh/scene/rigid_object.hpp"
#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/energies/capsule_contact.hpp"
#include "sflsh/sim/energies/damping.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/sim/energies/virtual_coupling.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/grasp_controller.hpp"
#include "sflsh/sim/rigid_body_terms.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/pose_recorder.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "sflsh/teleop/pose_ramp.hpp"
#include "sflsh/teleop/pose_stream_link.hpp"
#include "sflsh/teleop/pose_track.hpp"

namespace sflsh {
namespace {

using teleop::PoseSample;
using teleop::PoseInterpolation;
using teleop::PoseTrack;

/// A body of the scene as the run drives it.
struct SceneBody {
  const BodyDescription* desc = nullptr;
  std::shared_ptr<const Avatar> avatar;
  bool has_motion = false;
  MotionClip motion;
  int model_index = 0;
  Isometry placement = Isometry::Identity();  ///< at t = 0
};

struct SceneObject {
  const RigidObjectDescription* desc = nullptr;
  RigidObjectModel model;
  int model_index = -1;  ///< dynamic objects: their body in the model
};

/// The placement at time t: heading about +Y, offset, travelling at the body's velocity.
Isometry placement_at(const SceneBody& b, double t) {
  Isometry P = b.placement;
  if (b.has_motion) P.translation() += b.desc->velocity * t;
  return P;
}

/// The motion's pose at t (the rest pose without a motion), placed by P.
BodyPose placed_pose(const SceneBody& b, double t) {
  BodyPose pose = b.has_motion ? b.motion.sample(t) : BodyPose{};
  const Isometry P = placement_at(b, t);
  const Vec3 root = b.avatar->joints_rest.row(0).transpose();
  pose.axis_angle.row(0) = rotation_log(P.linear() * rodrigues(pose.axis_angle.row(0).transpose())).transpose();
  pose.translation = P * (root + pose.translation) - root;
  return pose;
}

std::string motion_spec_name(const std::string& spec) {
  const size_t slash = spec.find_last_of('/');
  return slash == std::string::npos ? spec : spec.substr(slash + 1);
}

/// The world frame at t + h from the poses at t and t + h (twist by finite difference).
WorldFrame frame_between(const Isometry& before, const Isometry& after, double h) {
  WorldFrame f;
  f.pose = after;
  f.linear_velocity = (after.translation() - before.translation()) / h;
  f.angular_velocity = rotation_log(after.linear() * before.linear().transpose()) / h;
  return f;
}

PoseTrack tool_track(const ToolDescription& t) {
  if (!t.pose_file.empty()) return PoseTrack(teleop::read_pose_file(t.pose_file), t.pose_file);
  if (t.keyframes.empty()) return PoseTrack({PoseSample{}}, "tool '" + t.name + "' start pose");
  std::vector<PoseSample> samples;
  for (const ToolKeyframe& k : t.keyframes) samples.push_back({k.time, k.position, k.orientation, k.closure});
  return PoseTrack(std::move(samples), "tool '" + t.name + "' keyframes");
}

Isometry sample_pose(const PoseSample& s) {
  Isometry T = Isometry::Identity();
  T.linear() = s.orientation.normalized().toRotationMatrix();
  T.translation() = s.position;
  return T;
}

/// Where body `b` starts: the placed motion at t = 0, moving with the motion
/// (and the body's velocity) over the first step.
BodyState initial_state(const SceneBody& b, double h) {
  BodyState s;
  s.q.bones = target_bones(*b.avatar, placed_pose(b, 0.0));
  s.q.z = VecX::Zero(b.avatar->num_reduced());
  s.q_prev.z = s.q.z;
  if (b.has_motion) {
    s.q_prev.bones = bones_one_step_before(s.q.bones, target_bones(*b.avatar, placed_pose(b, h)));
  } else {
    s.q_prev.bones = s.q.bones;
    for (Isometry& prev : s.q_prev.bones) prev.translation() -= b.desc->velocity * h;
  }
  return s;
}


/// A tool as the session drives it: its pose source, contact field, and per
/// body a grasp controller with its anchor term's key.
struct SceneTool {
  const ToolDescription* desc = nullptr;
  std::unique_ptr<PoseTrack> track;  ///< keyframes or pose file (null: live only)
  RigidObjectModel shape;            ///< when desc->has_shape
  std::vector<GraspController> grasps;   ///< per body (when the tool has sensors)
  std::vector<GraspController> grasps_at_start;  ///< `grasps` before the first step (reset)
  std::vector<std::string> anchor_keys;  ///< per body: the anchor term's tool name
  std::string contact_term;              ///< "contact:<tool>": its contact terms' name
  std::string anchor_prefix;             ///< "anchor:<tool>@": its anchor terms' names start so
  bool hold = false;  ///< the track is a recording: zero-order hold
  /// The device sample at the current time, and the pushed one for the next
  /// step (live tools).
  PoseSample device_now;
  bool live = false;
  PoseSample pushed;
  std::unique_ptr<teleop::PoseStreamLink> link;  ///< a live stream (pose_stream)
  std::uint64_t link_sequence = 0;               ///< the newest stream sample taken
  bool link_seen = false;
  /// The live device's take-over of the tool's pose (started by the first live sample).
  teleop::PoseRamp ramp;
  int model_index = -1;  ///< coupled tools: their rigid body in the model
  /// Gripper jaws: contact shapes turning about the hinge with the closure.
  struct Jaw {
    std::string name;  ///< "<tool>/jaw<i>": its contact terms' object and world frame
    RigidObjectModel model;
    Isometry offset = Isometry::Identity();
    double side = 1;
  };
  std::vector<Jaw> jaws;
  /// A jaw's pose in the tool frame at `closure` (rad): turned by side·closure/2 about the hinge.
  Isometry jaw_in_tool(const Jaw& j, double closure) const {
    Isometry H = Isometry::Identity();
    H.translation() = desc->hinge_origin;
    Isometry R = Isometry::Identity();
    R.linear() = Eigen::AngleAxisd(j.side * 0.5 * closure, desc->hinge_axis).toRotationMatrix();
    return H * R * H.inverse() * j.offset;
  }
  VirtualCouplingOptions coupling;
  std::unique_ptr<teleop::PoseRecorder> recorder;  ///< --record: the device poses used
  PoseSample recorded;
  SceneToolState state;

  /// Whether state.pose is the pose to draw (else the linear track at t, as before sessions).
  bool exact_pose() const { return live || hold || model_index >= 0; }
  /// The tool's body pose at the current time (coupled) or its device's.
  Isometry pose(const Simulator& sim) const {
    return model_index >= 0 ? sim.state(model_index).bones[0] : sample_pose(device_now);
  }
};

/// A term whose energy, gradient and Hessian are `scale` times another's: the
/// stiffness scale of a body's elastic and damping terms. Scaling every Young's
/// modulus and the Fung c of a material by s (Poisson's ratio kept) scales its
/// StVK stiffness C, c and the barrier's κ (∝ Young) by s, and
/// Ψ = (sc/2)(exp(2 sΨ_stvk / (sc)) − 1) + s Ψ_vol = s Ψ: the elastic energy,
/// and the damping's K₀, are exactly s times the unscaled ones (up to
/// rounding). Quantities reported are the inner term's (elastic and damping
/// report none).
class ScaledTerm final : public EnergyTerm {
 public:
  ScaledTerm(std::shared_ptr<const EnergyTerm> inner, double scale) : inner_(std::move(inner)), scale_(scale) {}
  std::string name() const override { return inner_->name(); }
  BodyBlocks blocks() const override { return inner_->blocks(); }
  std::unique_ptr<TermCache> make_cache() const override { return inner_->make_cache(); }
  void begin_step(const StepContext& ctx) const override { inner_->begin_step(ctx); }
  bool active(const StepContext& ctx) const override { return inner_->active(ctx); }
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override {
    return inner_->report(ctx, q);
  }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override {
    if (!grad && !hess) return scale_ * inner_->compute(ctx, q, nullptr, nullptr);
    // The inner term adds into its own zeroed buffers (per thread: groups step in parallel).
    thread_local VecX g;
    thread_local MatX H;
    if (grad) g.setZero(grad->size());
    if (hess) H.setZero(hess->rows(), hess->cols());
    VecRef gv(g);
    MatRef Hv(H);
    const double e = inner_->compute(ctx, q, grad ? &gv : nullptr, hess ? &Hv : nullptr);
    if (grad) *grad += scale_ * g;
    if (hess) *hess += scale_ * H;
    return scale_ * e;
  }

 private:
  std::shared_ptr<const EnergyTerm> inner_;
  double scale_;
};

bool same_sample(const PoseSample& a, const PoseSample& b) {
  return a.position == b.position && a.orientation.coeffs() == b.orientation.coeffs() && a.closure == b.closure;
}

}  // namespace

struct SceneSession::Impl {
  SceneDescription sc;
  SceneSessionOptions opt;
  double h = 0, seconds = 0;
  long steps = 0, k = 0;  ///< total steps, steps done
  std::map<std::string, std::shared_ptr<const Avatar>> avatars;
  std::vector<SceneBody> bodies;
  std::vector<SceneObject> objects;
  std::vector<SceneTool> tools;
  std::unique_ptr<Simulator> sim;
  StepInputs in;
  StepReport report;
  std::vector<SceneToolEvent> events;
  std::shared_ptr<const Model> base_model;  ///< the scene's model at stiffness scale 1
  State initial;                            ///< the state at t = 0 (reset)
  std::vector<double> stiffness;            ///< per body (scene order): its stiffness scale

  void build();
  /// Puts the tools at their t = 0 device poses (coupled tools' bodies in `s`)
  /// and starts their recordings.
  void start_tools(State& s);
  /// A live device takes over tool `t` at time `t0`: from the tool's pose by a
  /// ramp when it has one (keyframes, pose file), else the tool is placed on
  /// the device's first pose (a coupled body with it, at rest).
  void take_over(SceneTool& t, double t0);
  /// Rebuilds the simulator's model from base_model with the stiffness
  /// scales (its elastic and damping terms wrapped), keeping the state.
  void apply_stiffness();
  Isometry object_pose(const SceneObject& o, double t) const {
    if (o.model_index < 0) return object_pose_at(*o.desc, t);
    return Isometry(sim->state(o.model_index).bones[0] * o.model.shape_in_body);
  }
};

void SceneSession::Impl::build() {
  require(!sc.bodies.empty(), sc.path, ": the scene has no bodies");
  h = sc.solver.dt;

  // Bodies: avatars (read once per file and material), motions, placement.
  bodies.resize(sc.bodies.size());
  seconds = sc.solver.seconds;
  for (size_t i = 0; i < sc.bodies.size(); ++i) {
    const BodyDescription& d = sc.bodies[i];
    SceneBody& b = bodies[i];
    b.desc = &d;
    const std::string key = d.avatar + "\n" + d.material;
    auto it = avatars.find(key);
    if (it == avatars.end()) {
      require(!d.default_avatar || d.avatar != kDefaultAvatar, sc.path, ": bodies '", d.name,
              "': avatar: default is not resolved (the sflsh commands build it; a program sets the body's "
              "avatar to cached_avatar(...).path, sflsh/precompute/cached_avatar.hpp)");
      auto a = std::make_shared<Avatar>(read_avatar(d.avatar));
      if (!d.material.empty()) apply_material_file(d.material, a->materials);
      it = avatars.emplace(key, std::move(a)).first;
    }
    b.avatar = it->second;
    b.placement.linear() = Eigen::AngleAxisd(d.heading_deg * M_PI / 180.0, Vec3::UnitY()).toRotationMatrix();
    b.placement.translation() = d.offset;
    if (d.motion != "none") {
      MotionOptions mo;
      mo.rest_joints = b.avatar->joints_rest;
      mo.builtin_seconds = seconds > 0 ? seconds : 5.0;
      try {
        b.motion = load_motion(d.motion, mo);
      } catch (const Error& e) {
        fail(sc.path, ": bodies '", d.name, "': motion ", d.motion, ": ", e.what());
      }
      b.has_motion = true;
      if (sc.solver.seconds == 0) seconds = std::max(seconds, b.motion.duration());
    }
  }
  require(seconds > 0, sc.path, ": solver.seconds is 0 and no body has a motion; give solver.seconds");
  steps = std::max(1L, long(std::llround(seconds / h)));
  // The model.
  ModelOptions mo;
  mo.h = h;
  mo.gravity = sc.solver.gravity;
  mo.newton.iterations = sc.solver.newton_iterations;
  mo.newton.line_search = sc.solver.line_search;
  mo.newton.iterations_after_damping = sc.solver.iterations_after_damping;
  mo.newton.nonlinearity_tolerance = sc.solver.nonlinearity_tolerance;
  ModelBuilder mb(mo);
  auto in_body_contact = [&](const BodyDescription& d) {
    for (const BodyDescription& other : sc.bodies)
      if (&other != &d && sc.collides(d.name, other.name)) return true;
    return false;
  };
  for (SceneBody& b : bodies) {
    b.model_index = mb.add_body({b.desc->name, b.avatar, b.desc->bones_dynamic});
    add_soft_tissue_terms(mb, b.model_index, {true, sc.solver.damping});
    if (b.desc->bones_dynamic) {
      SkeletonTermsOptions sk;
      sk.track_root = b.has_motion;
      if (in_body_contact(*b.desc))
        sk.root_force_limit = opt.body_push_limit * estimate_body_mass(*b.avatar) * mo.gravity.norm();
      add_skeleton_terms(mb, b.model_index, sk);
    }
  }
  objects.resize(sc.objects.size());
  for (size_t i = 0; i < sc.objects.size(); ++i) {
    SceneObject& o = objects[i];
    o.desc = &sc.objects[i];
    o.model = make_rigid_object(*o.desc);
    if (!o.model.bake_report.empty() && opt.progress) std::cerr << o.desc->name << ": " << o.model.bake_report << "\n";
    if (o.desc->kind == ObjectKind::Dynamic) {
      o.model_index = mb.add_body({o.desc->name, nullptr, true});
      add_rigid_body_terms(mb, o.model_index, o.model.mass.mass, o.model.mass.inertia);
    }
  }
  // Contact terms: only the pairs the scene asks for.
  const ContactDescription& c = sc.contact;
  std::map<const Avatar*, std::shared_ptr<const PosedPoints>> samples;
  for (const SceneBody& b : bodies) {
    for (const SceneObject& o : objects) {
      if (!sc.collides(b.desc->name, o.desc->name)) continue;
      auto& pts = samples[b.avatar.get()];
      if (!pts) pts = std::make_shared<const PosedPoints>(skin_contact_samples(*b.avatar, c.sample_spacing));
      const bool dynamic = o.model_index >= 0;
      if (c.patch) {
        require(!dynamic, sc.path, ": contact.patch: object '", o.desc->name,
                "' is dynamic; the contact patch takes static and kinematic objects (a dynamic one: "
                "remove contact.patch or make it kinematic)");
        ContactPatchOptions po;
        po.pressure_stiffness = c.pressure_stiffness;
        po.spacing = c.patch_spacing;
        po.patch_radius = c.patch_radius;
        auto term = std::make_shared<const ContactPatchTerm>(
            o.desc->name, *b.avatar, o.model.field, dynamic ? o.model.shape_in_body : Isometry::Identity(), dynamic, po);
        if (dynamic)
          mb.add_term(term, {b.model_index, o.model_index});
        else
          mb.add_term(term, {b.model_index});
        continue;
      }
      SdfContactOptions co;
      co.stiffness = c.body_object_stiffness;
      co.friction = c.friction;
      auto term = std::make_shared<const SdfContactTerm>(o.desc->name, *pts, o.model.field,
                                                         dynamic ? o.model.shape_in_body : Isometry::Identity(),
                                                         dynamic, co);
      if (dynamic) {
        mb.add_term(term, {b.model_index, o.model_index});
      } else {
        mb.add_term(term, {b.model_index});
      }
    }
  }
  // Tools: kinematic frames; contact with every body through their shape,
  // grasping through anchors (one anchor term per tool and body).
  tools.resize(sc.tools.size());
  for (size_t i = 0; i < sc.tools.size(); ++i) {
    SceneTool& t = tools[i];
    t.desc = &sc.tools[i];
    t.contact_term = "contact:" + t.desc->name;
    t.anchor_prefix = "anchor:" + t.desc->name + "@";
    try {
      if (!opt.replay_dir.empty()) {
        const std::string file = (std::filesystem::path(opt.replay_dir) / (t.desc->name + ".csv")).string();
        t.track = std::make_unique<PoseTrack>(teleop::read_pose_file(file), file);
        t.hold = true;
      } else {
        t.track = std::make_unique<PoseTrack>(tool_track(*t.desc));
        t.hold = t.desc->pose_file_hold;
      }
    } catch (const Error& e) {
      fail(sc.path, ": tools '", t.desc->name, "': ", e.what());
    }
    if (t.desc->stream_port >= 0 && opt.open_streams && opt.replay_dir.empty()) {
      teleop::PoseStreamServerOptions so;
      so.port = t.desc->stream_port;
      so.checks.max_speed = t.desc->stream_max_speed;
      const std::string tool_name = t.desc->name;
      so.log = [tool_name](const std::string& line) { std::cerr << "tool " << tool_name << ": " << line << "\n"; };
      try {
        t.link = std::make_unique<teleop::PoseStreamLink>(so);
      } catch (const Error& e) {
        fail(sc.path, ": tools '", t.desc->name, "': pose_stream: ", e.what());
      }
      if (opt.progress)
        std::cerr << "tool " << t.desc->name << ": listening for device poses on udp://127.0.0.1:" << t.link->port()
                  << "\n";
    }
    if (t.desc->coupled) {
      const ToolCouplingDescription& cd = t.desc->coupling;
      // The tool body: a solid sphere of radius 2 cm of the coupling's mass
      // about the tool frame's origin (only its dynamics use it).
      const double inertia = 0.4 * cd.mass * 0.02 * 0.02;
      t.model_index = mb.add_body({t.desc->name, nullptr, true});
      add_rigid_body_terms(mb, t.model_index, cd.mass, inertia * Mat3::Identity(), false);
      t.coupling.stiffness = cd.stiffness;
      t.coupling.rotational_stiffness = cd.rotational_stiffness;
      t.coupling.damping = cd.damping >= 0 ? cd.damping : 2.0 * std::sqrt(cd.stiffness * cd.mass);
      t.coupling.rotational_damping =
          cd.rotational_damping >= 0 ? cd.rotational_damping : 2.0 * std::sqrt(cd.rotational_stiffness * inertia);
      mb.add_term(std::make_shared<const VirtualCouplingTerm>(t.desc->name, t.coupling), {t.model_index});
    }
    const bool coupled = t.model_index >= 0;
    for (size_t j = 0; j < t.desc->jaws.size(); ++j) {
      RigidObjectDescription as_object;
      as_object.name = t.desc->name + "/jaw" + std::to_string(j);
      as_object.shape = t.desc->jaws[j].shape;
      as_object.kind = ObjectKind::Kinematic;
      SceneTool::Jaw jaw{as_object.name, make_rigid_object(as_object), Isometry::Identity(),
                         t.desc->jaws[j].side};
      jaw.offset.translation() = t.desc->jaws[j].offset;
      t.jaws.push_back(std::move(jaw));
    }
    if (t.desc->has_shape) {
      RigidObjectDescription as_object;
      as_object.name = t.desc->name;
      as_object.shape = t.desc->shape;
      as_object.kind = ObjectKind::Kinematic;
      t.shape = make_rigid_object(as_object);
    }
    for (const SceneBody& b : bodies) {
      // A shape of the tool (its own, or a jaw) touching body b: with contact.patch a kinematic
      // tool gets the face-sampled contact and its patch, like an object; a coupled (dynamic)
      // tool keeps the per-sample penalty.
      auto add_shape_contact = [&](const std::string& frame, const geometry::SdfPtr& field) {
        std::shared_ptr<const EnergyTerm> term;
        if (c.patch && !coupled) {
          ContactPatchOptions po;
          po.pressure_stiffness = c.pressure_stiffness;
          po.spacing = c.patch_spacing;
          po.patch_radius = c.patch_radius;
          term = std::make_shared<const ContactPatchTerm>(frame, *b.avatar, field, Isometry::Identity(), false, po);
        } else {
          auto& pts = samples[b.avatar.get()];
          if (!pts) pts = std::make_shared<const PosedPoints>(skin_contact_samples(*b.avatar, c.sample_spacing));
          SdfContactOptions co;
          co.stiffness = c.body_object_stiffness;
          co.friction = c.friction;
          term = std::make_shared<const SdfContactTerm>(frame, *pts, field, Isometry::Identity(), coupled, co);
        }
        if (coupled)
          mb.add_term(term, {b.model_index, t.model_index});
        else
          mb.add_term(term, {b.model_index});
      };
      if (t.desc->has_shape) add_shape_contact(t.desc->name, t.shape.field);
      for (const SceneTool::Jaw& jaw : t.jaws) add_shape_contact(jaw.name, jaw.model.field);
      if (!t.desc->sensors.empty()) {
        GraspOptions go;
        for (const ToolSensorDescription& sd : t.desc->sensors) go.sensors.push_back({sd.origin, sd.direction, sd.range});
        go.closure_threshold = t.desc->closure_threshold;
        t.grasps.emplace_back(go);
        t.anchor_keys.push_back(t.desc->name + "@" + b.desc->name);
        auto term = std::make_shared<const AnchorTerm>(t.anchor_keys.back(), PosedPoints::at_surface(*b.avatar),
                                                       coupled, AnchorOptions{t.desc->hardness, t.desc->damping});
        if (coupled) {
          mb.add_term(term, {b.model_index, t.model_index});
        } else {
          mb.add_term(term, {b.model_index});
        }
      }
    }
  }
  for (size_t i = 0; i < bodies.size(); ++i) {
    const SceneBody& a = bodies[i];
    for (size_t j = i + 1; j < bodies.size(); ++j) {
      const SceneBody& b = bodies[j];
      if (!sc.collides(a.desc->name, b.desc->name)) continue;
      if (!a.desc->bones_dynamic && !b.desc->bones_dynamic) continue;  // nothing can move
      require(!a.avatar->capsules.empty() && !b.avatar->capsules.empty(), sc.path, ": bodies '", a.desc->name,
              "' and '", b.desc->name, "' collide, but an avatar has no bone capsules (/skeleton/capsules)");
      mb.add_term(std::make_shared<const CapsuleContactTerm>(*a.avatar, b.avatar.get(),
                                                             CapsuleContactOptions{c.body_body_stiffness, 2}),
                  {a.model_index, b.model_index});
    }
    if (c.self_contact && a.desc->bones_dynamic && !a.avatar->capsules.empty())
      mb.add_term(std::make_shared<const CapsuleContactTerm>(*a.avatar, nullptr,
                                                             CapsuleContactOptions{c.self_stiffness, 2}),
                  {a.model_index});
  }
  sim = std::make_unique<Simulator>(mb.build());

  // Initial state.
  State s = sim->scene_state();
  for (const SceneBody& b : bodies) s.bodies[b.model_index] = initial_state(b, h);
  for (const SceneObject& o : objects) {
    if (o.model_index < 0) continue;
    const Isometry G = object_pose_at(*o.desc, 0.0) * o.model.shape_in_body.inverse();
    Isometry G_prev = G;
    G_prev.translation() -= o.desc->velocity * h;
    const double w = o.desc->angular_velocity.norm();
    if (w > 0)
      G_prev.linear() = Eigen::AngleAxisd(-w * h, o.desc->angular_velocity / w).toRotationMatrix() * G.linear();
    s.bodies[o.model_index] = {Configuration{{G}, VecX(0)}, Configuration{{G_prev}, VecX(0)}};
  }
  start_tools(s);
  sim->set_state(s);
  in.bodies.resize(sim->model().bodies().size());
  base_model = sim->model_ptr();
  initial = s;
  stiffness.assign(bodies.size(), 1.0);
  for (SceneTool& t : tools) t.grasps_at_start = t.grasps;
}

void SceneSession::Impl::take_over(SceneTool& t, double t0) {
  const bool has_pose = !t.desc->keyframes.empty() || !t.desc->pose_file.empty();
  const Isometry device = sample_pose(t.pushed);
  if (has_pose) {
    t.ramp = teleop::PoseRamp(t0, t.desc->stream_ramp_in, t.pose(*sim), device);
    return;
  }
  t.ramp = teleop::PoseRamp(t0, 0.0, device, device);
  t.device_now = t.pushed;
  if (t.model_index >= 0) {
    State s = sim->scene_state();
    s.bodies[size_t(t.model_index)] = {Configuration{{device}, VecX(0)}, Configuration{{device}, VecX(0)}};
    sim->set_state(s);
  }
}

void SceneSession::Impl::start_tools(State& s) {
  for (SceneTool& t : tools) {
    t.device_now = t.track->at(0.0, t.hold ? PoseInterpolation::kHold : PoseInterpolation::kLinear);
    t.state.device = t.device_now;
    t.state.pose = sample_pose(t.device_now);
    if (t.model_index >= 0)
      s.bodies[t.model_index] = {Configuration{{t.state.pose}, VecX(0)}, Configuration{{t.state.pose}, VecX(0)}};
    if (!opt.record_dir.empty()) {
      t.recorder = std::make_unique<teleop::PoseRecorder>(
          (std::filesystem::path(opt.record_dir) / (t.desc->name + ".csv")).string());
      t.recorder->record({0, t.device_now, 0.0});
      t.recorded = t.device_now;
    }
  }
}

void SceneSession::Impl::apply_stiffness() {
  const Model& base = *base_model;
  std::shared_ptr<const Model> model = base_model;
  if (std::any_of(stiffness.begin(), stiffness.end(), [](double s) { return s != 1.0; })) {
    std::vector<double> per_model_body(base.bodies().size(), 1.0);
    for (size_t i = 0; i < bodies.size(); ++i) per_model_body[size_t(bodies[i].model_index)] = stiffness[i];
    ModelBuilder mb(base.options());
    for (const Model::Body& b : base.bodies()) mb.add_body({b.name, b.avatar, b.bones_dynamic});
    for (const Model::BoundTerm& t : base.terms()) {
      const double scale = per_model_body[size_t(t.bodies[0])];
      const bool soft = dynamic_cast<const ElasticTerm*>(t.term.get()) || dynamic_cast<const DampingTerm*>(t.term.get());
      mb.add_term(soft && scale != 1.0 ? std::make_shared<const ScaledTerm>(t.term, scale) : t.term, t.bodies);
    }
    model = mb.build();
  }
  const State keep = sim->scene_state();
  *sim = Simulator(model);  // the same Simulator object: references to it stay valid
  sim->set_state(keep);
}

SceneSession::SceneSession(const SceneDescription& scene, const SceneSessionOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->sc = scene;
  impl_->opt = options;
  impl_->build();
}

SceneSession::~SceneSession() = default;

const SceneDescription& SceneSession::scene() const { return impl_->sc; }
double SceneSession::dt() const { return impl_->h; }
double SceneSession::time() const { return impl_->sim->time(); }
long SceneSession::steps_done() const { return impl_->k; }
double SceneSession::seconds() const { return impl_->seconds; }
long SceneSession::total_steps() const { return impl_->steps; }
const StepReport& SceneSession::last_report() const { return impl_->report; }

void SceneSession::end_feedback() {
  for (SceneTool& t : impl_->tools)
    if (t.link) t.link->end();
}

void SceneSession::reset() {
  Impl& m = *impl_;
  m.k = 0;
  m.report = StepReport{};
  m.events.clear();
  m.in = StepInputs{};
  m.in.bodies.resize(m.sim->model().bodies().size());
  for (SceneTool& t : m.tools) {
    t.grasps = t.grasps_at_start;
    t.live = false;
    t.pushed = PoseSample{};
    t.link_seen = false;
    t.link_sequence = 0;
    t.ramp = teleop::PoseRamp();
    t.state = SceneToolState{};
    t.recorded = PoseSample{};
    t.recorder.reset();  // drops the rows so far (before start_tools opens the file again)
  }
  State s = m.initial;
  m.start_tools(s);
  m.sim->set_state(s);  // a copy: fresh term caches, as in a new session
}

void SceneSession::set_stiffness_scale(double scale, int body) {
  Impl& m = *impl_;
  require(std::isfinite(scale) && scale > 0, "stiffness scale ", scale, ": expected a finite value > 0");
  require(body >= -1 && body < int(m.bodies.size()), "stiffness scale: body ", body, ", expected -1 (all) or 0..",
          int(m.bodies.size()) - 1);
  if (body < 0)
    std::fill(m.stiffness.begin(), m.stiffness.end(), scale);
  else
    m.stiffness[size_t(body)] = scale;
  m.apply_stiffness();
}

double SceneSession::stiffness_scale(int body) const { return impl_->stiffness.at(size_t(body)); }
const Simulator& SceneSession::simulator() const { return *impl_->sim; }
const std::vector<SceneToolEvent>& SceneSession::tool_events() const { return impl_->events; }

const StepReport& SceneSession::advance() {
  Impl& m = *impl_;
  Simulator& sim = *m.sim;
  const double h = m.h;
  const long k = m.k;
  const double t = (k + 1) * h;
  StepInputs& in = m.in;
  for (const SceneBody& b : m.bodies) {
    BodyTargets& bt = in.bodies[b.model_index];
    bt.pose = placed_pose(b, t);
    bt.bones = target_bones(*b.avatar, bt.pose);
  }
  for (const SceneObject& o : m.objects) {
    if (o.model_index >= 0) continue;
    in.frames[o.desc->name] = frame_between(object_pose_at(*o.desc, t - h), object_pose_at(*o.desc, t), h);
  }
  for (SceneTool& tl : m.tools) {
    if (tl.link) {
      // The newest good sample of the live stream (held when none came).
      if (const auto got = tl.link->latest(); got && (!tl.link_seen || got->sequence != tl.link_sequence)) {
        tl.link_seen = true;
        tl.link_sequence = got->sequence;
        tl.pushed = got->sample;
        tl.live = true;
      }
    }
    if (tl.live && !tl.ramp.started()) m.take_over(tl, t - h);
    // The device at t (the grasp looks from there) and at t + h (where the
    // step takes the tool). Keyframes and pose files are interpolated at both
    // times; live and recorded devices step from the pose held at t.
    const bool linear = !tl.live && !tl.hold;
    const PoseSample now = linear ? tl.track->at(t - h) : tl.device_now;
    const PoseSample next = tl.live ? tl.ramp.apply(tl.pushed, t)
                                    : linear ? tl.track->at(t) : tl.track->at(t, PoseInterpolation::kHold);
    const WorldFrame f = frame_between(sample_pose(now), sample_pose(next), h);
    const bool coupled = tl.model_index >= 0;
    in.frames[coupled ? device_frame_name(tl.desc->name) : tl.desc->name] = f;
    // Where the jaws are at t: the coupled body, or the device.
    WorldFrame jaws = f;
    if (coupled) jaws = WorldFrame{sim.state(tl.model_index).bones[0]};
    const Isometry before = coupled ? jaws.pose : sample_pose(now);
    for (const SceneTool::Jaw& jaw : tl.jaws) {
      if (coupled) {
        in.frames[moving_shape_frame_name(jaw.name)] = WorldFrame{before * tl.jaw_in_tool(jaw, next.closure)};
      } else {
        in.frames[jaw.name] = frame_between(before * tl.jaw_in_tool(jaw, now.closure),
                                            sample_pose(next) * tl.jaw_in_tool(jaw, next.closure), h);
      }
    }
    for (size_t bi = 0; bi < tl.grasps.size(); ++bi) {
      GraspController& grasp = tl.grasps[bi];
      const SceneBody& b = m.bodies[bi];
      // The posed skin only while the jaws look for something to grasp.
      const Points skin = grasp.seeking(now.closure) ? sim.posed_surface(b.model_index) : Points();
      if (grasp.update(t - h, before, now.closure, skin, b.avatar->surface_faces)) {
        const GraspEvent& ev = grasp.log().back();
        m.events.push_back({ev.time, tl.desc->name, b.desc->name,
                            ev.kind == GraspEvent::Kind::Grasp ? "grasp" : "release", int(ev.points.size())});
      }
      add_anchor_frames(tl.anchor_keys[bi], jaws, grasp.anchors(), coupled, in.frames);
    }
    if (tl.recorder && !same_sample(next, tl.recorded)) {
      tl.recorder->record({0, next, t});
      tl.recorded = next;
    }
    tl.device_now = next;
    tl.state.device = tl.live ? tl.pushed : next;  // the device's own sample (next may be ramped)
  }
  m.report = sim.step(in);
  m.k = k + 1;
  const StepReport& rep = m.report;
  // Stops on NaN/Inf, naming the step, the term and the body (sim/finite_guard.hpp).
  require_finite_step(sim.model(), sim.scene_state(), rep, k + 1, m.sc.path.empty() ? "scene" : m.sc.path);
  // Tool feedback: the force on each tool is minus what its contact and
  // anchor terms exert on the bodies.
  for (SceneTool& tl : m.tools) {
    SceneToolState& ts = tl.state;
    ts.force.setZero();
    ts.torque.setZero();
    ts.anchors = 0;
    ts.max_stretch = 0;
    for (const TermQuantityReport& q : rep.quantities) {
      const bool contact = q.term == tl.contact_term || q.term.rfind(tl.contact_term + "/jaw", 0) == 0;
      const bool anchor = q.term.rfind(tl.anchor_prefix, 0) == 0;
      if ((contact || anchor) && q.name == "force" && q.value.size() == 3)
        ts.force -= Vec3(q.value[0], q.value[1], q.value[2]);
      if (anchor && q.name == "anchor_points") ts.anchors += int(q.value.size());
      if (anchor && q.name == "max_stretch") ts.max_stretch = std::max(ts.max_stretch, q.value[0]);
    }
    ts.live = tl.live;
    ts.pose = tl.pose(sim);
    if (tl.model_index >= 0) {
      // The device feels the coupling's pull, opposite to its force on the tool.
      const std::string name = "coupling:" + tl.desc->name;
      for (const TermQuantityReport& q : rep.quantities) {
        if (q.term != name) continue;
        if (q.name == "force") ts.feedback_force = -Vec3(q.value[0], q.value[1], q.value[2]);
        if (q.name == "torque") ts.feedback_torque = -Vec3(q.value[0], q.value[1], q.value[2]);
      }
    } else {
      ts.feedback_force = ts.force;
      ts.feedback_torque = ts.torque;
    }
    const ToolCouplingDescription& cd = tl.desc->coupling;
    ts.feedback_force *= cd.haptic_gain;
    ts.feedback_torque *= cd.haptic_gain;
    if (ts.feedback_force.norm() > cd.max_force) ts.feedback_force *= cd.max_force / ts.feedback_force.norm();
    ts.ramping_in = tl.ramp.active(t);
    if (tl.link)
      tl.link->publish(ts.feedback_force, ts.feedback_torque, t,
                       ts.ramping_in ? teleop::FeedbackStatus::kRampIn : teleop::FeedbackStatus::kRunning);
  }
  for (const SceneBody& b : m.bodies)
    if (!sim.state(b.model_index).z.allFinite() || !sim.state(b.model_index).bones[0].matrix().allFinite())
      fail(m.sc.path, ": body '", b.desc->name, "' became non-finite at step ", k + 1, " (t = ", t,
           " s); try a smaller solver.dt or lower contact stiffness");
  for (const SceneObject& o : m.objects)
    if (o.model_index >= 0 && !sim.state(o.model_index).bones[0].matrix().allFinite())
      fail(m.sc.path, ": object '", o.desc->name, "' became non-finite at step ", k + 1, " (t = ", t, " s)");
  for (const SceneTool& tl : m.tools)
    if (!tl.state.pose.matrix().allFinite())
      fail(m.sc.path, ": tool '", tl.desc->name, "' became non-finite at step ", k + 1, " (t = ", t, " s)");
  return rep;
}

int SceneSession::num_bodies() const { return int(impl_->bodies.size()); }
const std::string& SceneSession::body_name(int body) const { return impl_->bodies.at(body).desc->name; }
const Avatar& SceneSession::avatar(int body) const { return *impl_->bodies.at(body).avatar; }
int SceneSession::body_model_index(int body) const { return impl_->bodies.at(body).model_index; }
Points SceneSession::body_surface(int body) const { return impl_->sim->posed_surface(body_model_index(body)); }
Points SceneSession::body_displacement(int body) const {
  return impl_->sim->soft_displacement(body_model_index(body));
}
Points SceneSession::body_joints(int body) const { return impl_->sim->joints(body_model_index(body)); }
BodyPose SceneSession::body_target_pose(int body, double t) const { return placed_pose(impl_->bodies.at(body), t); }

int SceneSession::num_tools() const { return int(impl_->tools.size()); }
const std::string& SceneSession::tool_name(int tool) const { return impl_->tools.at(tool).desc->name; }
int SceneSession::tool_index(const std::string& name) const {
  std::string known;
  for (size_t i = 0; i < impl_->tools.size(); ++i) {
    if (impl_->tools[i].desc->name == name) return int(i);
    known += (known.empty() ? "" : ", ") + impl_->tools[i].desc->name;
  }
  fail(impl_->sc.path, ": no tool named '", name, "' (tools: ", known.empty() ? "none" : known, ")");
}
const SceneToolState& SceneSession::tool_state(int tool) const { return impl_->tools.at(tool).state; }

void SceneSession::set_device_pose(int tool, const PoseSample& sample) {
  SceneTool& t = impl_->tools.at(tool);
  require(sample.position.allFinite() && sample.orientation.coeffs().allFinite() && std::isfinite(sample.closure),
          "tool '", t.desc->name, "': device pose is not finite");
  require(sample.orientation.norm() > 1e-6, "tool '", t.desc->name, "': device orientation is a zero quaternion");
  t.pushed = sample;
  t.pushed.orientation.normalize();
  t.live = true;
}

int SceneSession::stream_port(int tool) const {
  const SceneTool& t = impl_->tools.at(tool);
  return t.link ? t.link->port() : 0;
}

std::string SceneSession::stream_counters(int tool) const {
  const SceneTool& t = impl_->tools.at(tool);
  if (!t.link) return "";
  return t.link->counters().describe() + ", feedback sent " + std::to_string(t.link->feedback_sent());
}

std::vector<std::string> SceneSession::finish_recording() {
  std::vector<std::string> paths;
  for (SceneTool& t : impl_->tools)
    if (t.recorder) {
      t.recorder->finish();
      paths.push_back(t.recorder->path());
      t.recorder.reset();
    }
  return paths;
}

SimulationResult SceneSession::result_header() const {
  const Impl& m = *impl_;
  SimulationResult r;
  r.motion = m.sc.path.empty() ? std::string("scene") : motion_spec_name(m.sc.path);
  r.dt = m.h;
  r.bones_dynamic = m.bodies[0].desc->bones_dynamic;
  r.newton_iters = m.sc.solver.newton_iterations;
  r.body_vertex_offsets.push_back(0);
  std::string names;
  int V = 0, F = 0;
  for (const SceneBody& b : m.bodies) {
    V += int(b.avatar->surface_rest.rows());
    F += int(b.avatar->surface_faces.rows());
  }
  r.surface_rest.resize(V, 3);
  r.faces.resize(F, 3);
  V = F = 0;
  for (const SceneBody& b : m.bodies) {
    r.surface_rest.middleRows(V, b.avatar->surface_rest.rows()) = b.avatar->surface_rest;
    r.faces.middleRows(F, b.avatar->surface_faces.rows()) = b.avatar->surface_faces.array() + V;
    V += int(b.avatar->surface_rest.rows());
    F += int(b.avatar->surface_faces.rows());
    r.body_names.push_back(b.desc->name);
    r.body_vertex_offsets.push_back(V);
    names += (names.empty() ? "" : ", ") + b.desc->name + " (" + motion_spec_name(b.desc->avatar) + ")";
  }
  r.avatar = names;
  for (const SceneObject& o : m.objects)
    r.objects.push_back({o.desc->name, shape_type_name(o.desc->shape.type), object_kind_name(o.desc->kind),
                         o.model.surface.vertices, o.model.surface.faces, {}});
  for (const SceneTool& t : m.tools)
    if (t.desc->has_shape)
      r.objects.push_back({t.desc->name, shape_type_name(t.desc->shape.type),
                           t.model_index >= 0 ? "dynamic" : "kinematic", t.shape.surface.vertices,
                           t.shape.surface.faces, {}});
  for (const SceneTool& t : m.tools)
    for (size_t j = 0; j < t.jaws.size(); ++j)
      r.objects.push_back({t.jaws[j].name, shape_type_name(t.desc->jaws[j].shape.type),
                           t.model_index >= 0 ? "dynamic" : "kinematic", t.jaws[j].model.surface.vertices,
                           t.jaws[j].model.surface.faces, {}});
  return r;
}

std::vector<Isometry> SceneSession::object_poses() const {
  const Impl& m = *impl_;
  const double t = m.sim->time();
  std::vector<Isometry> poses;
  for (const SceneObject& o : m.objects) poses.push_back(m.object_pose(o, t));
  for (const SceneTool& tl : m.tools)
    if (tl.desc->has_shape) poses.push_back(tl.exact_pose() ? tl.state.pose : sample_pose(tl.track->at(t)));
  for (const SceneTool& tl : m.tools)
    for (const SceneTool::Jaw& j : tl.jaws) poses.push_back(tl.state.pose * tl.jaw_in_tool(j, tl.state.device.closure));
  return poses;
}

void SceneSession::record_frame(SimulationResult& r, double ms) const {
  const Impl& m = *impl_;
  const Simulator& sim = *m.sim;
  const double t = m.k * m.h;
  const int V = r.body_vertex_offsets.back();
  Points positions(V, 3), displacement(V, 3), joints(24 * int(m.bodies.size()), 3);
  VecX reduced(0);
  for (size_t i = 0; i < m.bodies.size(); ++i) {
    const int v0 = r.body_vertex_offsets[i], n = r.body_vertex_offsets[i + 1] - v0, k = m.bodies[i].model_index;
    positions.middleRows(v0, n) = sim.posed_surface(k);
    displacement.middleRows(v0, n) = sim.soft_displacement(k);
    // The contact patches' dents (unposed), carried to the world by the skin's blend of bone rotations.
    const Avatar& a = *m.bodies[i].avatar;
    const Points dent = patch_surface_displacement(a, m.report, k);
    for (int v = 0; v < n; ++v) {
      if (dent.row(v).isZero()) continue;
      const Mat3 A = skinning_rotation_blend(a.surface_weights.row(v), sim.state(k).bones);
      displacement.row(v0 + v) += dent.row(v);
      positions.row(v0 + v) += (A * dent.row(v).transpose()).transpose();
    }
    joints.middleRows(24 * int(i), 24) = sim.joints(k);
    const VecX& z = sim.state(k).z;
    VecX grown(reduced.size() + z.size());
    grown << reduced, z;
    reduced = std::move(grown);
  }
  const SceneBody& b0 = m.bodies[0];
  r.frame_time.push_back(t);
  r.frame_step_ms.push_back(ms);
  r.frame_positions.push_back(std::move(positions));
  r.frame_displacement.push_back(std::move(displacement));
  r.frame_joints.push_back(std::move(joints));
  r.frame_reduced.push_back(std::move(reduced));
  r.frame_target_pelvis.push_back(placed_pose(b0, t).translation + b0.avatar->joints_rest.row(0).transpose());
  for (size_t i = 0; i < m.objects.size(); ++i) r.objects[i].poses.push_back(m.object_pose(m.objects[i], t));
  size_t next = m.objects.size();
  for (const SceneTool& tl : m.tools)
    if (tl.desc->has_shape) r.objects[next++].poses.push_back(tl.exact_pose() ? tl.state.pose : sample_pose(tl.track->at(t)));
  for (const SceneTool& tl : m.tools)
    for (const SceneTool::Jaw& j : tl.jaws)
      r.objects[next++].poses.push_back(tl.state.pose * tl.jaw_in_tool(j, tl.state.device.closure));
  ++r.num_frames;
}

}  // namespace sflsh
