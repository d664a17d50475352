// `sflsh run scene.yaml [--realtime]`: a scene run live — tools
// driven by keyframes, pose files, live UDP devices (pose_stream) or a
// recording (--replay) — in step with the wall clock or as fast as possible,
// reporting the real-time factor; optional result file, per-step tool log and
// a recording of the device poses that replays bit-identically.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include "command.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/line_plot_svg.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/scene/live_run.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/viewer/live_viewer.hpp"

namespace sflsh::cli {
namespace {

struct RunArgs {
  std::string scene;
  bool realtime = false;
  double seconds = 0;
  int max_substeps = 10;
  std::string out, tool_log, record, replay, cache_dir;
  bool quiet_status = false;
  bool serve = false;  // the browser viewer
  int port = 8080;
  std::string bind = "127.0.0.1";
};

/// Per-step rows: time, tool, device and tool positions, the force the
/// bodies put on the tool, what the device is sent, anchors, stretch,
/// closure, the bodies' elastic energy and the step's outcome.
class ToolLog {
 public:
  explicit ToolLog(const std::string& path) : out_(path), file_(out_.temp_path()) {
    require(bool(file_), path, ": cannot write the tool log");
    file_ << "time,tool,device_x,device_y,device_z,tool_x,tool_y,tool_z,force_x,force_y,force_z,feedback_x,"
             "feedback_y,feedback_z,anchors,max_stretch,closure,elastic_energy,outcome\n"
          << std::setprecision(9);
  }
  void add(const SceneSession& s, const StepReport& rep) {
    if (force_.empty()) force_.resize(size_t(s.num_tools())), feedback_.resize(size_t(s.num_tools()));
    time_.push_back(s.time());
    double elastic = 0;
    for (const TermEnergy& e : rep.energies)
      if (e.name.rfind("elastic", 0) == 0) elastic += e.value;
    for (int i = 0; i < s.num_tools(); ++i) {
      const SceneToolState& t = s.tool_state(i);
      const Vec3 d = t.device.position, c = t.pose.translation();
      file_ << s.time() << "," << s.tool_name(i) << "," << d.x() << "," << d.y() << "," << d.z() << "," << c.x()
            << "," << c.y() << "," << c.z() << "," << t.force.x() << "," << t.force.y() << "," << t.force.z() << ","
            << t.feedback_force.x() << "," << t.feedback_force.y() << "," << t.feedback_force.z() << ","
            << t.anchors << "," << t.max_stretch << "," << t.device.closure << "," << elastic << ","
            << to_string(rep.outcome) << "\n";
      force_[size_t(i)].push_back(t.force.norm());
      feedback_[size_t(i)].push_back(t.feedback_force.norm());
      names_.resize(size_t(s.num_tools()));
      names_[size_t(i)] = s.tool_name(i);
    }
  }
  /// A plot of |force| and |feedback| per tool against time.
  void plot(const std::string& path) const {
    std::vector<io::PlotSeries> series;
    for (size_t i = 0; i < force_.size(); ++i) {
      series.push_back({names_[i] + ": force from the bodies", time_, force_[i], io::plot_color(int(2 * i)), false});
      series.push_back({names_[i] + ": sent to the device", time_, feedback_[i], io::plot_color(int(2 * i + 1)), true});
    }
    io::write_line_plot_svg(path, "Force on the tools per step", "time (s)", "|force| (N)", series);
  }
  void commit() {
    file_.close();
    require(!file_.fail(), out_.path(), ": writing the tool log failed");
    out_.commit();
  }

