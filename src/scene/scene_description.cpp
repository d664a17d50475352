#include "sflsh/scene/scene_description.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>
#include <set>

#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/motion/builtin_motions.hpp"

namespace sflsh {
namespace fs = std::filesystem;

namespace {

const std::vector<std::pair<ShapeType, const char*>> kShapeNames = {
    {ShapeType::Plane, "plane"},     {ShapeType::Sphere, "sphere"},     {ShapeType::Box, "box"},
    {ShapeType::Capsule, "capsule"}, {ShapeType::Cylinder, "cylinder"}, {ShapeType::Mesh, "mesh"}};
const std::vector<std::pair<ObjectKind, const char*>> kKindNames = {
    {ObjectKind::Static, "static"}, {ObjectKind::Kinematic, "kinematic"}, {ObjectKind::Dynamic, "dynamic"}};

/// v scaled to unit length; left as is when it already is (to the last bits),
/// so that written and re-read unit vectors stay bit-identical.
template <class V>
V unit(const V& v) {
  return std::abs(v.norm() - 1) <= 4 * std::numeric_limits<double>::epsilon() ? v : V(v.normalized());
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

/// Reads YAML nodes of one file, failing with "FILE:LINE: KEY.PATH: message".
class SceneParser {
 public:
  SceneParser(std::string file, fs::path folder) : file_(std::move(file)), folder_(std::move(folder)) {}

  const std::string& file() const { return file_; }

  /// "FILE:LINE" of a node (the line of its first character).
  std::string where(const YAML::Node& n) const {
    return n.Mark().is_null() ? file_ : file_ + ":" + std::to_string(n.Mark().line + 1);
  }

  template <class... A>
  [[noreturn]] void error(const YAML::Node& n, const std::string& key, const A&... msg) const {
    fail(where(n), ": ", key.empty() ? std::string("(top level)") : key, ": ", msg...);
  }

  static std::string child_key(const std::string& key, const std::string& child) {
    return key.empty() ? child : key + "." + child;
  }
  static std::string item_key(const std::string& key, std::size_t i) { return key + "[" + std::to_string(i) + "]"; }

  /// `n` is a map whose keys are all in `allowed` (`what` says what it describes).
  void check_map(const YAML::Node& n, const std::string& key, const std::vector<std::string>& allowed,
                 const std::string& what) const {
    if (!n.IsMap()) error(n, key, "expected a map (", what, ")");
    for (const auto& kv : n) {
      if (!kv.first.IsScalar()) error(kv.first, key, "expected a plain name as key, got a list or map");
      const std::string k = kv.first.Scalar();
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
        error(kv.first, child_key(key, k), "unknown key '", k, "' for ", what, " (expected: ", join(allowed), ")");
    }
  }

  /// map[child], which must be present.
  YAML::Node required(const YAML::Node& map, const std::string& key, const std::string& child) const {
    const YAML::Node c = map[child];
    if (!c) error(map, child_key(key, child), "missing required key '", child, "'");
    return c;
  }

  std::string text(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) error(n, key, "expected a string");
    return n.Scalar();
  }

  /// A scalar converted by yaml-cpp to T; `what` names the expected type ("a number").
  template <class T>
  T convert(const YAML::Node& n, const std::string& key, const char* what) const {
    if (!n.IsScalar()) error(n, key, "expected ", what);
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      error(n, key, "expected ", what, ", got '", n.Scalar(), "'");
    }
  }
  double number(const YAML::Node& n, const std::string& key) const {
    const double v = convert<double>(n, key, "a number");
    if (!std::isfinite(v)) error(n, key, "must be finite, got ", n.Scalar());
    return v;
  }
  double positive(const YAML::Node& n, const std::string& key) const {
    const double v = number(n, key);
    if (v <= 0) error(n, key, "must be > 0, got ", v);
    return v;
  }
  double non_negative(const YAML::Node& n, const std::string& key) const {
    const double v = number(n, key);
    if (v < 0) error(n, key, "must be >= 0, got ", v);
    return v;
  }
  int integer(const YAML::Node& n, const std::string& key, int lo, int hi) const {
    const int v = convert<int>(n, key, "an integer");
    if (v < lo || v > hi) error(n, key, "must be in [", lo, ", ", hi, "], got ", v);
    return v;
  }
  bool boolean(const YAML::Node& n, const std::string& key) const { return convert<bool>(n, key, "true or false"); }
  /// A list of exactly `count` numbers.
  std::vector<double> numbers(const YAML::Node& n, const std::string& key, std::size_t count) const {
    if (!n.IsSequence() || n.size() != count) error(n, key, "expected a list of ", count, " numbers");
    std::vector<double> v;
    for (std::size_t i = 0; i < count; ++i) v.push_back(number(n[i], item_key(key, i)));
    return v;
  }
  Vec3 vec3(const YAML::Node& n, const std::string& key) const {
    const auto v = numbers(n, key, 3);
    return Vec3(v[0], v[1], v[2]);
  }
  /// [w, x, y, z], unit within 1e-3 (normalized exactly).
  Eigen::Quaterniond quaternion(const YAML::Node& n, const std::string& key) const {
    const auto v = numbers(n, key, 4);
    Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (std::abs(q.norm() - 1) > 1e-3)
      error(n, key, "expected a unit quaternion [w, x, y, z], got norm ", q.norm());
    return unit(q);
  }
  /// A file path relative to the scene's folder (or absolute) that exists.
  std::string existing_file(const YAML::Node& n, const std::string& key, const std::string& what,
                            const std::string& hint = "") const {
    const std::string given = text(n, key);
    if (given.empty()) error(n, key, "expected a file name");
    const fs::path p = fs::path(given).is_absolute() ? fs::path(given) : folder_ / given;
    // The error_code overloads: a name the OS refuses (too long, ...) is "not
    // found" with the scene's position, not a filesystem_error (fuzz finding).
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) error(n, key, what, " not found: ", p.string(), hint);
    const fs::path full = fs::absolute(p, ec);
    if (ec) error(n, key, what, " has a path the system refuses: ", p.string(), " (", ec.message(), ")");
    return full.lexically_normal().string();
  }

