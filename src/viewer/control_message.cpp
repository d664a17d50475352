#include "sflsh/viewer/control_message.hpp"

#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

namespace sflsh::viewer {
namespace {

using nlohmann::json;

constexpr double kMaxSeq = 9007199254740992.0;  // 2^53: exact in a JavaScript number

// Reads a finite number field into *out; returns the error sentence or "".
std::string number_field(const json& j, const char* key, double* out) {
  const auto it = j.find(key);
  if (it == j.end()) return std::string("missing field \"") + key + "\"";
  if (!it->is_number()) return std::string("field \"") + key + "\": expected a number";
  *out = it->get<double>();
  if (!std::isfinite(*out)) return std::string("field \"") + key + "\": expected a finite number";
  return "";
}

std::string range_field(const json& j, const char* key, double lo, double hi, double* out) {
  std::string e = number_field(j, key, out);
  if (!e.empty()) return e;
  if (*out < lo || *out > hi) {
    std::ostringstream os;
    os << "field \"" << key << "\" = " << *out << ": expected a value in [" << lo << ", " << hi << "]";
    return os.str();
  }
  return "";
}

// A fixed-length array of finite numbers.
std::string array_field(const json& j, const char* key, int n, double* out) {
  const auto it = j.find(key);
  if (it == j.end()) return std::string("missing field \"") + key + "\"";
  if (!it->is_array() || int(it->size()) != n)
    return std::string("field \"") + key + "\": expected an array of " + std::to_string(n) + " numbers";
  for (int i = 0; i < n; ++i) {
    const json& v = (*it)[i];
    if (!v.is_number()) return std::string("field \"") + key + "\": expected an array of " + std::to_string(n) + " numbers";
    out[i] = v.get<double>();
    if (!std::isfinite(out[i])) return std::string("field \"") + key + "\": expected finite numbers";
  }
  return "";
}

std::string parse_tool(const json& j, ControlMessage* m) {
  std::string e;
  if (j.contains("tool")) {
    double tool = 0;
    if (!(e = range_field(j, "tool", 0, 1000, &tool)).empty()) return e;
    if (tool != std::floor(tool)) return "field \"tool\": expected a tool index (integer)";
    m->tool = int(tool);
  }
  if (!(e = number_field(j, "t", &m->pose.time)).empty()) return e;
  double p[3], q[4];
  if (!(e = array_field(j, "pos", 3, p)).empty()) return e;
  if (!(e = array_field(j, "quat", 4, q)).empty()) return e;
  for (double v : p)
    if (std::abs(v) > 1e4) return "field \"pos\": expected coordinates within 10 km (m)";
  m->pose.position = Vec3(p[0], p[1], p[2]);
  m->pose.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  const double norm = m->pose.orientation.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    std::ostringstream os;
    os << "field \"quat\": norm " << norm << ", expected a unit quaternion (w x y z)";
    return os.str();
  }
  teleop::normalize_unless_unit(m->pose.orientation);
  return range_field(j, "closure", 0.0, teleop::kMaxClosure, &m->pose.closure);
}

}  // namespace

const char* to_string(ControlType type) {
  switch (type) {
    case ControlType::kTool: return "tool";
    case ControlType::kPause: return "pause";
    case ControlType::kStep: return "step";
    case ControlType::kReset: return "reset";
    case ControlType::kStiffness: return "stiffness";
    case ControlType::kSeek: return "seek";
    case ControlType::kSpeed: return "speed";
  }
  return "?";
}

ControlParse parse_control_message(std::string_view text) {
  ControlParse r;
  if (text.size() > kMaxControlMessageBytes) {
    r.error = "message of " + std::to_string(text.size()) + " bytes, expected at most " +
              std::to_string(kMaxControlMessageBytes);
    return r;
  }
  const json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    r.error = "not JSON";
    return r;
  }
  if (!j.is_object()) {
    r.error = "expected a JSON object";
    return r;
  }
  const auto type = j.find("type");
  if (type == j.end() || !type->is_string()) {
    r.error = "missing field \"type\" (a string)";
    return r;
  }
  ControlMessage m;
  double seq = 0;
  if (!(r.error = range_field(j, "seq", 0, kMaxSeq, &seq)).empty()) return r;
  if (seq != std::floor(seq)) {
    r.error = "field \"seq\": expected an integer";
    return r;
  }
  m.seq = std::uint64_t(seq);
  const std::string& t = type->get_ref<const std::string&>();
  if (t == "tool") {
    m.type = ControlType::kTool;
    r.error = parse_tool(j, &m);
  } else if (t == "pause") {
    m.type = ControlType::kPause;
    const auto it = j.find("paused");
    if (it == j.end() || !it->is_boolean())
      r.error = "field \"paused\": expected true or false";
    else
      m.paused = it->get<bool>();
  } else if (t == "step") {
    m.type = ControlType::kStep;
  } else if (t == "reset") {
    m.type = ControlType::kReset;
  } else if (t == "stiffness") {
    m.type = ControlType::kStiffness;
    r.error = range_field(j, "scale", kMinStiffnessScale, kMaxStiffnessScale, &m.value);
  } else if (t == "seek") {
    m.type = ControlType::kSeek;
    r.error = range_field(j, "time", 0.0, 1e9, &m.value);
  } else if (t == "speed") {
    m.type = ControlType::kSpeed;
    r.error = range_field(j, "speed", kMinPlaybackSpeed, kMaxPlaybackSpeed, &m.value);
  } else {
    r.error = "unknown type \"" + t.substr(0, 40) + "\"";
  }
  if (r.error.empty()) r.message = m;
  return r;
}

}  // namespace sflsh::viewer
