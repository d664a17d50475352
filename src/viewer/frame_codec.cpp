#include "sflsh/viewer/frame_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "sflsh/core/error.hpp"

namespace sflsh::viewer {
namespace {

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // little-endian hosts only (x86-64, arm64)
  out.append(b, sizeof(T));
}

template <class T>
T get(std::string_view in, std::size_t* at, const char* field) {
  require(*at + sizeof(T) <= in.size(), "viewer frame: truncated at field '", field, "' (", in.size(), " bytes)");
  T v;
  std::memcpy(&v, in.data() + *at, sizeof(T));
  *at += sizeof(T);
  return v;
}

/// Every tool's pose (position, then the quaternion w x y z), force, torque and closure.
nlohmann::json tools_json(const std::vector<ToolFrame>& tools) {
  nlohmann::json a = nlohmann::json::array();
  for (const ToolFrame& t : tools) {
    const Vec3 p = t.pose.translation();
    const Eigen::Quaterniond q(t.pose.rotation());
    a.push_back({{"pose", {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()}},
                 {"force", {t.force.x(), t.force.y(), t.force.z()}},
                 {"torque", {t.torque.x(), t.torque.y(), t.torque.z()}},
                 {"closure", t.closure}});
  }
  return a;
}

/// Every contact's force on its body (N), where it acts (m), its depth (mm) and active samples.
nlohmann::json contacts_json(const std::vector<ContactFrame>& contacts) {
  nlohmann::json a = nlohmann::json::array();
  for (const ContactFrame& c : contacts)
    a.push_back({{"force", {c.force.x(), c.force.y(), c.force.z()}},
                 {"point", {c.point.x(), c.point.y(), c.point.z()}},
                 {"depth_mm", c.max_penetration * 1e3},
                 {"active", c.active}});
  return a;
}

std::string info_json(const ViewerFrame& f, const FrameEnvelope& e) {
  const ViewerStats& s = f.stats;
  nlohmann::json j;
  j["t"] = f.time;
  j["seq"] = e.seq;
  j["driver"] = e.driver;
  j["clients"] = e.clients;
  j["paused"] = s.paused;
  j["rtf"] = s.rtf;
  j["step_ms"] = s.step_ms;
  nlohmann::json terms = nlohmann::json::array();
  for (size_t i = 0; i < s.term_names.size() && i < s.term_ms.size(); ++i) terms.push_back({s.term_names[i], s.term_ms[i]});
  j["terms"] = terms;
  j["stiffness"] = s.stiffness_scale;
  j["resets"] = s.resets;
  j["steps"] = s.steps;
  j["max_u_mm"] = s.max_displacement * 1e3;
  j["frame"] = s.frame_index;
  j["speed"] = s.speed;
  if (s.has_tool)
    j["tool"] = {{"force", {s.force.x(), s.force.y(), s.force.z()}},
                 {"device", {s.device.x(), s.device.y(), s.device.z()}},
                 {"quat", {s.device_orientation.w(), s.device_orientation.x(), s.device_orientation.y(),
                           s.device_orientation.z()}},
                 {"closure", s.closure},
                 {"contact", s.contact},
                 {"anchors", s.anchors}};
  if (!f.tools.empty()) j["tools"] = tools_json(f.tools);
  if (!f.contacts.empty()) j["contacts"] = contacts_json(f.contacts);
  return j.dump();
}

}  // namespace

QuantizedSkin quantize(const ViewerFrame& f, const ViewerScene& scene) {
  const Eigen::Index V = scene.rest.rows();
  require(f.positions.rows() == V, "viewer: frame with ", f.positions.rows(), " skin vertices, the scene has ", V);
  require(f.displacement.size() == V, "viewer: frame with ", f.displacement.size(), " displacement magnitudes, expected ", V);
  QuantizedSkin q;
  q.position.resize(3 * V);
  q.magnitude.resize(V);
  const Vec3 size = scene.box_max - scene.box_min;
  for (Eigen::Index i = 0; i < V; ++i) {
    for (int k = 0; k < 3; ++k) {
      double x = (f.positions(i, k) - scene.box_min[k]) / size[k];
      x = std::isfinite(x) ? std::clamp(x, 0.0, 1.0) : 0.0;
      q.position[3 * i + k] = std::uint16_t(std::lround(x * 65535.0));
    }
    double m = f.displacement[i] / scene.legend_max;
    m = std::isfinite(m) ? std::clamp(m, 0.0, 1.0) : 0.0;
    q.magnitude[i] = std::uint8_t(std::lround(m * 255.0));
  }
  return q;
}