 private:
  std::string file_;
  fs::path folder_;
};

// --- sections -----------------------------------------------------------------

BodyDescription parse_body(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  p.check_map(n, key, {"name", "avatar", "betas", "motion", "placement", "bones", "material", "velocity"}, "a body");
  BodyDescription b;
  b.name = p.text(p.required(n, key, "name"), SceneParser::child_key(key, "name"));
  const YAML::Node av = p.required(n, key, "avatar");
  if (av.IsScalar() && av.Scalar() == kDefaultAvatar) {
    b.avatar = kDefaultAvatar;  // the built-in body, built on first use (precompute/cached_avatar.hpp)
    b.default_avatar = true;
  } else {
    b.avatar = p.existing_file(av, SceneParser::child_key(key, "avatar"), "avatar file",
                               " (make it with `sflsh precompute --out FILE`, or write avatar: default)");
  }
  if (const auto v = n["betas"]) {
    const std::string k = SceneParser::child_key(key, "betas");
    if (!b.default_avatar) p.error(v, k, "betas apply to avatar: default only (an avatar file has its shape)");
    if (!v.IsSequence() || v.size() == 0 || v.size() > kMaxDefaultAvatarBetas)
      p.error(v, k, "expected a list of 1 to ", kMaxDefaultAvatarBetas, " numbers");
    const std::vector<double> betas = p.numbers(v, k, v.size());
    b.betas = Eigen::Map<const VecX>(betas.data(), Eigen::Index(betas.size()));
  }
  if (const auto m = n["motion"]) {
    const std::string k = SceneParser::child_key(key, "motion");
    b.motion = p.text(m, k);
    if (b.motion.rfind("builtin:", 0) == 0) {
      const auto names = builtin_motion_names();
      if (std::find(names.begin(), names.end(), b.motion.substr(8)) == names.end())
        p.error(m, k, "unknown built-in motion '", b.motion, "' (built-ins: ", join(names), ")");
    } else if (b.motion != "none") {
      b.motion = p.existing_file(m, k, "motion file", " (expected none, builtin:NAME or a motion file)");
    }
  }
  if (const auto pl = n["placement"]) {
    const std::string k = SceneParser::child_key(key, "placement");
    p.check_map(pl, k, {"offset", "heading_deg"}, "a placement");
    if (const auto v = pl["offset"]) b.offset = p.vec3(v, k + ".offset");
    if (const auto v = pl["heading_deg"]) b.heading_deg = p.number(v, k + ".heading_deg");
  }
  if (const auto v = n["bones"]) {
    const std::string s = p.text(v, SceneParser::child_key(key, "bones"));
    if (s != "dynamic" && s != "kinematic")
      p.error(v, SceneParser::child_key(key, "bones"), "expected dynamic or kinematic, got '", s, "'");
    b.bones_dynamic = s == "dynamic";
  }
  if (const auto v = n["material"]) b.material = p.existing_file(v, SceneParser::child_key(key, "material"), "material file");
  if (const auto v = n["velocity"]) b.velocity = p.vec3(v, SceneParser::child_key(key, "velocity"));
  return b;
}

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

