// Shapes and the `objects:` section of a scene file (static, kinematic on keyframes, dynamic with mass).
#include "scene/scene_yaml_reader.hpp"

namespace sflsh {
namespace {

const std::vector<std::pair<ShapeType, const char*>> kShapeNames = {
    {ShapeType::Plane, "plane"},     {ShapeType::Sphere, "sphere"},     {ShapeType::Box, "box"},
    {ShapeType::Capsule, "capsule"}, {ShapeType::Cylinder, "cylinder"}, {ShapeType::Mesh, "mesh"}};
const std::vector<std::pair<ObjectKind, const char*>> kKindNames = {
    {ObjectKind::Static, "static"}, {ObjectKind::Kinematic, "kinematic"}, {ObjectKind::Dynamic, "dynamic"}};

}  // namespace

const char* shape_type_name(ShapeType type) {
  for (const auto& [t, name] : kShapeNames)
    if (t == type) return name;
  return "?";
}

const char* object_kind_name(ObjectKind kind) {
  for (const auto& [k, name] : kKindNames)
    if (k == kind) return name;
  return "?";
}

namespace scene_yaml {
namespace {

Keyframe parse_keyframe(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  p.check_map(n, key, {"time", "position", "orientation"}, "a keyframe");
  Keyframe f;
  f.time = p.non_negative(p.required(n, key, "time"), SceneParser::child_key(key, "time"));
  f.position = p.vec3(p.required(n, key, "position"), SceneParser::child_key(key, "position"));
  if (const auto v = n["orientation"]) f.orientation = p.quaternion(v, SceneParser::child_key(key, "orientation"));
  return f;
}

}  // namespace

ShapeDescription parse_shape(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  if (!n.IsMap()) p.error(n, key, "expected a map with 'type' and the shape's parameters");
  ShapeDescription s;
  s.location = p.where(n) + ": " + key;
  const std::string tk = SceneParser::child_key(key, "type");
  const YAML::Node tn = p.required(n, key, "type");
  const std::string type = p.text(tn, tk);
  const auto it = std::find_if(kShapeNames.begin(), kShapeNames.end(), [&](const auto& e) { return type == e.second; });
  if (it == kShapeNames.end()) p.error(tn, tk, "unknown shape '", type, "' (expected plane, sphere, box, capsule, cylinder or mesh)");
  s.type = it->first;
  auto k = [&](const char* child) { return SceneParser::child_key(key, child); };
  const std::string what = "a " + type + " shape";
  switch (s.type) {
    case ShapeType::Plane:
      p.check_map(n, key, {"type", "normal"}, what);
      if (const auto v = n["normal"]) {
        s.normal = p.vec3(v, k("normal"));
        if (s.normal.norm() == 0) p.error(v, k("normal"), "must be a non-zero vector");
        s.normal = unit(s.normal);
      }
      break;
    case ShapeType::Sphere:
      p.check_map(n, key, {"type", "radius"}, what);
      s.radius = p.positive(p.required(n, key, "radius"), k("radius"));
      break;
    case ShapeType::Box: {
      p.check_map(n, key, {"type", "size"}, what);
      const YAML::Node v = p.required(n, key, "size");
      s.size = p.vec3(v, k("size"));
      for (int a = 0; a < 3; ++a)
        if (s.size[a] <= 0) p.error(v, SceneParser::item_key(k("size"), a), "must be > 0, got ", s.size[a]);
      break;
    }
    case ShapeType::Capsule:
    case ShapeType::Cylinder:
      p.check_map(n, key, {"type", "radius", "length"}, what);
      s.radius = p.positive(p.required(n, key, "radius"), k("radius"));
      s.length = s.type == ShapeType::Capsule ? p.non_negative(p.required(n, key, "length"), k("length"))
                                              : p.positive(p.required(n, key, "length"), k("length"));
      break;
    case ShapeType::Mesh:
      p.check_map(n, key, {"type", "file", "scale", "voxel_size", "padding", "band"}, what);
      s.mesh_file = p.existing_file(p.required(n, key, "file"), k("file"), "mesh file");
      if (const auto v = n["scale"]) s.mesh_scale = p.positive(v, k("scale"));
      if (const auto v = n["voxel_size"]) s.voxel_size = p.positive(v, k("voxel_size"));
      if (const auto v = n["padding"]) s.padding = p.non_negative(v, k("padding"));
      if (const auto v = n["band"]) s.band = p.non_negative(v, k("band"));
      break;
  }
  return s;
}

RigidObjectDescription parse_object(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  if (!n.IsMap()) p.error(n, key, "expected a map (a rigid object)");
  RigidObjectDescription o;
  auto k = [&](const char* child) { return SceneParser::child_key(key, child); };
  if (const auto v = n["kind"]) {
    const std::string s = p.text(v, k("kind"));
    const auto it = std::find_if(kKindNames.begin(), kKindNames.end(), [&](const auto& e) { return s == e.second; });
    if (it == kKindNames.end()) p.error(v, k("kind"), "expected static, kinematic or dynamic, got '", s, "'");
    o.kind = it->first;
  }
  switch (o.kind) {
    case ObjectKind::Static:
      p.check_map(n, key, {"name", "shape", "kind", "position", "orientation"}, "a static object");
      break;
    case ObjectKind::Kinematic:
      p.check_map(n, key, {"name", "shape", "kind", "keyframes"}, "a kinematic object (its pose comes from keyframes)");
      break;
    case ObjectKind::Dynamic:
      p.check_map(n, key,
                  {"name", "shape", "kind", "position", "orientation", "density", "mass", "velocity", "angular_velocity"},
                  "a dynamic object");
      break;
  }
  o.name = p.text(p.required(n, key, "name"), k("name"));
  o.shape = parse_shape(p, p.required(n, key, "shape"), k("shape"));
  if (const auto v = n["position"]) o.position = p.vec3(v, k("position"));
  if (const auto v = n["orientation"]) o.orientation = p.quaternion(v, k("orientation"));
  if (o.kind == ObjectKind::Kinematic) {
    const YAML::Node kf = p.required(n, key, "keyframes");
    if (!kf.IsSequence() || kf.size() == 0) p.error(kf, k("keyframes"), "expected a list of at least one keyframe");
    for (std::size_t i = 0; i < kf.size(); ++i) {
      o.keyframes.push_back(parse_keyframe(p, kf[i], SceneParser::item_key(k("keyframes"), i)));
      if (i > 0 && o.keyframes[i].time <= o.keyframes[i - 1].time)
        p.error(kf[i], SceneParser::item_key(k("keyframes"), i) + ".time", "keyframe times must increase, got ",
                o.keyframes[i].time, " after ", o.keyframes[i - 1].time);
    }
    o.position = o.keyframes.front().position;
    o.orientation = o.keyframes.front().orientation;
  }
  if (o.kind == ObjectKind::Dynamic) {
    if (o.shape.type == ShapeType::Plane) p.error(n["kind"], k("kind"), "a plane cannot be dynamic (it has no finite mass)");
    const YAML::Node d = n["density"], m = n["mass"];
    if (bool(d) == bool(m)) p.error(n, key, "a dynamic object needs exactly one of 'density' (kg/m^3) or 'mass' (kg)");
    if (d) o.density = p.positive(d, k("density"));
    if (m) o.mass = p.positive(m, k("mass"));
    if (const auto v = n["velocity"]) o.velocity = p.vec3(v, k("velocity"));
    if (const auto v = n["angular_velocity"]) o.angular_velocity = p.vec3(v, k("angular_velocity"));
  }
  return o;
}

}  // namespace scene_yaml
}  // namespace sflsh
