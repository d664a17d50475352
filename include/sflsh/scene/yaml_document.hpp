#pragma once
// The YAML helpers every reader of a YAML file shares (scene files, material
// files, shape maps, fit data sets): loading with one error for malformed
// text, and a node's "FILE:LINE" for errors that point at it.
#include <yaml-cpp/yaml.h>

#include <string>

namespace sflsh {

/// Parses YAML `text`; malformed text fails "NAME:LINE: malformed YAML: MESSAGE".
YAML::Node load_yaml_text(const std::string& text, const std::string& name);
/// Reads and parses the YAML file `path`; `what` names the kind of file in
/// errors when it is missing or unreadable (io::require_input_file).
YAML::Node load_yaml_file(const std::string& path, const std::string& what);
/// "FILE:LINE" of node `n` (the line of its first character), or FILE when the node has no position.
std::string yaml_where(const std::string& file, const YAML::Node& n);

}  // namespace sflsh