Keyframe parse_keyframe(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  p.check_map(n, key, {"time", "position", "orientation"}, "a keyframe");
  Keyframe f;
  f.time = p.non_negative(p.required(n, key, "time"), SceneParser::child_key(key, "time"));
  f.position = p.vec3(p.required(n, key, "position"), SceneParser::child_key(key, "position"));
  if (const auto v = n["orientation"]) f.orientation = p.quaternion(v, SceneParser::child_key(key, "orientation"));
  return f;
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

ToolDescription parse_tool(const SceneParser& p, const YAML::Node& n, const std::string& key) {
  p.check_map(n, key, {"name", "shape", "keyframes", "pose_file", "pose_interpolation", "pose_stream", "coupling", "gripper",
               "grasp"},
              "a tool");
  auto k = [&](const std::string& c) { return SceneParser::child_key(key, c); };
  ToolDescription t;
  t.name = p.text(p.required(n, key, "name"), k("name"));
  if (const auto s = n["shape"]) {
    t.shape = parse_shape(p, s, k("shape"));
    t.has_shape = true;
  }
  const YAML::Node kf = n["keyframes"], file = n["pose_file"], stream = n["pose_stream"];
  if (stream) {
    if (file) p.error(file, k("pose_file"), "give one pose source: 'pose_stream' or 'pose_file', not both");
    const std::string sk = k("pose_stream");
    p.check_map(stream, sk, {"port", "max_speed", "ramp_in"}, "a pose stream");
    const double port = p.non_negative(p.required(stream, sk, "port"), sk + ".port");
    if (port != std::floor(port) || port > 65535)
      p.error(stream["port"], sk + ".port", "expected a UDP port number 0..65535 (0: any free port), got ", port);
    t.stream_port = int(port);
    if (const auto v = stream["max_speed"]) t.stream_max_speed = p.positive(v, sk + ".max_speed");
    if (const auto v = stream["ramp_in"]) t.stream_ramp_in = p.non_negative(v, sk + ".ramp_in");
  } else if (bool(kf) == bool(file)) {
    p.error(n, key, "give exactly one pose source: 'keyframes', 'pose_file' or 'pose_stream'");
  }
  if (file) t.pose_file = p.existing_file(file, k("pose_file"), "pose file");
  if (const auto v = n["pose_interpolation"]) {
    const std::string mode = p.text(v, k("pose_interpolation"));
    if (!file) p.error(v, k("pose_interpolation"), "applies to a pose_file only");
    if (mode != "linear" && mode != "hold")
      p.error(v, k("pose_interpolation"), "expected 'linear' or 'hold', got '", mode, "'");
    t.pose_file_hold = mode == "hold";
  }
  if (const auto cn = n["coupling"]) {
    const std::string ck = k("coupling");
    p.check_map(cn, ck,
                {"stiffness", "damping", "rotational_stiffness", "rotational_damping", "mass", "max_force",
                 "haptic_gain"},
                "a virtual coupling");
    ToolCouplingDescription& c = t.coupling;
    auto damping = [&](const char* name, double& out) {
      if (const auto v = cn[name]) {
        if (v.IsScalar() && v.Scalar() == "auto")
          out = -1;
        else
          out = p.non_negative(v, ck + "." + name);
      }
    };
    if (const auto v = cn["stiffness"]) c.stiffness = p.positive(v, ck + ".stiffness");
    if (const auto v = cn["rotational_stiffness"]) c.rotational_stiffness = p.positive(v, ck + ".rotational_stiffness");
    damping("damping", c.damping);
    damping("rotational_damping", c.rotational_damping);
    if (const auto v = cn["mass"]) c.mass = p.positive(v, ck + ".mass");
    if (const auto v = cn["max_force"]) c.max_force = p.positive(v, ck + ".max_force");
    if (const auto v = cn["haptic_gain"]) c.haptic_gain = p.non_negative(v, ck + ".haptic_gain");
    t.coupled = true;
  }
  if (kf) {
    if (!kf.IsSequence() || kf.size() == 0) p.error(kf, k("keyframes"), "expected a list of at least one keyframe");
    for (std::size_t i = 0; i < kf.size(); ++i) {
      const std::string ik = SceneParser::item_key(k("keyframes"), i);
      p.check_map(kf[i], ik, {"time", "position", "orientation", "closure"}, "a tool keyframe");
      ToolKeyframe f;
      f.time = p.non_negative(p.required(kf[i], ik, "time"), ik + ".time");
      f.position = p.vec3(p.required(kf[i], ik, "position"), ik + ".position");
      if (const auto q = kf[i]["orientation"]) f.orientation = p.quaternion(q, ik + ".orientation");
      if (const auto c = kf[i]["closure"]) f.closure = p.non_negative(c, ik + ".closure");
      if (i > 0 && f.time <= t.keyframes.back().time)
        p.error(kf[i], ik + ".time", "keyframe times must increase, got ", f.time, " after ", t.keyframes.back().time);
      t.keyframes.push_back(f);
    }
  }
  if (const auto g = n["gripper"]) {
    const std::string gk = k("gripper");
    p.check_map(g, gk, {"hinge", "jaws"}, "a gripper");
    const YAML::Node hinge = p.required(g, gk, "hinge");
    p.check_map(hinge, gk + ".hinge", {"origin", "axis"}, "a hinge");
    if (const auto o = hinge["origin"]) t.hinge_origin = p.vec3(o, gk + ".hinge.origin");
    const YAML::Node axis = p.required(hinge, gk + ".hinge", "axis");
    t.hinge_axis = p.vec3(axis, gk + ".hinge.axis");
    if (t.hinge_axis.norm() < 1e-9) p.error(axis, gk + ".hinge.axis", "must not be zero");
    t.hinge_axis.normalize();
    const YAML::Node jaws = p.required(g, gk, "jaws");
    if (!jaws.IsSequence() || jaws.size() < 1 || jaws.size() > 2)
      p.error(jaws, gk + ".jaws", "expected a list of one or two jaws");
    for (std::size_t i = 0; i < jaws.size(); ++i) {
      const std::string jk = SceneParser::item_key(gk + ".jaws", i);
      p.check_map(jaws[i], jk, {"shape", "offset", "side"}, "a jaw");
      ToolJawDescription jd;
      jd.shape = parse_shape(p, p.required(jaws[i], jk, "shape"), jk + ".shape");
      if (jd.shape.type == ShapeType::Plane) p.error(jaws[i]["shape"], jk + ".shape", "a jaw cannot be a plane");
      if (const auto o = jaws[i]["offset"]) jd.offset = p.vec3(o, jk + ".offset");
      if (const auto sd = jaws[i]["side"]) {
        jd.side = p.number(sd, jk + ".side");
        if (jd.side != 1 && jd.side != -1) p.error(sd, jk + ".side", "expected 1 or -1, got ", jd.side);
      }
      t.jaws.push_back(jd);
    }
  }
  if (const auto g = n["grasp"]) {
    const std::string gk = k("grasp");
    p.check_map(g, gk, {"sensors", "closure_threshold", "hardness", "damping"}, "a grasp");
    const YAML::Node ss = p.required(g, gk, "sensors");
    if (!ss.IsSequence() || ss.size() == 0) p.error(ss, gk + ".sensors", "expected a list of at least one sensor");
    for (std::size_t i = 0; i < ss.size(); ++i) {
      const std::string sk = SceneParser::item_key(gk + ".sensors", i);
      p.check_map(ss[i], sk, {"origin", "direction", "range"}, "a proximity sensor");
      ToolSensorDescription sd;
      if (const auto o = ss[i]["origin"]) sd.origin = p.vec3(o, sk + ".origin");
      const YAML::Node d = p.required(ss[i], sk, "direction");
      sd.direction = p.vec3(d, sk + ".direction");
      if (sd.direction.norm() < 1e-9) p.error(d, sk + ".direction", "must not be zero");
      sd.direction.normalize();
      sd.range = p.positive(p.required(ss[i], sk, "range"), sk + ".range");
      t.sensors.push_back(sd);
    }
    if (const auto v = g["closure_threshold"]) t.closure_threshold = p.non_negative(v, gk + ".closure_threshold");
    if (const auto v = g["hardness"]) t.hardness = p.positive(v, gk + ".hardness");
    if (const auto v = g["damping"]) t.damping = p.non_negative(v, gk + ".damping");
  }
  return t;
}

ContactDescription parse_contact(const SceneParser& p, const YAML::Node& n, const SceneDescription& scene) {
  const std::string key = "contact";
  p.check_map(n, key, {"stiffness", "friction", "self_contact", "sample_spacing", "pairs", "patch"},
              "the contact settings");
  ContactDescription c;
  if (const auto s = n["stiffness"]) {
    const std::string sk = "contact.stiffness";
    p.check_map(s, sk, {"body_object", "body_body", "self"}, "contact stiffnesses");
    if (const auto v = s["body_object"]) c.body_object_stiffness = p.non_negative(v, sk + ".body_object");
    if (const auto v = s["body_body"]) c.body_body_stiffness = p.non_negative(v, sk + ".body_body");
    if (const auto v = s["self"]) c.self_stiffness = p.non_negative(v, sk + ".self");
  }
  if (const auto v = n["friction"]) c.friction = p.non_negative(v, "contact.friction");
  if (const auto v = n["self_contact"]) c.self_contact = p.boolean(v, "contact.self_contact");
  if (const auto v = n["sample_spacing"]) c.sample_spacing = p.non_negative(v, "contact.sample_spacing");
  if (const auto v = n["patch"]) {
    const std::string pk = "contact.patch";
    if (v.IsScalar()) {
      c.patch = p.boolean(v, pk);
    } else {
      p.check_map(v, pk, {"radius", "pressure_stiffness", "spacing"}, "the contact patch settings");
      c.patch = true;
      if (const auto r = v["radius"]) c.patch_radius = p.positive(r, pk + ".radius");
      if (const auto r = v["pressure_stiffness"]) c.pressure_stiffness = p.positive(r, pk + ".pressure_stiffness");
      if (const auto r = v["spacing"]) c.patch_spacing = p.positive(r, pk + ".spacing");
    }
    if (c.patch && c.friction > 0)
      p.error(v, pk, "the contact patch is frictionless; set contact.friction: 0 to use it (friction is ", c.friction,
              ")");
  }
  if (const auto v = n["pairs"]) {
    const std::string pk = "contact.pairs";
    if (v.IsScalar()) {
      if (v.Scalar() != "all") p.error(v, pk, "expected 'all' or a list of name pairs, got '", v.Scalar(), "'");
    } else {
      if (!v.IsSequence()) p.error(v, pk, "expected 'all' or a list of name pairs");
      c.all_pairs = false;
      std::set<std::pair<std::string, std::string>> seen;
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string ik = SceneParser::item_key(pk, i);
        const YAML::Node e = v[i];
        if (!e.IsSequence() || e.size() != 2) p.error(e, ik, "expected a pair of names [a, b]");
        const std::string a = p.text(e[0], ik + "[0]"), b = p.text(e[1], ik + "[1]");
        for (std::size_t j = 0; j < 2; ++j) {
          const std::string& name = j == 0 ? a : b;
          if (scene.body_index(name) < 0 && scene.object_index(name) < 0) {
            std::vector<std::string> known;
            for (const auto& body : scene.bodies) known.push_back(body.name);
            for (const auto& obj : scene.objects) known.push_back(obj.name);
            p.error(e[j], SceneParser::item_key(ik, j), "no body or object named '", name, "' (the scene has: ", join(known), ")");
          }
        }
        if (a == b) p.error(e, ik, "a pair needs two different names (self-contact is contact.self_contact)");
        if (scene.body_index(a) < 0 && scene.body_index(b) < 0)
          p.error(e, ik, "'", a, "' and '", b, "' are both rigid objects; only pairs with a body collide");
        if (!seen.insert(std::minmax(a, b)).second) p.error(e, ik, "the pair [", a, ", ", b, "] is listed twice");
        c.pairs.emplace_back(a, b);
      }
    }
  }
  return c;
}

