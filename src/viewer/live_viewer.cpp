#include "sflsh/viewer/live_viewer.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "sflsh/core/interrupt.hpp"

namespace sflsh::viewer {

struct LiveViewer::Impl {
  SceneSession& session;
  std::unique_ptr<ViewerServer> server;
  bool paused = false;
  double step_ms_avg = 0;
  double max_u = 0;
  long contact_frames = 0, applied = 0, ignored = 0;
  LiveRunStatus last_status;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  explicit Impl(SceneSession& s) : session(s) {}

  // Applies the page's controls; returns true when a single step was asked for.
  bool apply_controls() {
    bool step = false;
    for (const ControlMessage& m : server->poll()) {
      switch (m.type) {
        case ControlType::kTool: {
          teleop::PoseSample p = m.pose;
          p.time = session.time();
          session.set_device_pose(m.tool, p);
          ++applied;
          break;
        }
        case ControlType::kPause:
          paused = m.paused;
          ++applied;
          break;
        case ControlType::kStep:
          step = true;
          ++applied;
          break;
        default:
          ++ignored;
          std::fprintf(stderr, "viewer: '%s' does not apply to a live scene yet (no SceneSession API); ignored\n",
                       to_string(m.type));
      }
    }
    return step;
  }
};

LiveViewer::LiveViewer(SceneSession& session, const ViewerServerOptions& options, const std::string& title)
    : impl_(std::make_unique<Impl>(session)) {
  SimulationResult header = session.result_header();
  session.record_frame(header, 0.0);
  std::vector<std::string> tools;
  for (int t = 0; t < session.num_tools(); ++t) tools.push_back(session.tool_name(t));
  ViewerScene scene = viewer_scene(header, tools, 0.5, 0.01);
  scene.mode = "live";
  scene.title = title;
  scene.duration = session.seconds();
  scene.dt = session.dt();
  impl_->server = std::make_unique<ViewerServer>(std::move(scene), options);
  std::printf("viewer: serving %s (open it in a browser)\n", impl_->server->url().c_str());
  std::fflush(stdout);
}

LiveViewer::~LiveViewer() = default;

ViewerServer& LiveViewer::server() { return *impl_->server; }

ViewerFrame LiveViewer::frame(const LiveRunStatus& status) const {
  const SceneSession& s = impl_->session;
  ViewerFrame f;
  f.time = s.time();
  const Eigen::Index V = impl_->server->scene().rest.rows();
  f.positions.resize(V, 3);
  f.displacement.resize(V);
  f.joints.resize(24 * s.num_bodies(), 3);
  Eigen::Index row = 0;
  for (int b = 0; b < s.num_bodies(); ++b) {
    const Points x = s.body_surface(b), u = s.body_displacement(b);
    f.positions.middleRows(row, x.rows()) = x;
    f.displacement.segment(row, x.rows()) = u.rowwise().norm();
    row += x.rows();
    f.joints.middleRows(24 * b, 24) = s.body_joints(b);
  }
  f.object_poses = s.object_poses();
  ViewerStats& st = f.stats;
  st.rtf = status.rtf;
  st.step_ms = impl_->step_ms_avg;
  for (const TermEnergy& e : s.last_report().energies) {
    st.term_names.push_back(e.name);
    st.term_ms.push_back(e.ms);
  }
  st.term_names.push_back("solve");
  st.term_ms.push_back(s.last_report().ms_solve);
  st.paused = impl_->paused;
  st.steps = status.steps;
  st.max_displacement = f.displacement.size() ? f.displacement.maxCoeff() : 0.0;
  if (s.num_tools() > 0) {
    const SceneToolState& t = s.tool_state(0);
    st.has_tool = true;
    st.force = t.force;
    st.device = t.device.position;
    st.device_orientation = t.device.orientation;
    st.closure = t.device.closure;
    st.anchors = t.anchors;
    st.contact = t.force.norm() > 0 || t.anchors > 0;
  }
  return f;
}

void LiveViewer::install(LiveRunHooks& hooks) {
  Impl* d = impl_.get();
  hooks.before_frame = [this, d](SceneSession&) {
    bool step = d->apply_controls();
    // Paused: keep serving the held state and reading controls until resumed or a step is asked for.
    while (d->paused && !step && interrupt_signal() == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      step = d->apply_controls();
      if (d->server->frame_due()) d->server->publish(frame(d->last_status));
    }
    return true;
  };
  hooks.after_frame = [this, d](const SceneSession& s, const LiveRunStatus& status) {
    d->last_status = status;
    const double ms = s.last_report().ms_total;
    d->step_ms_avg = d->step_ms_avg == 0 ? ms : 0.95 * d->step_ms_avg + 0.05 * ms;
    if (!d->server->frame_due()) return;
    ViewerFrame f = frame(status);
    d->max_u = std::max(d->max_u, f.stats.max_displacement);
    if (f.stats.contact) ++d->contact_frames;
    d->server->publish(std::move(f));
  };
}

std::string LiveViewer::summary() const {
  const ViewerCounters c = impl_->server->counters();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - impl_->start).count();
  char line[512];
  std::snprintf(line, sizeof line,
                "viewer: %ld frames published, %ld client(s), %.2f MB/s of frames (all clients) over %.1f s; "
                "controls %ld applied, %ld ignored; max |u| %.3f mm; tool contact in %ld frames",
                c.frames_published, c.clients_connected, wall > 0 ? c.frame_bytes_sent / 1e6 / wall : 0.0, wall,
                impl_->applied, c.controls_rejected + impl_->ignored, impl_->max_u * 1e3, impl_->contact_frames);
  return line;
}

}  // namespace sflsh::viewer