std::string encode_frame(const ViewerFrame& f, const QuantizedSkin& skin, const ViewerScene& scene,
                         const FrameEnvelope& e, QuantizedSkin* last) {
  const std::uint32_t V = std::uint32_t(skin.magnitude.size());
  std::vector<std::uint32_t> changed;
  bool delta = last && last->magnitude.size() == V;
  if (delta) {
    for (std::uint32_t i = 0; i < V; ++i)
      if (skin.magnitude[i] != last->magnitude[i] || skin.position[3 * i] != last->position[3 * i] ||
          skin.position[3 * i + 1] != last->position[3 * i + 1] || skin.position[3 * i + 2] != last->position[3 * i + 2])
        changed.push_back(i);
    delta = changed.size() * 11 < std::size_t(V) * 7;  // 4 + 6 + 1 bytes per entry vs 6 + 1
  }
  const std::string info = info_json(f, e);
  const std::uint32_t N = delta ? std::uint32_t(changed.size()) : V;
  std::string out;
  out.reserve(kFrameHeaderBytes + N * 11 + f.object_poses.size() * 28 + f.joints.rows() * 12 + info.size() + 4);
  put<std::uint32_t>(out, kFrameMagic);
  put<std::uint16_t>(out, kFrameVersion);
  put<std::uint16_t>(out, delta ? kDeltaFrame : kFullFrame);
  put<std::uint32_t>(out, e.number);
  put<std::uint32_t>(out, V);
  put<std::uint32_t>(out, N);
  put<std::uint32_t>(out, std::uint32_t(f.object_poses.size()));
  put<std::uint32_t>(out, std::uint32_t(f.joints.rows()));
  put<std::uint32_t>(out, std::uint32_t(info.size()));
  put<double>(out, f.time);
  put<float>(out, float(scene.legend_max));
  put<std::uint32_t>(out, 0);
  if (delta) {
    for (std::uint32_t i : changed) put<std::uint32_t>(out, i);
    for (std::uint32_t i : changed)
      for (int k = 0; k < 3; ++k) put<std::uint16_t>(out, skin.position[3 * i + k]);
    for (std::uint32_t i : changed) put<std::uint8_t>(out, skin.magnitude[i]);
  } else {
    out.append(reinterpret_cast<const char*>(skin.position.data()), skin.position.size() * 2);
    out.append(reinterpret_cast<const char*>(skin.magnitude.data()), skin.magnitude.size());
  }
  while (out.size() % 4) out.push_back('\0');
  for (const Isometry& p : f.object_poses) {
    const Eigen::Quaterniond q(p.linear());
    for (double v : {p.translation().x(), p.translation().y(), p.translation().z(), q.w(), q.x(), q.y(), q.z()})
      put<float>(out, float(v));
  }
  for (Eigen::Index j = 0; j < f.joints.rows(); ++j)
    for (int k = 0; k < 3; ++k) put<float>(out, float(f.joints(j, k)));
  out += info;
  if (last) *last = skin;
  return out;
}

DecodedFrame decode_frame(std::string_view in, const ViewerScene& scene, QuantizedSkin* state) {
  std::size_t at = 0;
  require(get<std::uint32_t>(in, &at, "magic") == kFrameMagic, "viewer frame: bad magic");
  require(get<std::uint16_t>(in, &at, "version") == kFrameVersion, "viewer frame: unknown version");
  DecodedFrame d;
  d.kind = get<std::uint16_t>(in, &at, "kind");
  require(d.kind == kFullFrame || d.kind == kDeltaFrame, "viewer frame: field 'kind' = ", d.kind, ", expected 1 or 2");
  d.number = get<std::uint32_t>(in, &at, "number");
  const std::uint32_t V = get<std::uint32_t>(in, &at, "V"), N = get<std::uint32_t>(in, &at, "N");
  const std::uint32_t O = get<std::uint32_t>(in, &at, "O"), J = get<std::uint32_t>(in, &at, "J");
  const std::uint32_t L = get<std::uint32_t>(in, &at, "L");
  d.time = get<double>(in, &at, "time");
  const double legend = get<float>(in, &at, "legend");
  get<std::uint32_t>(in, &at, "reserved");
  require(V == std::uint32_t(scene.rest.rows()), "viewer frame: field 'V' = ", V, ", the scene has ", scene.rest.rows());
  require(N <= V && (d.kind == kDeltaFrame || N == V), "viewer frame: field 'N' = ", N, " for V = ", V);
  const std::size_t need = std::size_t(N) * (d.kind == kDeltaFrame ? 11 : 7);
  require(at + need <= in.size(), "viewer frame: truncated skin");
  if (d.kind == kFullFrame) {
    state->position.assign(3 * V, 0);
    state->magnitude.assign(V, 0);
  }
  require(state->magnitude.size() == V, "viewer frame: a delta frame before any full frame");
  std::vector<std::uint32_t> index(N);
  for (std::uint32_t e = 0; e < N; ++e) {
    index[e] = d.kind == kDeltaFrame ? get<std::uint32_t>(in, &at, "index") : e;
    require(index[e] < V, "viewer frame: field 'index' = ", index[e], " >= V = ", V);
  }
  for (std::uint32_t e = 0; e < N; ++e)
    for (int k = 0; k < 3; ++k) state->position[3 * index[e] + k] = get<std::uint16_t>(in, &at, "position");
  for (std::uint32_t e = 0; e < N; ++e) state->magnitude[index[e]] = get<std::uint8_t>(in, &at, "magnitude");
  at = (at + 3) / 4 * 4;
  d.positions.resize(V, 3);
  d.displacement.resize(V);
  const Vec3 size = scene.box_max - scene.box_min;
  for (std::uint32_t i = 0; i < V; ++i) {
    for (int k = 0; k < 3; ++k) d.positions(i, k) = scene.box_min[k] + state->position[3 * i + k] / 65535.0 * size[k];
    d.displacement[i] = state->magnitude[i] / 255.0 * legend;
  }
  for (std::uint32_t o = 0; o < O; ++o) {
    float v[7];
    for (float& x : v) x = get<float>(in, &at, "poses");
    Isometry p = Isometry::Identity();
    p.translation() = Vec3(v[0], v[1], v[2]);
    p.linear() = Eigen::Quaterniond(v[3], v[4], v[5], v[6]).normalized().toRotationMatrix();
    d.object_poses.push_back(p);
  }
  d.joints.resize(J, 3);
  for (std::uint32_t j = 0; j < J; ++j)
    for (int k = 0; k < 3; ++k) d.joints(j, k) = get<float>(in, &at, "joints");
  require(at + L == in.size(), "viewer frame: ", in.size() - at, " bytes of info, header says ", L);
  d.info = std::string(in.substr(at));
  return d;
}

}  // namespace sflsh::viewer