SolverDescription parse_solver(const SceneParser& p, const YAML::Node& n) {
  p.check_map(n, "solver", {"dt", "seconds", "newton_iters", "iterations_after_damping", "line_search", "nonlinearity_tolerance", "gravity", "damping"}, "the solver settings");
  SolverDescription s;
  if (const auto v = n["dt"]) {
    if (!v.IsScalar()) p.error(v, "solver.dt", "expected a time step such as 1/60 or 0.01");
    try {
      s.dt = parse_time_step(v.Scalar(), "dt");
    } catch (const Error&) {
      p.error(v, "solver.dt", "expected a time step in (0, 0.1] s such as 1/60 or 0.01, got '", v.Scalar(), "'");
    }
  }
  if (const auto v = n["seconds"]) s.seconds = p.non_negative(v, "solver.seconds");
  if (const auto v = n["newton_iters"]) s.newton_iterations = p.integer(v, "solver.newton_iters", 1, 100);
  if (const auto v = n["iterations_after_damping"])
    s.iterations_after_damping = p.integer(v, "solver.iterations_after_damping", 0, 100);
  if (const auto v = n["line_search"]) s.line_search = p.boolean(v, "solver.line_search");
  if (const auto v = n["nonlinearity_tolerance"]) {
    if (!(v.IsScalar() && v.Scalar() == "auto")) {
      const double t = p.convert<double>(v, "solver.nonlinearity_tolerance", "auto or a number >= 0");
      if (!(std::isfinite(t) && t >= 0))
        p.error(v, "solver.nonlinearity_tolerance", "expected auto or a number >= 0, got ", v.Scalar());
      s.nonlinearity_tolerance = t;
    }
  }
  if (const auto v = n["gravity"]) s.gravity = p.vec3(v, "solver.gravity");
  if (const auto v = n["damping"]) s.damping = p.non_negative(v, "solver.damping");
  return s;
}

