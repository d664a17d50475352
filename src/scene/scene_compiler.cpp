#include "sflsh/scene/scene_compiler.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/material_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/energies/capsule_contact.hpp"
#include "sflsh/sim/energies/skin_contact.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/damping.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/sim/rigid_body_terms.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/energies/scaled_term.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"

namespace sflsh {
namespace {

/// Skin contact samples per avatar, made on first use and shared by its contact terms.
using SkinSamples = std::map<const Avatar*, std::shared_ptr<const PosedPoints>>;

/// The bodies: avatars (read once per file and material), motions, placement.
/// Sets `seconds` (solver.seconds, or the longest motion when it is 0).
std::vector<CompiledBody> compile_bodies(const SceneDescription& sc, double& seconds) {
  std::map<std::string, std::shared_ptr<const Avatar>> avatars;
  std::vector<CompiledBody> bodies(sc.bodies.size());
  seconds = sc.solver.seconds;
  for (size_t i = 0; i < sc.bodies.size(); ++i) {
    const BodyDescription& d = sc.bodies[i];
    CompiledBody& b = bodies[i];
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
  return bodies;
}

ModelOptions model_options(const SolverDescription& s) {
  ModelOptions mo;
  mo.h = s.dt;
  mo.gravity = s.gravity;
  mo.newton.iterations = s.newton_iterations;
  mo.newton.line_search = s.line_search;
  mo.newton.iterations_after_damping = s.iterations_after_damping;
  mo.newton.nonlinearity_tolerance = s.nonlinearity_tolerance;
  return mo;
}

/// Adds the bodies with their soft-tissue and (dynamic bones) skeleton terms.
/// Bodies that collide with another body track their motion's root with a
/// force limit so that contact, not the motion, decides where they meet.
void add_bodies(ModelBuilder& mb, std::vector<CompiledBody>& bodies, const SceneDescription& sc,
                const SceneCompileOptions& opt) {
  auto in_body_contact = [&](const BodyDescription& d) {
    for (const BodyDescription& other : sc.bodies)
      if (&other != &d && sc.collides(d.name, other.name)) return true;
    return false;
  };
  for (CompiledBody& b : bodies) {
    b.model_index = mb.add_body({b.desc->name, b.avatar, b.desc->bones_dynamic});
    add_soft_tissue_terms(mb, b.model_index, {true, sc.solver.damping});
    if (b.desc->bones_dynamic) {
      SkeletonTermsOptions sk;
      sk.track_root = b.has_motion;
      if (in_body_contact(*b.desc))
        sk.root_force_limit = opt.body_push_limit * estimate_body_mass(*b.avatar) * mb.options().gravity.norm();
      add_skeleton_terms(mb, b.model_index, sk);
    }
  }
}

/// Adds the rigid objects (dynamic ones as 6-DoF bodies with their mass).
std::vector<CompiledObject> add_objects(ModelBuilder& mb, const SceneDescription& sc, const SceneCompileOptions& opt) {
  std::vector<CompiledObject> objects(sc.objects.size());
  for (size_t i = 0; i < sc.objects.size(); ++i) {
    CompiledObject& o = objects[i];
    o.desc = &sc.objects[i];
    o.model = make_rigid_object(*o.desc);
    if (!o.model.bake_report.empty() && opt.progress) std::cerr << o.desc->name << ": " << o.model.bake_report << "\n";
    if (o.desc->kind == ObjectKind::Dynamic) {
      o.model_index = mb.add_body({o.desc->name, nullptr, true});
      add_rigid_body_terms(mb, o.model_index, o.model.mass.mass, o.model.mass.inertia);
    } else {
      o.frame = mb.add_frame(o.desc->name);
    }
  }
  return objects;
}

/// The scene's contact.patch settings as the patch term's options.
ContactPatchOptions patch_options(const ContactDescription& c) {
  ContactPatchOptions po;
  po.pressure_stiffness = c.pressure_stiffness;
  po.spacing = c.patch_spacing;
  po.patch_radius = c.patch_radius;
  po.max_patch_nodes = c.max_patch_nodes;
  po.friction = c.friction;
  return po;
}

/// A rigid shape touching body `b`: with `patch` the face-sampled contact and
/// its pressure patch, else the per-skin-sample penalty with friction. The
/// shape is the world frame `frame` (static or kinematic) or, `dynamic`, the
/// rigid body `shape_body` of the model with the shape at `shape_in_body`.
/// Returns the term's model index.
int add_shape_contact(ModelBuilder& mb, const CompiledBody& b, const std::string& frame,
                       const geometry::SdfPtr& field, const Isometry& shape_in_body, bool dynamic, int shape_body,
                       bool patch, const ContactDescription& c, SkinSamples& samples) {
  std::shared_ptr<const EnergyTerm> term;
  if (patch) {
    term = std::make_shared<const ContactPatchTerm>(frame, *b.avatar, field, shape_in_body, dynamic, patch_options(c));
  } else {
    auto& pts = samples[b.avatar.get()];
    if (!pts) pts = std::make_shared<const PosedPoints>(skin_contact_samples(*b.avatar, c.sample_spacing));
    SdfContactOptions co;
    co.stiffness = c.body_object_stiffness;
    co.friction = c.friction;
    term = std::make_shared<const SdfContactTerm>(frame, *pts, field, shape_in_body, dynamic, co);
  }
  if (dynamic) return mb.add_term(term, {b.model_index, shape_body});
  return mb.add_term(term, {b.model_index});
}

/// Adds one contact term per colliding body–object pair; appends their model indices to `terms`.
void add_object_contacts(ModelBuilder& mb, const std::vector<CompiledBody>& bodies,
                         const std::vector<CompiledObject>& objects, const SceneDescription& sc, SkinSamples& samples,
                         std::vector<int>& terms) {
  const ContactDescription& c = sc.contact;
  for (const CompiledBody& b : bodies)
    for (const CompiledObject& o : objects) {
      if (!sc.collides(b.desc->name, o.desc->name)) continue;
      const bool dynamic = o.model_index >= 0;
      terms.push_back(add_shape_contact(mb, b, o.desc->name, o.model.field,
                                        dynamic ? o.model.shape_in_body : Isometry::Identity(), dynamic, o.model_index,
                                        c.patch, c, samples));
    }
}

/// The shape of a tool (its own or a jaw's) as a kinematic object called `name`.
RigidObjectModel tool_shape(const std::string& name, const ShapeDescription& shape) {
  RigidObjectDescription as_object;
  as_object.name = name;
  as_object.shape = shape;
  as_object.kind = ObjectKind::Kinematic;
  return make_rigid_object(as_object);
}

/// Adds a tool: with `coupling` a rigid body pulled by a virtual coupling;
/// contact with every body through its shape and jaws (with contact.patch the
/// face-sampled contact and its patch, a coupled tool's bound to its body,
/// the jaws through their moving shape frames); with sensors one anchor term
/// per body for grasping (with contact.patch, the anchors join the patch of
/// the tool's shape, or get their own: one patch under the tool, whose
/// displacement the shape and the anchors share).
/// Records the tool's input ids and the terms that act on it.
CompiledTool add_tool(ModelBuilder& mb, const ToolDescription& d, const std::vector<CompiledBody>& bodies,
                      const ContactDescription& c, SkinSamples& samples) {
  CompiledTool t;
  t.desc = &d;
  if (d.coupled) {
    const ToolCouplingDescription& cd = d.coupling;
    // The tool body: a solid sphere of radius 2 cm of the coupling's mass
    // about the tool frame's origin (only its dynamics use it).
    const double inertia = 0.4 * cd.mass * 0.02 * 0.02;
    t.model_index = mb.add_body({d.name, nullptr, true});
    add_rigid_body_terms(mb, t.model_index, cd.mass, inertia * Mat3::Identity(), false);
    t.coupling.stiffness = cd.stiffness;
    t.coupling.rotational_stiffness = cd.rotational_stiffness;
    t.coupling.damping = cd.damping >= 0 ? cd.damping : 2.0 * std::sqrt(cd.stiffness * cd.mass);
    t.coupling.rotational_damping =
        cd.rotational_damping >= 0 ? cd.rotational_damping : 2.0 * std::sqrt(cd.rotational_stiffness * inertia);
    t.coupling_term = mb.add_term(std::make_shared<const VirtualCouplingTerm>(d.name, t.coupling), {t.model_index});
  }
  const bool coupled = t.coupled();
  t.frame = mb.add_frame(coupled ? device_frame_name(d.name) : d.name);
  for (size_t j = 0; j < d.jaws.size(); ++j) {
    CompiledJaw jaw{d.name + "/jaw" + std::to_string(j), {}, Isometry::Identity(), d.jaws[j].side, {}};
    jaw.model = tool_shape(jaw.name, d.jaws[j].shape);
    jaw.offset.translation() = d.jaws[j].offset;
    jaw.frame = mb.add_frame(coupled ? moving_shape_frame_name(jaw.name) : jaw.name);
    t.jaws.push_back(std::move(jaw));
  }
  if (d.has_shape) t.shape = tool_shape(d.name, d.shape);
  for (const ToolSensorDescription& sd : d.sensors) t.grasp.sensors.push_back({sd.origin, sd.direction, sd.range});
  t.grasp.closure_threshold = d.closure_threshold;
  for (const CompiledBody& b : bodies) {
    const std::string anchor_set = d.name + "@" + b.desc->name;
    const AnchorOptions anchor_options{d.hardness, d.damping};
    const bool grasps = !d.sensors.empty();
    // The shape shares the anchors' patch, with contact.patch and a grasp.
    const bool shape_in_patch = c.patch && grasps && d.has_shape;
    if (c.patch && grasps) {
      // The anchors' patch (a coupled tool's body bound second).
      auto term = std::make_shared<const ContactPatchTerm>(d.name, *b.avatar, shape_in_patch ? t.shape.field : nullptr,
                                                           Isometry::Identity(), coupled, patch_options(c),
                                                           PatchAnchors{anchor_set, anchor_options});
      const int index = coupled ? mb.add_term(term, {b.model_index, t.model_index}) : mb.add_term(term, {b.model_index});
      t.anchor_terms.push_back(index);
      if (shape_in_patch) t.contact_terms.push_back(index);
      t.anchor_sets.push_back(mb.add_anchor_set(anchor_set));
    }
    if (d.has_shape && !shape_in_patch)
      t.contact_terms.push_back(add_shape_contact(mb, b, d.name, t.shape.field, Isometry::Identity(), coupled,
                                                  t.model_index, c.patch, c, samples));
    for (const CompiledJaw& jaw : t.jaws)
      t.contact_terms.push_back(add_shape_contact(mb, b, jaw.name, jaw.model.field, Isometry::Identity(), coupled,
                                                  t.model_index, c.patch, c, samples));
    if (!grasps || c.patch) continue;
    auto term = std::make_shared<const AnchorTerm>(anchor_set, PosedPoints::at_surface(*b.avatar), coupled,
                                                   anchor_options);
    t.anchor_terms.push_back(coupled ? mb.add_term(term, {b.model_index, t.model_index})
                                     : mb.add_term(term, {b.model_index}));
    t.anchor_sets.push_back(mb.add_anchor_set(anchor_set));
  }
  return t;
}

/// Adds one capsule contact term per colliding pair of bodies (skipped when
/// both are kinematic) and one per body with self contact; appends their
/// model indices to `terms`.
void add_body_contacts(ModelBuilder& mb, const std::vector<CompiledBody>& bodies, const SceneDescription& sc,
                       std::vector<int>& terms) {
  const ContactDescription& c = sc.contact;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const CompiledBody& a = bodies[i];
    for (size_t j = i + 1; j < bodies.size(); ++j) {
      const CompiledBody& b = bodies[j];
      if (!sc.collides(a.desc->name, b.desc->name)) continue;
      if (!a.desc->bones_dynamic && !b.desc->bones_dynamic) continue;  // nothing can move
      require(!a.avatar->capsules.empty() && !b.avatar->capsules.empty(), sc.path, ": bodies '", a.desc->name,
              "' and '", b.desc->name, "' collide, but an avatar has no bone capsules (/skeleton/capsules)");
      const bool skin = c.body_model == ContactDescription::BodyModel::Skin;
      if (skin) {
        SkinContactOptions so;
        so.pressure_stiffness = c.body_pressure_stiffness;
        so.spacing = c.body_spacing;
        terms.push_back(mb.add_term(std::make_shared<const SkinContactTerm>(*a.avatar, *b.avatar, so),
                                    {a.model_index, b.model_index}));
      }
      terms.push_back(mb.add_term(std::make_shared<const CapsuleContactTerm>(
                      *a.avatar, b.avatar.get(), CapsuleContactOptions{c.body_body_stiffness, 2, skin ? c.core_radius : 1.0}),
                  {a.model_index, b.model_index}));
    }
    if (c.self_contact && a.desc->bones_dynamic && !a.avatar->capsules.empty())
      terms.push_back(mb.add_term(std::make_shared<const CapsuleContactTerm>(*a.avatar, nullptr,
                                                                             CapsuleContactOptions{c.self_stiffness, 2}),
                                  {a.model_index}));
  }
}

/// Marks each body's elastic and damping terms (what a stiffness scale multiplies).
void mark_stiffness_terms(const Model& model, std::vector<CompiledBody>& bodies) {
  for (CompiledBody& b : bodies) {
    const EnergyTerm* elastic = model.find_term<ElasticTerm>(b.model_index);
    const EnergyTerm* damping = model.find_term<DampingTerm>(b.model_index);
    for (size_t i = 0; i < model.terms().size(); ++i) {
      const EnergyTerm* t = model.terms()[i].term.get();
      if (t && (t == elastic || t == damping)) b.stiffness_terms.push_back(int(i));
    }
  }
}

/// The state at t = 0: bodies at their placed motion, dynamic objects at their
/// pose moving with their velocity and angular velocity.
State initial_state(const Model& model, const CompiledScene& cs) {
  State s = rest_state(model);
  for (const CompiledBody& b : cs.bodies) s.bodies[b.model_index] = b.initial_state(cs.h);
  for (const CompiledObject& o : cs.objects) {
    if (o.model_index < 0) continue;
    const Isometry G = object_pose_at(*o.desc, 0.0) * o.model.shape_in_body.inverse();
    Isometry G_prev = G;
    G_prev.translation() -= o.desc->velocity * cs.h;
    const double w = o.desc->angular_velocity.norm();
    if (w > 0)
      G_prev.linear() = Eigen::AngleAxisd(-w * cs.h, o.desc->angular_velocity / w).toRotationMatrix() * G.linear();
    s.bodies[o.model_index] = {Configuration{{G}, VecX(0)}, Configuration{{G_prev}, VecX(0)}};
  }
  return s;
}

}  // namespace

Isometry CompiledBody::placement_at(double t) const {
  Isometry P = placement;
  if (has_motion) P.translation() += desc->velocity * t;
  return P;
}

BodyPose CompiledBody::target_pose(double t) const {
  BodyPose pose = has_motion ? motion.sample(t) : BodyPose{};
  if (!placed) return pose;
  const Isometry P = placement_at(t);
  const Vec3 root = avatar->joints_rest.row(0).transpose();
  pose.axis_angle.row(0) = rotation_log(P.linear() * rodrigues(pose.axis_angle.row(0).transpose())).transpose();
  pose.translation = P * (root + pose.translation) - root;
  return pose;
}

BodyState CompiledBody::initial_state(double h) const {
  BodyState s;
  s.q.bones = target_bones(*avatar, target_pose(0.0));
  s.q.z = VecX::Zero(avatar->num_reduced());
  s.q_prev.z = s.q.z;
  if (start_at_rest) {
    s.q_prev.bones = s.q.bones;
  } else if (has_motion) {
    s.q_prev.bones = bones_one_step_before(s.q.bones, target_bones(*avatar, target_pose(h)));
  } else {
    s.q_prev.bones = s.q.bones;
    for (Isometry& prev : s.q_prev.bones) prev.translation() -= desc->velocity * h;
  }
  return s;
}

Isometry CompiledTool::jaw_in_tool(const CompiledJaw& j, double closure) const {
  Isometry H = Isometry::Identity();
  H.translation() = desc->hinge_origin;
  Isometry R = Isometry::Identity();
  R.linear() = Eigen::AngleAxisd(j.side * 0.5 * closure, desc->hinge_axis).toRotationMatrix();
  return H * R * H.inverse() * j.offset;
}

CompiledScene compile_scene(const SceneDescription& sc, const SceneCompileOptions& opt) {
  require(!sc.bodies.empty(), sc.path, ": the scene has no bodies");
  CompiledScene cs;
  cs.name = sc.path.empty() ? std::string("scene") : sc.path;
  cs.h = sc.solver.dt;
  cs.bodies = compile_bodies(sc, cs.seconds);
  require(cs.seconds > 0, sc.path, ": solver.seconds is 0 and no body has a motion; give solver.seconds");
  cs.steps = std::max(1L, long(std::llround(cs.seconds / cs.h)));
  ModelBuilder mb(model_options(sc.solver));
  add_bodies(mb, cs.bodies, sc, opt);
  cs.objects = add_objects(mb, sc, opt);
  SkinSamples samples;
  add_object_contacts(mb, cs.bodies, cs.objects, sc, samples, cs.contact_terms);
  for (const ToolDescription& d : sc.tools) {
    cs.tools.push_back(add_tool(mb, d, cs.bodies, sc.contact, samples));
    cs.contact_terms.insert(cs.contact_terms.end(), cs.tools.back().contact_terms.begin(),
                            cs.tools.back().contact_terms.end());
  }
  add_body_contacts(mb, cs.bodies, sc, cs.contact_terms);
  cs.model = mb.build();
  mark_stiffness_terms(*cs.model, cs.bodies);
  cs.initial = initial_state(*cs.model, cs);
  return cs;
}

CompiledScene compile_avatar_motion(const SceneDescription& sc, std::shared_ptr<const Avatar> avatar,
                                    const MotionClip& motion, const SimulatorOptions& sim,
                                    const SkeletonTermsOptions& skeleton, bool start_at_rest) {
  require(sc.bodies.size() == 1, "compile_avatar_motion: ", sc.bodies.size(), " bodies, expected 1");
  CompiledScene cs;
  cs.name = motion.name;
  cs.one_avatar = true;
  cs.h = sim.h;
  cs.seconds = sc.solver.seconds > 0 ? sc.solver.seconds : motion.duration();
  cs.steps = std::max(1L, long(std::llround(cs.seconds / cs.h)));
  CompiledBody b;
  b.desc = &sc.bodies[0];
  b.avatar = avatar;
  b.has_motion = true;
  b.motion = motion;
  b.placed = false;
  b.start_at_rest = start_at_rest;
  cs.bodies.push_back(std::move(b));
  cs.model = avatar_model(std::move(avatar), sim, sim.bones_dynamic ? &skeleton : nullptr, sc.bodies[0].name);
  mark_stiffness_terms(*cs.model, cs.bodies);
  cs.initial = initial_state(*cs.model, cs);
  return cs;
}

std::shared_ptr<const Model> model_with_stiffness(const std::shared_ptr<const Model>& base,
                                                  const std::vector<CompiledBody>& bodies,
                                                  const std::vector<double>& scales) {
  if (std::all_of(scales.begin(), scales.end(), [](double s) { return s == 1.0; })) return base;
  std::vector<double> term_scale(base->terms().size(), 1.0);
  for (size_t i = 0; i < bodies.size(); ++i)
    for (int t : bodies[i].stiffness_terms) term_scale[size_t(t)] = scales[i];
  ModelBuilder mb(base->options());
  for (const Model::Body& b : base->bodies()) mb.add_body({b.name, b.avatar, b.bones_dynamic});
  // The same input ids: frames and anchor sets first, in their order.
  for (const std::string& f : base->frame_names()) mb.add_frame(f);
  for (const std::string& a : base->anchor_set_names()) mb.add_anchor_set(a);
  for (size_t i = 0; i < base->terms().size(); ++i) {
    const Model::BoundTerm& t = base->terms()[i];
    const double s = term_scale[i];
    mb.add_term(s != 1.0 ? std::make_shared<const ScaledTerm>(t.term, s) : t.term, t.bodies);
  }
  return mb.build();
}

}  // namespace sflsh
