#pragma once
// Reading a scene file's YAML: the helpers every section parser shares (a
// node's "FILE:LINE", typed values with their range checks, files relative to
// the scene) and one parser per section. Errors are one line naming the file,
// the line and the key path ("scene.yaml:7: tools[0].grasp.hardness: must be
// > 0, got -1"). Internal to src/scene.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/yaml_document.hpp"

namespace sflsh::scene_yaml {

namespace fs = std::filesystem;

/// v scaled to unit length; left as is when it already is (to the last bits),
/// so that written and re-read unit vectors stay bit-identical.
template <class V>
V unit(const V& v) {
  return std::abs(v.norm() - 1) <= 4 * std::numeric_limits<double>::epsilon() ? v : V(v.normalized());
}

inline std::string join(const std::vector<std::string>& items) {
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
  std::string where(const YAML::Node& n) const { return yaml_where(file_, n); }

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

// --- sections (one file each: parse_bodies.cpp, parse_objects.cpp,
// parse_tools.cpp, parse_settings.cpp) ---------------------------------------

BodyDescription parse_body(const SceneParser& p, const YAML::Node& n, const std::string& key);
ShapeDescription parse_shape(const SceneParser& p, const YAML::Node& n, const std::string& key);
RigidObjectDescription parse_object(const SceneParser& p, const YAML::Node& n, const std::string& key);
ToolDescription parse_tool(const SceneParser& p, const YAML::Node& n, const std::string& key);
/// `scene`: the bodies and objects read so far (the pairs name them).
ContactDescription parse_contact(const SceneParser& p, const YAML::Node& n, const SceneDescription& scene);
SolverDescription parse_solver(const SceneParser& p, const YAML::Node& n);
OutputDescription parse_output(const SceneParser& p, const YAML::Node& n);

}  // namespace sflsh::scene_yaml