OutputDescription parse_output(const SceneParser& p, const YAML::Node& n) {
  p.check_map(n, "output", {"out", "export", "render", "render_frames", "fps"}, "the outputs");
  OutputDescription o;
  if (const auto v = n["out"]) o.out = p.text(v, "output.out");
  if (o.out.empty()) p.error(n["out"], "output.out", "expected a file name");
  if (const auto v = n["export"]) o.export_path = p.text(v, "output.export");
  if (const auto v = n["render"]) o.render = p.text(v, "output.render");
  if (const auto v = n["render_frames"]) o.render_frames = p.integer(v, "output.render_frames", 1, 1000);
  if (const auto v = n["fps"]) o.fps = p.positive(v, "output.fps");
  return o;
}

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

int SceneDescription::body_index(const std::string& name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return int(i);
  return -1;
}

int SceneDescription::object_index(const std::string& name) const {
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (objects[i].name == name) return int(i);
  return -1;
}

bool SceneDescription::collides(const std::string& a, const std::string& b) const {
  if (a == b || (body_index(a) < 0 && body_index(b) < 0)) return false;
  if ((body_index(a) < 0 && object_index(a) < 0) || (body_index(b) < 0 && object_index(b) < 0)) return false;
  if (contact.all_pairs) return true;
  return std::any_of(contact.pairs.begin(), contact.pairs.end(), [&](const auto& p) {
    return (p.first == a && p.second == b) || (p.first == b && p.second == a);
  });
}

