// The `contact:`, `solver:` and `output:` sections of a scene file.
#include "scene/scene_yaml_reader.hpp"

#include <set>

#include "sflsh/core/time_step.hpp"

namespace sflsh::scene_yaml {

ContactDescription parse_contact(const SceneParser& p, const YAML::Node& n, const SceneDescription& scene) {
  const std::string key = "contact";
  p.check_map(n, key, {"stiffness", "friction", "self_contact", "sample_spacing", "pairs", "patch", "bodies"},
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
      p.check_map(v, pk, {"radius", "max_nodes", "pressure_stiffness", "spacing"}, "the contact patch settings");
      c.patch = true;
      if (const auto r = v["radius"]) c.patch_radius = p.positive(r, pk + ".radius");
      if (const auto r = v["max_nodes"]) c.max_patch_nodes = p.integer(r, pk + ".max_nodes", 1, 1000000);
      if (const auto r = v["pressure_stiffness"]) c.pressure_stiffness = p.positive(r, pk + ".pressure_stiffness");
      if (const auto r = v["spacing"]) c.patch_spacing = p.positive(r, pk + ".spacing");
    }
  }
  if (const auto v = n["bodies"]) {
    const std::string bk = "contact.bodies";
    p.check_map(v, bk, {"model", "pressure_stiffness", "spacing", "core_radius"}, "the body-body contact settings");
    if (const auto m = v["model"]) {
      const std::string model = p.text(m, bk + ".model");
      if (model == "skin")
        c.body_model = ContactDescription::BodyModel::Skin;
      else if (model == "capsules")
        c.body_model = ContactDescription::BodyModel::Capsules;
      else
        p.error(m, bk + ".model", "expected 'skin' or 'capsules', got '", model, "'");
    }
    if (const auto r = v["pressure_stiffness"]) c.body_pressure_stiffness = p.positive(r, bk + ".pressure_stiffness");
    if (const auto r = v["spacing"]) c.body_spacing = p.positive(r, bk + ".spacing");
    if (const auto r = v["core_radius"]) {
      c.core_radius = p.positive(r, bk + ".core_radius");
      if (c.core_radius > 1) p.error(r, bk + ".core_radius", "expected a share in (0, 1], got ", c.core_radius);
    }
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

}  // namespace sflsh::scene_yaml
