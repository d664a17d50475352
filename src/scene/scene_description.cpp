// Reading a scene file: the top level (bodies, objects and tools with unique names, then the settings).
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/yaml_document.hpp"

#include <fstream>
#include <set>
#include <sstream>

#include "scene/scene_yaml_reader.hpp"

namespace sflsh {

using namespace scene_yaml;
namespace fs = std::filesystem;

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
  const YAML::Node root = load_yaml_text(yaml_text, path);
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

}  // namespace sflsh
