// The `tools:` section of a scene file: shape, pose source, coupling, gripper jaws and grasp sensors.
#include "scene/scene_yaml_reader.hpp"

namespace sflsh::scene_yaml {
namespace {

/// coupling: the virtual coupling's gains (damping "auto" = critical).
void parse_coupling(const SceneParser& p, const YAML::Node& cn, const std::string& ck, ToolDescription& t) {
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

/// keyframes: the tool's poses and closures over time, times increasing.
void parse_tool_keyframes(const SceneParser& p, const YAML::Node& kf, const std::string& key, ToolDescription& t) {
  if (!kf.IsSequence() || kf.size() == 0) p.error(kf, key, "expected a list of at least one keyframe");
  for (std::size_t i = 0; i < kf.size(); ++i) {
    const std::string ik = SceneParser::item_key(key, i);
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

/// gripper: the hinge and the one or two jaws turning about it.
void parse_gripper(const SceneParser& p, const YAML::Node& g, const std::string& gk, ToolDescription& t) {
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

/// grasp: the proximity sensors, the closure threshold and the anchors' hardness and damping.
void parse_grasp(const SceneParser& p, const YAML::Node& g, const std::string& gk, ToolDescription& t) {
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

}  // namespace

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
  if (const auto cn = n["coupling"]) parse_coupling(p, cn, k("coupling"), t);
  if (kf) parse_tool_keyframes(p, kf, k("keyframes"), t);
  if (const auto g = n["gripper"]) parse_gripper(p, g, k("gripper"), t);
  if (const auto g = n["grasp"]) parse_grasp(p, g, k("grasp"), t);
  return t;
}

}  // namespace sflsh::scene_yaml
