#pragma once
// The browser viewer's server: HTTP for the page (web_assets.hpp) and one
// WebSocket per client on the same port (Boost.Beast), on its own thread.
//
// The simulation (or the player) never waits on it:
//   * publish() hands over the newest frame (a pointer swap under a mutex
//     held for nanoseconds); each client is sent the newest frame whenever
//     its previous send has finished, so a slow client skips frames
//     (latest-frame-wins) and a vanished one costs nothing;
//   * frame_due() says when the next frame is wanted (the display rate,
//     default 30 fps), so frames are built at that rate, not the physics rate;
//   * poll() drains the control messages that arrived since the last call.
// On connect a client is sent the scene (scene_json, text), then frames
// (frame_codec.hpp, binary). The first connected client drives (its control
// messages are queued); later clients watch (their controls are logged and
// ignored) until the driver leaves. A malformed control message or a tool
// pose that fails the stream checks (teleop::PoseStreamFilter: time order,
// speed) is logged on stderr and ignored; the last good pose stays.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/teleop/pose_stream_filter.hpp"
#include "sflsh/viewer/control_message.hpp"
#include "sflsh/viewer/frame_codec.hpp"
#include "sflsh/viewer/viewer_scene.hpp"

namespace sflsh::viewer {

struct ViewerServerOptions {
  /// Address to listen on. Default loopback; any other address is served
  /// with a warning on stderr (no authentication: whoever reaches it drives).
  std::string bind = "127.0.0.1";
  int port = 8080;   ///< TCP port; 0 = any free port (see port())
  double fps = 30;   ///< display rate (frames per second), in (0, 60]
  /// Checks of tool poses from the page. Default max speed 5 m/s (a mouse drag
  /// is slower; a jump from a glitch or a bad client is not).
  teleop::PoseStreamCheckOptions checks{5.0, 1e-3};
  bool quiet = false;  ///< no log lines on stderr (tests)
};

/// Server-side counters (thread-safe snapshot).
struct ViewerCounters {
  long frames_published = 0;
  long messages_sent = 0;       ///< scene + frame messages written to clients
  long frame_bytes_sent = 0;    ///< bytes of frame messages (not the scene)
  long controls_accepted = 0;
  long controls_rejected = 0;   ///< malformed, from a watcher, or failing the pose checks
  long clients_connected = 0;   ///< ever
};

class ViewerServer {
 public:
  /// Listens on options.bind:options.port and starts the server thread.
  /// Throws sflsh::Error naming the address when it cannot listen or
  /// options are out of range.
  ViewerServer(ViewerScene scene, const ViewerServerOptions& options = {});
  /// Stops the thread and closes every connection.
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  int port() const;         ///< the bound port
  std::string url() const;  ///< "http://ADDR:PORT/"
  const ViewerScene& scene() const;

  /// True when a frame is due (1/fps after the previous one's due time).
  bool frame_due() const;
  /// Hands `frame` to the clients (never blocks on the network). Stamped
  /// with the seq of the last control message poll() returned.
  void publish(ViewerFrame frame);
  /// The control messages accepted since the last call, in arrival order.
  std::vector<ControlMessage> poll();

  int num_clients() const;
  ViewerCounters counters() const;

  struct Impl;  ///< implementation (viewer_server.cpp); public only for its session classes

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::viewer
