// `sflsh view result.h5`: plays a result file in the browser viewer:
// serves the page on loopback, and plays the frames with timeline scrubbing,
// play/pause and speed from the page (viewer/result_player.hpp).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>

#include "command.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/viewer/result_player.hpp"
#include "sflsh/viewer/viewer_server.hpp"

namespace sflsh::cli {
namespace {

struct ViewArgs {
  std::string result, bind = "127.0.0.1";
  int port = 8080;
  double seconds = 0, speed = 1;
  bool play = false;
};

void run_view(const ViewArgs& a) {
  require(a.seconds >= 0, "--seconds ", a.seconds, ": expected >= 0 (0 = until Ctrl-C)");
  require(a.speed >= viewer::kMinPlaybackSpeed && a.speed <= viewer::kMaxPlaybackSpeed, "--speed ", a.speed,
          ": expected a value in [", viewer::kMinPlaybackSpeed, ", ", viewer::kMaxPlaybackSpeed, "]");
  const SimulationResult result = read_simulation_result(a.result);
  require(result.num_frames > 0 && !result.frame_positions.empty(), a.result, ": the result has no frames to play");
  viewer::ViewerScene scene = viewer::playback_scene(result, std::filesystem::path(a.result).filename().string());
  viewer::ViewerServerOptions o;
  o.bind = a.bind;
  o.port = a.port;
  viewer::ViewerServer server(std::move(scene), o);
  viewer::ResultPlayer player(result);
  {
    viewer::ControlMessage m;
    m.type = viewer::ControlType::kSpeed;
    m.value = a.speed;
    player.apply(m);
    m.type = viewer::ControlType::kPause;
    m.paused = !a.play;
    player.apply(m);
  }
  std::printf("serving %s (%d frames, %.3f s); open it in a browser; Ctrl-C stops\n", server.url().c_str(),
              int(result.frame_time.size()), result.frame_time.back());
  std::fflush(stdout);
  InterruptScope interrupt_scope;
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  auto last = start;
  while (interrupt_signal() == 0) {
    const auto now = clock::now();
    if (a.seconds > 0 && std::chrono::duration<double>(now - start).count() >= a.seconds) break;
    for (const viewer::ControlMessage& m : server.poll()) player.apply(m);
    if (server.frame_due()) {
      player.advance(std::chrono::duration<double>(now - last).count());
      last = now;
      server.publish(player.current());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const viewer::ViewerCounters c = server.counters();
  std::printf("served %ld frames to %ld client(s), %.1f MB of frames; controls: %ld applied, %ld ignored\n",
              c.frames_published, c.clients_connected, c.frame_bytes_sent / 1e6, c.controls_accepted,
              c.controls_rejected);
}

const CommandRegistrar reg(62, [](CLI::App& app) {
  auto a = std::make_shared<ViewArgs>();
  auto* cmd = app.add_subcommand("view", "Play a result file in the browser viewer (README: Live viewer)");
  cmd->add_option("result", a->result, "Result file (.h5) from simulate or run")->required()->check(CLI::ExistingFile);
  cmd->add_option("--port", a->port, "TCP port (0 = any free port; the URL is printed)")->capture_default_str();
  cmd->add_option("--bind", a->bind,
                  "Address to listen on; anything but loopback is served with a warning (no authentication)")
      ->capture_default_str();
  cmd->add_option("--seconds", a->seconds, "Serve for this many seconds of wall time (0 = until Ctrl-C)")
      ->capture_default_str();
  cmd->add_option("--speed", a->speed, "Initial playback speed")->capture_default_str();
  cmd->add_flag("--play", a->play, "Start playing at once (default: paused at the first frame)");
  cmd->callback([a] { run_view(*a); });
});

}  // namespace
}  // namespace sflsh::cli
