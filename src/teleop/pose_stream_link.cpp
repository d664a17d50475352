#include "sflsh/teleop/pose_stream_link.hpp"

#include <chrono>

namespace sflsh::teleop {

namespace {

/// One datagram per poll, so every accepted pose gets its own answer.
PoseStreamServerOptions one_per_poll(PoseStreamServerOptions o) {
  o.max_datagrams_per_poll = 1;
  return o;
}

}  // namespace

PoseStreamLink::PoseStreamLink(PoseStreamServerOptions options) : server_(one_per_poll(std::move(options))) {
  port_ = server_.port();
  thread_ = std::thread([this] { run(); });
}

PoseStreamLink::~PoseStreamLink() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void PoseStreamLink::run() {
  const auto start = std::chrono::steady_clock::now();
  while (!stop_) {
    if (!server_.wait_readable(0.005)) continue;  // wakes at least every 5 ms to see stop_
    // One datagram at a time: each accepted pose is answered at once.
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::optional<StreamSample> got = server_.poll(now);
    FeedbackMessage f;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (got) latest_ = got;
      counters_ = server_.counters();
      f = feedback_;
    }
    if (got && server_.send_feedback(f.force, f.torque, f.sim_time, f.status)) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++sent_;
    }
  }
}

std::optional<StreamSample> PoseStreamLink::latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

void PoseStreamLink::publish(const Vec3& force, const Vec3& torque, double sim_time, FeedbackStatus status) {
  std::lock_guard<std::mutex> lock(mutex_);
  feedback_.force = force;
  feedback_.torque = torque;
  feedback_.sim_time = sim_time;
  feedback_.status = status;
}

void PoseStreamLink::end() {
  std::lock_guard<std::mutex> lock(mutex_);
  feedback_.force.setZero();
  feedback_.torque.setZero();
  feedback_.status = FeedbackStatus::kEnded;
}

bool PoseStreamLink::ended() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return feedback_.status == FeedbackStatus::kEnded;
}

PoseStreamCounters PoseStreamLink::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

long PoseStreamLink::feedback_sent() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sent_;
}

}  // namespace sflsh::teleop
