#pragma once
// A live device on its own thread: a PoseStreamServer read by a
// background thread that answers every accepted pose at once with the newest
// feedback the simulation published, so force feedback runs at the device's
// rate (up to 1 kHz) whatever the physics rate, and the physics loop never
// waits on the network: it takes the newest accepted sample when it starts a
// step (latest()) and publishes the force when the step ends (publish()).
// Rejected datagrams are logged (one line each, PoseStreamServer) and do not
// change latest(): the simulation holds the last good pose.
#include <atomic>
#include <mutex>
#include <optional>
#include <thread>

#include "sflsh/teleop/pose_stream_server.hpp"

namespace sflsh::teleop {

class PoseStreamLink {
 public:
  /// Binds the server (throws like PoseStreamServer) and starts the thread.
  explicit PoseStreamLink(PoseStreamServerOptions options = {});
  /// Stops and joins the thread.
  ~PoseStreamLink();
  PoseStreamLink(const PoseStreamLink&) = delete;
  PoseStreamLink& operator=(const PoseStreamLink&) = delete;

  int port() const { return port_; }
  /// The newest accepted sample (receive_time: seconds of the link's steady
  /// clock since it started), or nothing before the first.
  std::optional<StreamSample> latest() const;
  /// The force (N) and torque (N·m, world) on the tool at simulation time
  /// `sim_time` (s), with the simulation's status: sent in reply to every
  /// accepted sample from now on (after end(), the simulation runs again).
  void publish(const Vec3& force, const Vec3& torque, double sim_time,
               FeedbackStatus status = FeedbackStatus::kRunning);
  /// The simulation stopped: every later pose is answered with zero force and
  /// torque, status kEnded and the last published sim_time.
  void end();
  bool ended() const;
  /// Copies of the server's counters and the feedback messages sent.
  PoseStreamCounters counters() const;
  long feedback_sent() const;

 private:
  void run();

  PoseStreamServer server_;
  int port_ = 0;
  mutable std::mutex mutex_;
  std::optional<StreamSample> latest_;
  FeedbackMessage feedback_;
  PoseStreamCounters counters_;
  long sent_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace sflsh::teleop