SceneDescription read_scene_description(const std::string& path) {
  if (!fs::is_regular_file(path)) fail(path, ": scene file not found");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) fail(path, ": cannot read the scene file");
  return parse_scene_description(text.str(), path);
}

SceneDescription parse_scene_description(const std::string& yaml_text, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    fail(path, ":", e.mark.line + 1, ": malformed YAML: ", e.msg);
  }
  const fs::path folder = fs::absolute(path).parent_path();
  const SceneParser p(path, folder);
  if (!root.IsMap()) fail(path, ": expected a map with 'bodies' (and optionally objects, contact, solver, output)");
  p.check_map(root, "", {"solver", "output", "contact", "bodies", "objects", "tools"}, "a scene");

  SceneDescription scene;
  scene.path = path;
  std::set<std::string> names;
  auto unique_name = [&](const YAML::Node& item, const std::string& key, const std::string& name) {
    if (name.empty()) p.error(item["name"], key + ".name", "must not be empty");
    if (!names.insert(name).second)
      p.error(item["name"], key + ".name", "the name '", name, "' is used twice (names are unique across bodies, objects and tools)");
  };
  const YAML::Node bodies = p.required(root, "", "bodies");
  if (!bodies.IsSequence() || bodies.size() == 0) p.error(bodies, "bodies", "expected a list of at least one body");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const std::string key = SceneParser::item_key("bodies", i);
    scene.bodies.push_back(parse_body(p, bodies[i], key));
    unique_name(bodies[i], key, scene.bodies.back().name);
  }
  if (const auto objects = root["objects"]) {
    if (!objects.IsSequence()) p.error(objects, "objects", "expected a list of rigid objects");
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string key = SceneParser::item_key("objects", i);
      scene.objects.push_back(parse_object(p, objects[i], key));
      unique_name(objects[i], key, scene.objects.back().name);
    }
  }
  if (const auto tools = root["tools"]) {
    if (!tools.IsSequence()) p.error(tools, "tools", "expected a list of tools");
    for (std::size_t i = 0; i < tools.size(); ++i) {
      const std::string key = SceneParser::item_key("tools", i);
      scene.tools.push_back(parse_tool(p, tools[i], key));
      unique_name(tools[i], key, scene.tools.back().name);
    }
  }
  if (const auto c = root["contact"]) scene.contact = parse_contact(p, c, scene);
  if (const auto s = root["solver"]) scene.solver = parse_solver(p, s);
  if (const auto o = root["output"]) scene.output = parse_output(p, o);
  const bool any_motion = std::any_of(scene.bodies.begin(), scene.bodies.end(), [](const auto& b) { return b.motion != "none"; });
  if (scene.solver.seconds == 0 && !any_motion)
    p.error(root["solver"] ? root["solver"] : root, "solver.seconds",
            "must be > 0 when no body has a motion (0 means: as long as the longest motion)");
  return scene;
}

// --- writing --------------------------------------------------------------------

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
      << num(c.patch_radius) << YAML::Key << "pressure_stiffness" << YAML::Value << num(c.pressure_stiffness)
      << YAML::Key << "spacing" << YAML::Value << num(c.patch_spacing) << YAML::EndMap;
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
  io::AtomicOutput out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    require(bool(f), path, ": cannot open for writing");
    f << text;
    f.close();
    require(bool(f), path, ": write failed (disk full?)");
  }
  out.commit();
}


}  // namespace sflsh
