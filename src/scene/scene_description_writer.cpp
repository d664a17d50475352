// Writing a SceneDescription back as YAML that reads back to the same description.
#include "sflsh/scene/scene_description.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <fstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh {
namespace {

/// The shortest decimal that reads back as exactly x (YAML numbers without
/// the 17-digit noise of 0.80000000000000004).
std::string num(double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

void emit_vec(YAML::Emitter& e, const std::vector<double>& v) {
  e << YAML::Flow << YAML::BeginSeq;
  for (double x : v) e << num(x);
  e << YAML::EndSeq;
}
void emit(YAML::Emitter& e, const Vec3& v) { emit_vec(e, {v.x(), v.y(), v.z()}); }
void emit(YAML::Emitter& e, const Eigen::Quaterniond& q) { emit_vec(e, {q.w(), q.x(), q.y(), q.z()}); }

void emit_shape(YAML::Emitter& e, const ShapeDescription& s) {
  e << YAML::BeginMap << YAML::Key << "type" << YAML::Value << shape_type_name(s.type);
  switch (s.type) {
    case ShapeType::Plane:
      e << YAML::Key << "normal" << YAML::Value;
      emit(e, s.normal);
      break;
    case ShapeType::Sphere:
      e << YAML::Key << "radius" << YAML::Value << num(s.radius);
      break;
    case ShapeType::Box:
      e << YAML::Key << "size" << YAML::Value;
      emit(e, s.size);
      break;
    case ShapeType::Capsule:
    case ShapeType::Cylinder:
      e << YAML::Key << "radius" << YAML::Value << num(s.radius) << YAML::Key << "length" << YAML::Value << num(s.length);
      break;
    case ShapeType::Mesh:
      e << YAML::Key << "file" << YAML::Value << s.mesh_file << YAML::Key << "scale" << YAML::Value << s.mesh_scale
        << YAML::Key << "voxel_size" << YAML::Value << num(s.voxel_size) << YAML::Key << "padding" << YAML::Value << s.padding
        << YAML::Key << "band" << YAML::Value << num(s.band);
      break;
  }
  e << YAML::EndMap;
}

void emit_pose(YAML::Emitter& e, const Vec3& position, const Eigen::Quaterniond& orientation) {
  e << YAML::Key << "position" << YAML::Value;
  emit(e, position);
  e << YAML::Key << "orientation" << YAML::Value;
  emit(e, orientation);
}

void emit_object(YAML::Emitter& e, const RigidObjectDescription& o) {
  e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << o.name << YAML::Key << "shape" << YAML::Value;
  emit_shape(e, o.shape);
  e << YAML::Key << "kind" << YAML::Value << object_kind_name(o.kind);
  if (o.kind == ObjectKind::Kinematic) {
    e << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
    for (const auto& f : o.keyframes) {
      e << YAML::Flow << YAML::BeginMap << YAML::Key << "time" << YAML::Value << num(f.time);
      emit_pose(e, f.position, f.orientation);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  } else {
    emit_pose(e, o.position, o.orientation);
  }
  if (o.kind == ObjectKind::Dynamic) {
    if (o.mass > 0)
      e << YAML::Key << "mass" << YAML::Value << num(o.mass);
    else
      e << YAML::Key << "density" << YAML::Value << num(o.density);
    e << YAML::Key << "velocity" << YAML::Value;
    emit(e, o.velocity);
    e << YAML::Key << "angular_velocity" << YAML::Value;
    emit(e, o.angular_velocity);
  }
  e << YAML::EndMap;
}

}  // namespace

void emit_tool(YAML::Emitter& e, const ToolDescription& t) {
  e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << t.name;
  if (t.has_shape) {
    e << YAML::Key << "shape" << YAML::Value;
    emit_shape(e, t.shape);
  }
  if (t.stream_port >= 0) {
    e << YAML::Key << "pose_stream" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "port"
      << YAML::Value << t.stream_port << YAML::Key << "max_speed" << YAML::Value << num(t.stream_max_speed)
      << YAML::Key << "ramp_in" << YAML::Value << num(t.stream_ramp_in) << YAML::EndMap;
  }
  if (!t.pose_file.empty()) {
    e << YAML::Key << "pose_file" << YAML::Value << t.pose_file;
    e << YAML::Key << "pose_interpolation" << YAML::Value << (t.pose_file_hold ? "hold" : "linear");
  } else if (!t.keyframes.empty()) {
    e << YAML::Key << "keyframes" << YAML::Value << YAML::BeginSeq;
    for (const auto& f : t.keyframes) {
      e << YAML::Flow << YAML::BeginMap << YAML::Key << "time" << YAML::Value << num(f.time);
      emit_pose(e, f.position, f.orientation);
      e << YAML::Key << "closure" << YAML::Value << num(f.closure) << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  if (t.coupled) {
    const ToolCouplingDescription& c = t.coupling;
    auto damping = [&](double v) { return v < 0 ? std::string("auto") : num(v); };
    e << YAML::Key << "coupling" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "stiffness"
      << YAML::Value << num(c.stiffness) << YAML::Key << "damping" << YAML::Value << damping(c.damping) << YAML::Key
      << "rotational_stiffness" << YAML::Value << num(c.rotational_stiffness) << YAML::Key << "rotational_damping"
      << YAML::Value << damping(c.rotational_damping) << YAML::Key << "mass" << YAML::Value << num(c.mass)
      << YAML::Key << "max_force" << YAML::Value << num(c.max_force) << YAML::Key << "haptic_gain" << YAML::Value
      << num(c.haptic_gain) << YAML::EndMap;
  }
  if (!t.jaws.empty()) {
    e << YAML::Key << "gripper" << YAML::Value << YAML::BeginMap << YAML::Key << "hinge" << YAML::Value << YAML::Flow
      << YAML::BeginMap << YAML::Key << "origin" << YAML::Value;
    emit(e, t.hinge_origin);
    e << YAML::Key << "axis" << YAML::Value;
    emit(e, t.hinge_axis);
    e << YAML::EndMap << YAML::Key << "jaws" << YAML::Value << YAML::BeginSeq;
    for (const ToolJawDescription& j : t.jaws) {
      e << YAML::BeginMap << YAML::Key << "shape" << YAML::Value;
      emit_shape(e, j.shape);
      e << YAML::Key << "offset" << YAML::Value;
      emit(e, j.offset);
      e << YAML::Key << "side" << YAML::Value << num(j.side) << YAML::EndMap;
    }
    e << YAML::EndSeq << YAML::EndMap;
  }
  if (!t.sensors.empty()) {
    e << YAML::Key << "grasp" << YAML::Value << YAML::BeginMap << YAML::Key << "sensors" << YAML::Value << YAML::BeginSeq;
    for (const auto& sd : t.sensors) {
      e << YAML::Flow << YAML::BeginMap << YAML::Key << "origin" << YAML::Value;
      emit(e, sd.origin);
      e << YAML::Key << "direction" << YAML::Value;
      emit(e, sd.direction);
      e << YAML::Key << "range" << YAML::Value << num(sd.range) << YAML::EndMap;
    }
    e << YAML::EndSeq << YAML::Key << "closure_threshold" << YAML::Value << num(t.closure_threshold) << YAML::Key
      << "hardness" << YAML::Value << num(t.hardness) << YAML::Key << "damping" << YAML::Value << num(t.damping)
      << YAML::EndMap;
  }
  e << YAML::EndMap;
}

std::string scene_description_yaml(const SceneDescription& scene) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  const auto& s = scene.solver;
  e << YAML::Key << "solver" << YAML::Value << YAML::BeginMap << YAML::Key << "dt" << YAML::Value << num(s.dt) << YAML::Key
    << "seconds" << YAML::Value << num(s.seconds) << YAML::Key << "newton_iters" << YAML::Value << s.newton_iterations
    << YAML::Key << "iterations_after_damping" << YAML::Value << s.iterations_after_damping
    << YAML::Key << "line_search" << YAML::Value << s.line_search << YAML::Key << "nonlinearity_tolerance"
    << YAML::Value << (s.nonlinearity_tolerance ? num(*s.nonlinearity_tolerance) : std::string("auto")) << YAML::Key
    << "gravity" << YAML::Value;
  emit(e, s.gravity);
  e << YAML::Key << "damping" << YAML::Value << num(s.damping) << YAML::EndMap;

  const auto& o = scene.output;
  e << YAML::Key << "output" << YAML::Value << YAML::BeginMap << YAML::Key << "out" << YAML::Value << o.out;
  if (!o.export_path.empty()) e << YAML::Key << "export" << YAML::Value << o.export_path;
  if (!o.render.empty()) e << YAML::Key << "render" << YAML::Value << o.render;
  e << YAML::Key << "render_frames" << YAML::Value << o.render_frames << YAML::Key << "fps" << YAML::Value << num(o.fps)
    << YAML::EndMap;

  const auto& c = scene.contact;
  e << YAML::Key << "contact" << YAML::Value << YAML::BeginMap << YAML::Key << "stiffness" << YAML::Value
    << YAML::BeginMap << YAML::Key << "body_object" << YAML::Value << num(c.body_object_stiffness) << YAML::Key
    << "body_body" << YAML::Value << num(c.body_body_stiffness) << YAML::Key << "self" << YAML::Value << num(c.self_stiffness)
    << YAML::EndMap << YAML::Key << "friction" << YAML::Value << num(c.friction) << YAML::Key << "self_contact"
    << YAML::Value << c.self_contact << YAML::Key << "sample_spacing"
    << YAML::Value << num(c.sample_spacing);
  if (c.patch)
    e << YAML::Key << "patch" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "radius" << YAML::Value
      << num(c.patch_radius) << YAML::Key << "max_nodes" << YAML::Value << c.max_patch_nodes
      << YAML::Key << "pressure_stiffness" << YAML::Value << num(c.pressure_stiffness)
      << YAML::Key << "spacing" << YAML::Value << num(c.patch_spacing) << YAML::EndMap;
  e << YAML::Key << "bodies" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "model" << YAML::Value
    << (c.body_model == ContactDescription::BodyModel::Skin ? "skin" : "capsules") << YAML::Key << "pressure_stiffness"
    << YAML::Value << num(c.body_pressure_stiffness) << YAML::Key << "spacing" << YAML::Value << num(c.body_spacing)
    << YAML::Key << "core_radius" << YAML::Value << num(c.core_radius) << YAML::EndMap;
  e << YAML::Key << "pairs" << YAML::Value;
  if (c.all_pairs) {
    e << "all";
  } else {
    e << YAML::BeginSeq;
    for (const auto& [a, b] : c.pairs) e << YAML::Flow << YAML::BeginSeq << a << b << YAML::EndSeq;
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;

  e << YAML::Key << "bodies" << YAML::Value << YAML::BeginSeq;
  for (const auto& b : scene.bodies) {
    e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << b.name << YAML::Key << "avatar" << YAML::Value
      << (b.default_avatar ? std::string(kDefaultAvatar) : b.avatar);
    if (b.betas.size() > 0) {
      e << YAML::Key << "betas" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (Eigen::Index i = 0; i < b.betas.size(); ++i) e << num(b.betas[i]);
      e << YAML::EndSeq;
    }
    e << YAML::Key << "motion" << YAML::Value << b.motion << YAML::Key << "placement" << YAML::Value << YAML::BeginMap
      << YAML::Key << "offset" << YAML::Value;
    emit(e, b.offset);
    e << YAML::Key << "heading_deg" << YAML::Value << num(b.heading_deg) << YAML::EndMap << YAML::Key << "bones" << YAML::Value
      << (b.bones_dynamic ? "dynamic" : "kinematic");
    if (!b.material.empty()) e << YAML::Key << "material" << YAML::Value << b.material;
    e << YAML::Key << "velocity" << YAML::Value;
    emit(e, b.velocity);
    e << YAML::EndMap;
  }
  e << YAML::EndSeq;
  if (!scene.objects.empty()) {
    e << YAML::Key << "objects" << YAML::Value << YAML::BeginSeq;
    for (const auto& obj : scene.objects) emit_object(e, obj);
    e << YAML::EndSeq;
  }
  if (!scene.tools.empty()) {
    e << YAML::Key << "tools" << YAML::Value << YAML::BeginSeq;
    for (const auto& t : scene.tools) emit_tool(e, t);
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;
  require(e.good(), "scene YAML: ", e.GetLastError());
  return std::string(e.c_str()) + "\n";
}

void write_scene_description(const SceneDescription& scene, const std::string& path) {
  const std::string text = scene_description_yaml(scene);
  io::write_text_file(path, [&](std::ostream& f) {
    f << text;
  });
}

}  // namespace sflsh
