#include "sflsh/scene/tool_driver.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "sflsh/core/error.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/sim/energies/virtual_coupling.hpp"
#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/pose_recorder.hpp"
#include "sflsh/teleop/pose_stream_link.hpp"
#include "sflsh/teleop/pose_track.hpp"
#include "scene/scene_run_state.hpp"

namespace sflsh {
namespace {

using teleop::PoseInterpolation;
using teleop::PoseSample;
using teleop::PoseTrack;

/// The tool's own pose source: its pose file, its keyframes, or the identity.
PoseTrack tool_track(const ToolDescription& t) {
  if (!t.pose_file.empty()) return PoseTrack(teleop::read_pose_file(t.pose_file), t.pose_file);
  if (t.keyframes.empty()) return PoseTrack({PoseSample{}}, "tool '" + t.name + "' start pose");
  std::vector<PoseSample> samples;
  for (const ToolKeyframe& k : t.keyframes) samples.push_back({k.time, k.position, k.orientation, k.closure});
  return PoseTrack(std::move(samples), "tool '" + t.name + "' keyframes");
}

Isometry sample_pose(const PoseSample& s) { return pose_at(s.position, s.orientation); }

bool same_sample(const PoseSample& a, const PoseSample& b) {
  return a.position == b.position && a.orientation.coeffs() == b.orientation.coeffs() && a.closure == b.closure;
}

Vec3 vec3_of(const std::vector<double>& v) { return Vec3(v[0], v[1], v[2]); }

bool contains(const std::vector<int>& terms, int term) {
  return std::find(terms.begin(), terms.end(), term) != terms.end();
}

}  // namespace

ToolDriver::ToolDriver(const CompiledTool& tool, int num_bodies, const ToolDriverOptions& options)
    : tool_(&tool), options_(options), num_bodies_(num_bodies) {
  const ToolDescription& d = *tool.desc;
  const std::string& scene = options.scene_path;
  try {
    if (!options.replay_dir.empty()) {
      const std::string file = (std::filesystem::path(options.replay_dir) / (d.name + ".csv")).string();
      track_ = std::make_unique<PoseTrack>(teleop::read_pose_file(file), file);
      hold_ = true;
    } else {
      track_ = std::make_unique<PoseTrack>(tool_track(d));
      hold_ = d.pose_file_hold;
    }
  } catch (const Error& e) {
    fail(scene, ": tools '", d.name, "': ", e.what());
  }
  if (d.stream_port >= 0 && options.open_stream && options.replay_dir.empty()) {
    teleop::PoseStreamServerOptions so;
    so.port = d.stream_port;
    so.checks.max_speed = d.stream_max_speed;
    const std::string tool_name = d.name;
    so.log = [tool_name](const std::string& line) { std::cerr << "tool " << tool_name << ": " << line << "\n"; };
    try {
      link_ = std::make_unique<teleop::PoseStreamLink>(so);
    } catch (const Error& e) {
      fail(scene, ": tools '", d.name, "': pose_stream: ", e.what());
    }
    if (options.progress)
      std::cerr << "tool " << d.name << ": listening for device poses on udp://127.0.0.1:" << link_->port() << "\n";
  }
  if (!d.sensors.empty()) grasps_.assign(size_t(num_bodies), GraspController(tool.grasp));
}

ToolDriver::~ToolDriver() = default;
ToolDriver::ToolDriver(ToolDriver&&) noexcept = default;
ToolDriver& ToolDriver::operator=(ToolDriver&&) noexcept = default;

void ToolDriver::start(State& s) {
  device_now_ = track_->at(0.0, hold_ ? PoseInterpolation::kHold : PoseInterpolation::kLinear);
  state_.device = device_now_;
  state_.pose = sample_pose(device_now_);
  if (tool_->coupled())
    s.bodies[tool_->model_index] = {Configuration{{state_.pose}, VecX(0)}, Configuration{{state_.pose}, VecX(0)}};
  start_recording(0.0);
}

void ToolDriver::start_recording(double t) {
  if (options_.record_dir.empty()) return;
  recorder_ = std::make_unique<teleop::PoseRecorder>(
      (std::filesystem::path(options_.record_dir) / (name() + ".csv")).string());
  recorder_->record({0, device_now_, t});
  recorded_ = device_now_;
}

void ToolDriver::reset() {
  if (!tool_->desc->sensors.empty()) grasps_.assign(size_t(num_bodies_), GraspController(tool_->grasp));
  live_ = false;
  pushed_ = PoseSample{};
  link_seen_ = false;
  link_sequence_ = 0;
  ramp_ = teleop::PoseRamp();
  state_ = SceneToolState{};
  recorded_ = PoseSample{};
  recorder_.reset();  // drops the rows so far (before start() opens the file again)
}

void ToolDriver::resume(const Simulator& sim, double t, std::vector<std::vector<Anchor>> grasps) {
  require(grasps.size() == grasps_.size(), "tool '", name(), "': ", grasps.size(), " bodies' grasps to resume, the tool has ",
          grasps_.size());
  for (size_t b = 0; b < grasps.size(); ++b) grasps_[b].restore(std::move(grasps[b]));
  device_now_ = track_->at(t, hold_ ? PoseInterpolation::kHold : PoseInterpolation::kLinear);
  state_.device = device_now_;
  state_.pose = pose(sim);
  start_recording(t);
}

std::vector<std::vector<Anchor>> ToolDriver::grasped() const {
  std::vector<std::vector<Anchor>> out;
  for (const GraspController& g : grasps_) out.push_back(g.anchors());
  return out;
}

void ToolDriver::push(const PoseSample& sample) {
  require(sample.position.allFinite() && sample.orientation.coeffs().allFinite() && std::isfinite(sample.closure),
          "tool '", name(), "': device pose is not finite");
  require(sample.orientation.norm() > 1e-6, "tool '", name(), "': device orientation is a zero quaternion");
  pushed_ = sample;
  pushed_.orientation.normalize();
  live_ = true;
}

Isometry ToolDriver::pose(const Simulator& sim) const {
  return tool_->coupled() ? sim.state(tool_->model_index).bones[0] : sample_pose(device_now_);
}

void ToolDriver::take_over(Simulator& sim, double t0) {
  const ToolDescription& d = *tool_->desc;
  const bool has_pose = !d.keyframes.empty() || !d.pose_file.empty();
  const Isometry device = sample_pose(pushed_);
  if (has_pose) {
    ramp_ = teleop::PoseRamp(t0, d.stream_ramp_in, pose(sim), device);
    return;
  }
  ramp_ = teleop::PoseRamp(t0, 0.0, device, device);
  device_now_ = pushed_;
  if (tool_->coupled()) {
    State s = sim.scene_state();
    s.bodies[size_t(tool_->model_index)] = {Configuration{{device}, VecX(0)}, Configuration{{device}, VecX(0)}};
    sim.set_state(s);
  }
}

void ToolDriver::drive(Simulator& sim, const std::vector<CompiledBody>& bodies, double t, double h, StepInputs& in,
                       std::vector<SceneToolEvent>& events) {
  const CompiledTool& tl = *tool_;
  if (link_) {
    // The newest good sample of the live stream (held when none came).
    if (const auto got = link_->latest(); got && (!link_seen_ || got->sequence != link_sequence_)) {
      link_seen_ = true;
      link_sequence_ = got->sequence;
      pushed_ = got->sample;
      live_ = true;
    }
  }
  if (live_ && !ramp_.started()) take_over(sim, t - h);
  // The device at t − h (the grasp looks from there) and at t (where the step
  // takes the tool). Keyframes and pose files are interpolated at both times;
  // live and recorded devices step from the pose held at t − h.
  const bool linear = !live_ && !hold_;
  const PoseSample now = linear ? track_->at(t - h) : device_now_;
  const PoseSample next = live_ ? ramp_.apply(pushed_, t)
                                : linear ? track_->at(t) : track_->at(t, PoseInterpolation::kHold);
  const WorldFrame f = frame_between(sample_pose(now), sample_pose(next), h);
  const bool coupled = tl.coupled();
  in.frames[tl.frame] = f;
  // Where the jaws are at t − h: the coupled body, or the device.
  WorldFrame jaws = f;
  if (coupled) jaws = WorldFrame{sim.state(tl.model_index).bones[0]};
  const Isometry before = coupled ? jaws.pose : sample_pose(now);
  for (const CompiledJaw& jaw : tl.jaws) {
    if (coupled) {
      in.frames[jaw.frame] = WorldFrame{before * tl.jaw_in_tool(jaw, next.closure)};
    } else {
      in.frames[jaw.frame] = frame_between(before * tl.jaw_in_tool(jaw, now.closure),
                                           sample_pose(next) * tl.jaw_in_tool(jaw, next.closure), h);
    }
  }
  for (size_t bi = 0; bi < grasps_.size(); ++bi) {
    GraspController& grasp = grasps_[bi];
    const CompiledBody& b = bodies[bi];
    // The posed skin only while the jaws look for something to grasp.
    const Points skin = grasp.seeking(now.closure) ? sim.posed_surface(b.model_index) : Points();
    if (grasp.update(t - h, before, now.closure, skin, b.avatar->surface_faces)) {
      const GraspEvent& ev = grasp.log().back();
      events.push_back({ev.time, name(), b.desc->name, ev.kind == GraspEvent::Kind::Grasp ? "grasp" : "release",
                        int(ev.points.size())});
    }
    const size_t set = size_t(tl.anchor_sets[bi].index);
    if (in.anchors.size() <= set) in.anchors.resize(set + 1);
    anchor_points(jaws, grasp.anchors(), coupled, in.anchors[set]);
  }
  if (recorder_ && !same_sample(next, recorded_)) {
    recorder_->record({0, next, t});
    recorded_ = next;
  }
  device_now_ = next;
  state_.device = live_ ? pushed_ : next;  // the device's own sample (next may be ramped)
}

void ToolDriver::feel(const Simulator& sim, const StepReport& rep, double t) {
  const CompiledTool& tl = *tool_;
  SceneToolState& ts = state_;
  // The force on the tool is minus what its contact and anchor terms exert on the bodies.
  ts.force.setZero();
  ts.torque.setZero();
  ts.anchors = 0;
  ts.max_stretch = 0;
  for (const TermQuantityReport& q : rep.quantities) {
    const bool contact = contains(tl.contact_terms, q.term_index);
    const bool anchor = contains(tl.anchor_terms, q.term_index);
    if ((contact || anchor) && q.name == "force" && q.value.size() == 3) ts.force -= vec3_of(q.value);
    if (anchor && q.name == "anchor_points") ts.anchors += int(q.value.size());
    if (anchor && q.name == "max_stretch") ts.max_stretch = std::max(ts.max_stretch, q.value[0]);
  }
  ts.live = live_;
  ts.pose = pose(sim);
  if (tl.coupled()) {
    // The device feels the coupling's pull, opposite to its force on the tool.
    for (const TermQuantityReport& q : rep.quantities) {
      if (q.term_index != tl.coupling_term) continue;
      if (q.name == "force") ts.feedback_force = -vec3_of(q.value);
      if (q.name == "torque") ts.feedback_torque = -vec3_of(q.value);
    }
  } else {
    ts.feedback_force = ts.force;
    ts.feedback_torque = ts.torque;
  }
  const ToolCouplingDescription& cd = tl.desc->coupling;
  ts.feedback_force *= cd.haptic_gain;
  ts.feedback_torque *= cd.haptic_gain;
  if (ts.feedback_force.norm() > cd.max_force) ts.feedback_force *= cd.max_force / ts.feedback_force.norm();
  ts.ramping_in = ramp_.active(t);
  if (link_)
    link_->publish(ts.feedback_force, ts.feedback_torque, t,
                   ts.ramping_in ? teleop::FeedbackStatus::kRampIn : teleop::FeedbackStatus::kRunning);
}

void ToolDriver::end_feedback() {
  if (link_) link_->end();
}

Isometry ToolDriver::drawn_pose(double t) const {
  const bool exact = live_ || hold_ || tool_->coupled();
  return exact ? state_.pose : sample_pose(track_->at(t));
}

Isometry ToolDriver::jaw_pose(const CompiledJaw& jaw) const {
  return state_.pose * tool_->jaw_in_tool(jaw, state_.device.closure);
}

int ToolDriver::stream_port() const { return link_ ? link_->port() : 0; }

std::string ToolDriver::stream_counters() const {
  if (!link_) return "";
  return link_->counters().describe() + ", feedback sent " + std::to_string(link_->feedback_sent());
}

std::string ToolDriver::finish_recording() {
  if (!recorder_) return "";
  recorder_->finish();
  std::string path = recorder_->path();
  recorder_.reset();
  return path;
}

// The scene's tools as SceneSession shows them.

const std::vector<SceneToolEvent>& SceneSession::tool_events() const { return impl_->events; }

int SceneSession::num_tools() const { return int(impl_->tools.size()); }
const std::string& SceneSession::tool_name(int tool) const { return impl_->tools.at(tool).name(); }
int SceneSession::tool_index(const std::string& name) const {
  std::string known;
  for (size_t i = 0; i < impl_->tools.size(); ++i) {
    if (impl_->tools[i].name() == name) return int(i);
    known += (known.empty() ? "" : ", ") + impl_->tools[i].name();
  }
  fail(impl_->sc.path, ": no tool named '", name, "' (tools: ", known.empty() ? "none" : known, ")");
}
const SceneToolState& SceneSession::tool_state(int tool) const { return impl_->tools.at(tool).state(); }
const CompiledTool& SceneSession::compiled_tool(int tool) const { return impl_->tools.at(tool).tool(); }
void SceneSession::set_device_pose(int tool, const teleop::PoseSample& sample) { impl_->tools.at(tool).push(sample); }
int SceneSession::stream_port(int tool) const { return impl_->tools.at(tool).stream_port(); }
std::string SceneSession::stream_counters(int tool) const { return impl_->tools.at(tool).stream_counters(); }

void SceneSession::end_feedback() {
  for (ToolDriver& t : impl_->tools) t.end_feedback();
}

std::vector<std::string> SceneSession::finish_recording() {
  std::vector<std::string> paths;
  for (ToolDriver& t : impl_->tools)
    if (std::string p = t.finish_recording(); !p.empty()) paths.push_back(std::move(p));
  return paths;
}

}  // namespace sflsh