 private:
  io::AtomicOutput out_;
  std::ofstream file_;
  std::vector<double> time_;
  std::vector<std::vector<double>> force_, feedback_;
  std::vector<std::string> names_;
};

void run_scene_live(const RunArgs& a) {
  SceneDescription scene = read_scene_description(a.scene);
  require(a.seconds >= 0 && std::isfinite(a.seconds), "run: --seconds ", a.seconds, ": expected >= 0 (0 = the scene's)");
  require(a.max_substeps >= 1, "run: --max-substeps ", a.max_substeps, ": expected >= 1");
  if (!a.out.empty()) io::check_output_file(a.out, "--out");
  if (!a.tool_log.empty()) io::check_output_file(a.tool_log, "--tool-log");
  if (!a.record.empty()) {
    std::filesystem::create_directories(a.record);
    io::check_output_folder(a.record, "--record");
  }
  require(a.replay.empty() || std::filesystem::is_directory(a.replay), "run: --replay ", a.replay,
          ": not a folder (give the --record folder of a run)");
  SceneSessionOptions so;
  so.record_dir = a.record;
  so.replay_dir = a.replay;
  prepare_scene_assets(scene, a.cache_dir.empty() ? default_cache_dir() : a.cache_dir);
  SceneSession session(scene, so);

  SimulationResult result = session.result_header();
  if (!a.out.empty()) session.record_frame(result, 0.0);
  std::unique_ptr<ToolLog> log;
  if (!a.tool_log.empty()) log = std::make_unique<ToolLog>(a.tool_log);
  const double frame_dt = 1.0 / scene.output.fps;
  double next_frame = frame_dt, ms_since_frame = 0;
  int steps_since_frame = 0;
  LiveRunHooks hooks;
  hooks.after_step = [&](const SceneSession& s, const StepReport& rep) {
    if (log) log->add(s, rep);
    if (a.out.empty()) return;
    result.add_step(s.time(), rep);
    ms_since_frame += rep.ms_total;
    ++steps_since_frame;
    if (s.time() + 1e-9 >= next_frame) {
      s.record_frame(result, ms_since_frame / steps_since_frame);
      next_frame += frame_dt;
      ms_since_frame = 0;
      steps_since_frame = 0;
    }
  };
  std::unique_ptr<viewer::LiveViewer> view;
  if (a.serve) {
    view = std::make_unique<viewer::LiveViewer>(session, viewer::ViewerServerOptions{a.bind, a.port},
                                                std::filesystem::path(a.scene).filename().string(),
                                                /*allow_reset=*/a.out.empty() && a.tool_log.empty());
    view->install(hooks);
  }
  LiveRunOptions lo;
  lo.realtime = a.realtime;
  lo.seconds = a.seconds;
  lo.max_substeps = a.max_substeps;
  lo.progress = !a.quiet_status;
  LiveRunStatus status;
  std::string stopped;  // the numerical guard's message when the run met NaN/Inf
  {
    const InterruptScope interrupt_scope;
    try {
      status = run_live(session, lo, hooks);
    } catch (const NonFiniteError& e) {
      stopped = e.what();
      result.incomplete = true;
      result.stop_reason = stopped;
    }
  }
  session.end_feedback();  // from here on, a device gets zero force and status "ended"
  std::cout << status.describe(a.realtime) << "\n";
  if (view) std::cout << view->summary() << "\n";
  for (const SceneToolEvent& e : session.tool_events())
    std::printf("tool %s t = %.3f s: %s %d skin points of %s\n", e.tool.c_str(), e.time, e.kind.c_str(), e.points,
                e.body.c_str());
  for (int i = 0; i < session.num_tools(); ++i)
    if (session.stream_port(i) > 0)
      std::printf("tool %s stream (udp://127.0.0.1:%d): %s\n", session.tool_name(i).c_str(), session.stream_port(i),
                  session.stream_counters(i).c_str());
  for (const std::string& p : session.finish_recording()) std::printf("recorded the device poses to %s\n", p.c_str());
  if (log) {
    log->commit();
    const std::filesystem::path p(a.tool_log);
    const std::string svg = (p.parent_path() / (p.stem().string() + ".svg")).string();
    log->plot(svg);
    std::printf("wrote %s (tools per step) and %s (plot)\n", a.tool_log.c_str(), svg.c_str());
  }
  if (!a.out.empty()) {
    result.tool_events = session.tool_events();  // also those after the last frame
    write_simulation_result(result, a.out);
    std::printf("wrote %s (%d frames%s)\n", a.out.c_str(), result.num_frames,
                status.interrupted ? ", up to the signal" : stopped.empty() ? "" : ", marked incomplete");
  }
  if (!stopped.empty()) fail(stopped);
}

const CommandRegistrar reg(45, [](CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand(
      "run",
      "Run a scene live: tools from keyframes, pose files or live UDP devices with force feedback; --realtime keeps "
      "in step with the wall clock and reports the real-time factor");
  cmd->add_option("scene", a->scene, "Scene file (YAML; tools: include/sflsh/scene/scene_description.hpp)")
      ->required();
  cmd->add_flag("--realtime", a->realtime,
                "Keep the simulation in step with the wall clock (N <= --max-substeps substeps of solver.dt per "
                "frame; behind: RTF < 1). Without it: as fast as possible, deterministic");
  cmd->add_option("--seconds", a->seconds, "Simulated seconds (0 = the scene's solver.seconds); Ctrl-C ends a run early")
      ->capture_default_str();
  cmd->add_option("--max-substeps", a->max_substeps, "N_max: most substeps per real-time frame")->capture_default_str();
  cmd->add_option("--out", a->out, "Also write a result file (HDF5) with frames at the scene's output.fps");
  cmd->add_option("--tool-log", a->tool_log,
                  "Write a CSV per step and tool: device and tool position, force, feedback, anchors, energy");
  cmd->add_option("--record", a->record,
                  "Record the device poses every tool used into FOLDER/<tool>.csv (replay with --replay FOLDER)");
  cmd->add_option("--replay", a->replay,
                  "Drive every tool from FOLDER/<tool>.csv of a --record run (bit-identical trajectories)");
  cmd->add_option("--cache-dir", a->cache_dir, "Cache of baked mesh SDFs (default: $SFLSH_CACHE_DIR or ~/.cache/sflsh)");
  cmd->add_flag("--quiet-status", a->quiet_status, "No status line per second");
  cmd->add_flag("--serve", a->serve, "Serve the live browser viewer (README: Live viewer); the page drives the first tool");
  cmd->add_option("--port", a->port, "--serve: TCP port (0 = any free port)")->capture_default_str();
  cmd->add_option("--bind", a->bind, "--serve: address to listen on; not loopback = a warning (no authentication)")
      ->capture_default_str();
  cmd->callback([a] { run_scene_live(*a); });
});

}  // namespace
}  // namespace sflsh::cli
