#include "sflsh/scene/yaml_document.hpp"

#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/input_file.hpp"

namespace sflsh {

YAML::Node load_yaml_text(const std::string& text, const std::string& name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail(name, ":", e.mark.line + 1, ": malformed YAML: ", e.msg);
  }
}

YAML::Node load_yaml_file(const std::string& path, const std::string& what) {
  io::require_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) fail(path, ": cannot read the ", what);
  return load_yaml_text(text.str(), path);
}

std::string yaml_where(const std::string& file, const YAML::Node& n) {
  return n.Mark().is_null() ? file : file + ":" + std::to_string(n.Mark().line + 1);
}

}  // namespace sflsh
