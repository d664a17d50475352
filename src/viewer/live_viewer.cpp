#include "sflsh/viewer/live_viewer.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "sflsh/core/interrupt.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh::viewer {

struct LiveViewer::Impl {
  SceneSession& session;
  std::unique_ptr<ViewerServer> server;
  bool paused = false;
  bool allow_reset = true;
  long resets = 0;
  long paused_steps = 0;
  double frame_ms = 0;     ///< wall time building frames on the physics thread (ms, summed)
  long frames_built = 0;  ///< single steps taken while paused (not in run_live's count)
  double step_ms_avg = 0;
  double max_u = 0;
  long contact_frames = 0, applied = 0, ignored = 0;
  LiveRunStatus last_status;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  /// Per body: its skin's embedding, and the pose blend-shape offsets of the
  /// bones they were computed for. The offsets (#V·3 by 207 posedirs times
  /// the pose feature: ~46 MB of memory read for the default avatar) are
  /// recomputed only when the bones move; a body whose bones are still (a
  /// kinematic body without motion, a body at rest) costs the skinning only.
  struct BodyCache {
    PosedPoints skin;
    std::vector<Isometry> bones;
    Points offsets;
  };
  mutable std::vector<BodyCache> bodies;

  explicit Impl(SceneSession& s) : session(s) {
    for (int b = 0; b < s.num_bodies(); ++b) bodies.push_back({PosedPoints::at_surface(s.avatar(b)), {}, Points()});
  }

  /// Builds the frame of the current state and hands it to the server.
  void publish(const LiveViewer& viewer) {
    const auto t0 = std::chrono::steady_clock::now();
    ViewerFrame f = viewer.frame(last_status);
    frame_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++frames_built;
    max_u = std::max(max_u, f.stats.max_displacement);
    if (f.stats.contact) ++contact_frames;
    server->publish(std::move(f));
  }

  static bool same_bones(const std::vector<Isometry>& a, const std::vector<Isometry>& b) {
    if (a.size() != b.size()) return false;
    for (size_t j = 0; j < a.size(); ++j)
      if (a[j].matrix() != b[j].matrix()) return false;
    return true;
  }
  /// The body's posed skin (m, world) and soft displacement (m): what
  /// SceneSession::body_surface/body_displacement give, with the offsets cached.
  void body_skin(int b, Points* x, Points* u) const {
    const Configuration& q = session.simulator().state(session.body_model_index(b));
    BodyCache& c = bodies[size_t(b)];
    if (c.offsets.size() == 0 || !same_bones(c.bones, q.bones)) {
      c.offsets = surface_pose_offsets(session.avatar(b), q.bones);
      c.bones = q.bones;
    }
    *x = c.skin.world(q, &c.offsets);
    *u = c.skin.soft_displacement(q.z);
  }

  // Applies the page's controls; returns true when a single step was asked for.
  bool apply_controls() {
    bool step = false;
    double stiffness = 0;  // the last stiffness asked for in this batch (0: none)
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
        case ControlType::kReset:
          if (!allow_reset) {
            ++ignored;
            std::fprintf(stderr, "viewer: reset ignored: this run writes --out/--tool-log files whose time "
                                 "would go back\n");
            break;
          }
          session.reset();  // keeps the stiffness scale (a setting)
          ++resets;
          ++applied;
          break;
        case ControlType::kStiffness:
          stiffness = m.value;
          ++applied;
          break;
        default:  // seek, speed: playback only
          ++ignored;
          std::fprintf(stderr, "viewer: '%s' applies to playback only; ignored\n", to_string(m.type));
      }
    }
    // Several slider moves in one batch: the model is rebuilt once, for the last.
    if (stiffness > 0 && stiffness != session.stiffness_scale(0)) session.set_stiffness_scale(stiffness);
    return step;
  }
};

LiveViewer::LiveViewer(SceneSession& session, const ViewerServerOptions& options, const std::string& title,
                       bool allow_reset)
    : impl_(std::make_unique<Impl>(session)) {
  impl_->allow_reset = allow_reset;
  SimulationResult header = session.result_header();
  session.record_frame(header, 0.0);
  std::vector<std::string> tools;
  for (int t = 0; t < session.num_tools(); ++t) tools.push_back(session.tool_name(t));
  ViewerScene scene = viewer_scene(header, tools, 0.5, 0.01);
  scene.mode = "live";
  scene.title = title;
  scene.duration = session.seconds();
  scene.dt = session.dt();
  scene.can_reset = allow_reset;
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
    Points x, u;
    impl_->body_skin(b, &x, &u);
    f.positions.middleRows(row, x.rows()) = x;
    f.displacement.segment(row, x.rows()) = u.rowwise().norm();
    row += x.rows();
    f.joints.middleRows(24 * b, 24) = s.body_joints(b);
  }
  f.object_poses = s.object_poses();
  f.tools = s.tool_frames();        // every tool's force arrow, not only the driven one's
  f.contacts = s.contact_frames();  // every contact's force arrow
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
  st.stiffness_scale = s.stiffness_scale(0);
  st.resets = impl_->resets;
  st.steps = status.steps + impl_->paused_steps;
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
  // The run's own after_step hook (result and tool-log rows), called for every step.
  auto run_after_step = hooks.after_step;
  // Applies the page's controls; while paused, serves the held state and takes
  // single steps asked for (one solver step each: run_live's real-time frame
  // would take up to max_substeps after the pause) until resumed.
  auto controls = [this, d, run_after_step](SceneSession& s) {
    bool step = d->apply_controls();
    while (d->paused && interrupt_signal() == 0) {
      if (step) {
        const StepReport& rep = s.advance();
        ++d->paused_steps;
        if (run_after_step) run_after_step(s, rep);
        d->publish(*this);
      } else if (d->server->frame_due()) {
        d->publish(*this);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      step = d->apply_controls();
    }
  };
  hooks.before_frame = [controls](SceneSession& s) {
    controls(s);
    return true;
  };
  // Between the substeps too: a behind real-time frame runs up to max_substeps,
  // and the page's poses and the display rate should not wait for its end.
  hooks.after_step = [this, d, run_after_step, controls](const SceneSession&, const StepReport& rep) {
    if (run_after_step) run_after_step(d->session, rep);
    d->step_ms_avg = d->step_ms_avg == 0 ? rep.ms_total : 0.99 * d->step_ms_avg + 0.01 * rep.ms_total;
    controls(d->session);
    if (d->server->frame_due()) d->publish(*this);
  };
  hooks.after_frame = [this, d](const SceneSession&, const LiveRunStatus& status) {
    d->last_status = status;
    if (d->server->frame_due()) d->publish(*this);
  };
}

std::string LiveViewer::summary() const {
  const ViewerCounters c = impl_->server->counters();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - impl_->start).count();
  char line[512];
  std::snprintf(line, sizeof line,
                "viewer: %ld frames published, %ld client(s), %.2f MB/s of frames (all clients) over %.1f s; "
                "controls %ld applied, %ld ignored; max |u| %.3f mm; tool contact in %ld frames; "
                "frame build %.2f ms mean on the physics thread",
                c.frames_published, c.clients_connected, wall > 0 ? c.frame_bytes_sent / 1e6 / wall : 0.0, wall,
                impl_->applied, c.controls_rejected + impl_->ignored, impl_->max_u * 1e3, impl_->contact_frames,
                impl_->frames_built ? impl_->frame_ms / double(impl_->frames_built) : 0.0);
  return line;
}

}  // namespace sflsh::viewer
