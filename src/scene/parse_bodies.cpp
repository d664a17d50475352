// The `bodies:` section of a scene file: avatar, shape, motion, placement, bones, material, velocity.
#include "scene/scene_yaml_reader.hpp"

#include "sflsh/motion/builtin_motions.hpp"

namespace sflsh::scene_yaml {

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

}  // namespace sflsh::scene_yaml
