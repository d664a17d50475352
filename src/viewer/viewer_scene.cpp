#include "sflsh/viewer/viewer_scene.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "sflsh/core/error.hpp"
#include "sflsh/scene/result_export.hpp"

namespace sflsh::viewer {
namespace {

using nlohmann::json;

template <class M>
json flat(const M& m) {
  json a = json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index k = 0; k < m.cols(); ++k) a.push_back(m(i, k));
  return a;
}

// Rounds metres to 0.1 µm so the JSON stays short (positions are quantized far coarser).
Points rounded(const Points& p) { return (p.array() * 1e7).round() / 1e7; }

}  // namespace

ViewerScene viewer_scene(const SimulationResult& r, const std::vector<std::string>& tool_names, double pad,
                         double min_legend) {
  require(!r.frame_positions.empty(), "viewer: the result has no frames to show");
  ViewerScene s;
  s.faces = r.faces;
  s.rest = r.frame_positions.front();
  const int bodies = r.body_names.empty() ? 1 : int(r.body_names.size());
  if (r.body_names.empty()) {
    s.body_names = {"body"};
    s.body_offsets = {0, int(s.rest.rows())};
  } else {
    s.body_names = r.body_names;
    s.body_offsets = r.body_vertex_offsets;
  }
  s.num_joints = 24 * bodies;
  const std::vector<geometry::PrimitiveMesh> meshes = object_display_meshes(r);
  for (size_t o = 0; o < r.objects.size(); ++o) {
    ViewerObject v;
    v.name = r.objects[o].name;
    v.shape = r.objects[o].shape;
    v.kind = r.objects[o].kind;
    v.vertices = meshes[o].vertices;
    v.faces = meshes[o].faces;
    s.objects.push_back(v);
  }
  for (const std::string& t : tool_names) {
    s.tools.push_back(t);
    int found = -1;
    for (size_t o = 0; o < s.objects.size(); ++o) {
      const std::string& name = s.objects[o].name;
      if (name == t) {
        found = int(o);
        s.objects[o].kind = "tool";
      } else if (name.rfind(t + "/jaw", 0) == 0) {
        s.objects[o].kind = "tool";  // a jaw of the tool's gripper (its pose opens with the closure)
      }
    }
    s.tool_objects.push_back(found);
  }
  s.tool_events = r.tool_events;
  for (const ContactTrack& c : r.contacts) s.contacts.push_back({c.term, c.body, {}});
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  double umax = 0;
  for (size_t f = 0; f < r.frame_positions.size(); ++f) {
    lo = lo.cwiseMin(r.frame_positions[f].colwise().minCoeff().transpose());
    hi = hi.cwiseMax(r.frame_positions[f].colwise().maxCoeff().transpose());
    if (f < r.frame_displacement.size() && r.frame_displacement[f].rows() > 0)
      umax = std::max(umax, r.frame_displacement[f].rowwise().norm().maxCoeff());
    for (size_t o = 0; o < r.objects.size(); ++o)
      if (r.objects[o].shape != "plane" && f < r.objects[o].poses.size()) {
        lo = lo.cwiseMin(r.objects[o].poses[f].translation());
        hi = hi.cwiseMax(r.objects[o].poses[f].translation());
      }
  }
  s.box_min = lo.array() - pad;
  s.box_max = hi.array() + pad;
  s.legend_max = std::max(min_legend, std::ceil(umax * 1e3) * 1e-3);
  s.duration = r.frame_time.empty() ? 0.0 : r.frame_time.back();
  s.dt = r.dt;
  return s;
}

ViewerScene playback_scene(const SimulationResult& r, const std::string& title) {
  std::vector<std::string> tools;
  for (const ToolTrack& t : r.tools) tools.push_back(t.name);
  ViewerScene s = viewer_scene(r, tools, 0.05, 0.001);
  s.mode = "playback";
  s.title = title;
  return s;
}

std::string scene_json(const ViewerScene& s) {
  json j;
  j["type"] = "scene";
  j["protocol"] = 1;
  j["mode"] = s.mode;
  j["title"] = s.title;
  j["faces"] = flat(s.faces);
  j["rest"] = flat(rounded(s.rest));
  json bodies = json::array();
  for (size_t b = 0; b < s.body_names.size(); ++b)
    bodies.push_back({{"name", s.body_names[b]}, {"begin", s.body_offsets[b]}, {"end", s.body_offsets[b + 1]}});
  j["bodies"] = bodies;
  j["joints"] = s.num_joints;
  json objects = json::array();
  for (const ViewerObject& o : s.objects)
    objects.push_back({{"name", o.name}, {"shape", o.shape}, {"kind", o.kind}, {"vertices", flat(rounded(o.vertices))},
                       {"faces", flat(o.faces)}});
  j["objects"] = objects;
  json tools = json::array();
  for (size_t t = 0; t < s.tools.size(); ++t) tools.push_back({{"name", s.tools[t]}, {"object", s.tool_objects[t]}});
  j["tools"] = tools;
  json contacts = json::array();
  for (const ContactTrack& c : s.contacts) contacts.push_back({{"term", c.term}, {"body", c.body}});
  j["contacts"] = contacts;
  j["box_min"] = {s.box_min.x(), s.box_min.y(), s.box_min.z()};
  j["box_max"] = {s.box_max.x(), s.box_max.y(), s.box_max.z()};
  j["legend_max_mm"] = s.legend_max * 1e3;
  j["duration"] = s.duration;
  j["dt"] = s.dt;
  j["can_reset"] = s.can_reset;
  json events = json::array();
  for (const ToolEvent& e : s.tool_events)
    events.push_back({{"time", e.time}, {"tool", e.tool}, {"body", e.body}, {"kind", e.kind}, {"points", e.points}});
  j["tool_events"] = events;
  return j.dump();
}

}  // namespace sflsh::viewer
