#pragma once
// The simulator's end of the live pose stream (message format:
// stream_message.hpp): a UDP socket bound to 127.0.0.1, read without blocking
// once per simulation step, answered with the force on the tool.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sflsh/teleop/pose_stream_filter.hpp"

namespace sflsh::teleop {

struct PoseStreamServerOptions {
  /// UDP port on 127.0.0.1; 0 (default) lets the system pick a free one (see port()).
  int port = 0;
  PoseStreamCheckOptions checks;
  /// Most datagrams one poll() reads (default 4096, > 4 s of a 1 kHz device):
  /// bounds the work per simulation step when a sender floods the port; the
  /// rest wait in the socket buffer for the next poll.
  int max_datagrams_per_poll = 4096;
  /// Receives one line per rejected datagram. Default (empty): the line goes to stderr.
  std::function<void(const std::string&)> log;
};

/// An accepted sample with where it stands in the stream.
struct StreamSample {
  std::uint64_t sequence = 0;
  PoseSample sample;          ///< sample.time = device time (s); quaternion normalized
  double receive_time = 0.0;  ///< the caller's clock (s) passed to poll()
};

class PoseStreamServer {
 public:
  /// Opens and binds the socket; throws sflsh::Error naming the port and the
  /// system error when that fails (port in use, no permission).
  explicit PoseStreamServer(PoseStreamServerOptions options = {});
  ~PoseStreamServer();
  PoseStreamServer(const PoseStreamServer&) = delete;
  PoseStreamServer& operator=(const PoseStreamServer&) = delete;

  /// The bound UDP port (the picked one when options.port was 0).
  int port() const { return port_; }

  /// Drains the pending datagrams (at most options.max_datagrams_per_poll)
  /// without blocking, checks each in arrival
  /// order (one log line per rejected one) and returns the newest sample
  /// accepted in this call, or nothing when none was. `now` (s, the caller's
  /// clock, e.g. simulation time) is stamped as receive_time. When `accepted`
  /// is given, every sample accepted in this call is appended to it in order
  /// (for a PoseRecorder).
  std::optional<StreamSample> poll(double now, std::vector<StreamSample>* accepted = nullptr);

  /// The held pose: the last accepted sample over the server's lifetime.
  const std::optional<StreamSample>& last_good() const { return last_good_; }

  /// Sends a feedback message echoing the last accepted sequence number to
  /// the address the last accepted sample came from. Force in N, torque in
  /// N·m (world frame), sim_time in s, and the simulation's status. Returns
  /// false (sends nothing) before the first accepted sample or when the
  /// socket buffer is full.
  bool send_feedback(const Vec3& force, const Vec3& torque, double sim_time,
                     FeedbackStatus status = FeedbackStatus::kRunning);

  /// Blocks until a datagram is waiting or `timeout` seconds pass (≥ 0);
  /// returns whether one is waiting. Lets a thread answer at the device rate.
  bool wait_readable(double timeout) const;

  const PoseStreamCounters& counters() const { return counters_; }
  long feedback_sent() const { return feedback_sent_; }

 private:
  void handle(const std::uint8_t* data, std::size_t size, const std::string& from, double now,
              std::vector<StreamSample>* accepted, std::optional<StreamSample>* newest);

  PoseStreamServerOptions options_;
  int fd_ = -1;
  int port_ = 0;
  PoseStreamFilter filter_;
  PoseStreamCounters counters_;
  std::optional<StreamSample> last_good_;
  std::vector<std::uint8_t> reply_to_;  ///< sockaddr_in bytes of the last accepted sender
  std::vector<std::uint8_t> pending_from_;
  long feedback_sent_ = 0;
};

}  // namespace sflsh::teleop
